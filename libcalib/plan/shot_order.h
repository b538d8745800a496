// The order in which a plan's photos are quickest to take on site:
//   1. one walk per placement: the placements in turn, nearest first along a
//      tour of their boards' directions from the instrument (the board stays
//      put while all its shots are taken);
//   2. within a placement, the faces grouped (one change of face), face 1
//      first;
//   3. within a face, the zooms in increasing order;
//   4. within a zoom, a nearest-neighbour tour of the pointings from where
//      the instrument stands, the distance between two pointings being the
//      larger of the two motor moves (both axes turn at once): the
//      horizontal move wrapped to [0, pi].
#pragma once

#include <vector>

#include "libcalib/model/targets.h"
#include "libcalib/plan/planner.h"

namespace rtscalib {

// The motor travel between two pointings [rad] (4. above).
double MotorTravel(const PlannedShot& a, const PlannedShot& b);

// Orders `shots` (1.-4. above) and returns the total motor travel of the
// ordered list [rad]. `scenes` gives the placements' boards.
double OrderShots(const PlacedScenes& scenes, std::vector<PlanShot>* shots);

}  // namespace rtscalib
