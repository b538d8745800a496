// The simulated instrument: a seeded truth model, an acquisition plan and
// noise -> records (and, with targets, pixel observations). Every test of
// rtscalib uses it as ground truth.
//
// Acquisition plan of Klug Sec. 4 (the "reduced" set):
//   sweep1: theta = pi/2, phi = 0 .. 2pi (15 points, endpoint excluded)
//   sweep2: phi = 0, theta = 0 .. pi (15 points, both ends included)
//   at each pose: EDM at d = 1 m and 2 m; camera rays of length 1 m at the
//   principal point and 1 px off it in u and in v, for every zoom level.
// Cross-validation grid ("full" set): phi_steps x theta_steps poses over
// phi in [0, 2pi), theta in (0, pi) with the same tool calls, plus extra
// distances and pixels spread over the image (set = "grid").
// Face 2 rows use the face-2 reading of each face-1 pointing (SPEC 1).
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"
#include "libcalib/sim/options.h"

namespace rtscalib {

struct SimulatedData {
  Observations obs;
  // Exact (noise-free) values for checking: x for each record, uv for each pixel row.
  std::vector<Eigen::Vector3d> exact_points;
  std::vector<Eigen::Vector2d> exact_pixels;
};

// The truth resembling Klug's optimised PLT 300 (Tables 6/7), with one camera
// per zoom level (640x480 px, f = 1000 px unless `camera` says otherwise).
InstrumentModel PaperTruth(int num_zooms);

SimulatedData Simulate(const SimulationOptions& options);

// A starting model for tests and benchmarks of the refinement alone: the
// truth moved by about `scale` (metres and radians) in every parameter a fit
// frees - base, EDM (dh: pose; spherical: t_x, t_y), link 1's alpha and a,
// camera tools - with the effect values (and the cameras' focus terms)
// zeroed (the enabled set is kept).
// What a good extraction gives; end-to-end tests start from the extraction.
InstrumentModel PerturbedStart(const InstrumentModel& truth, std::uint64_t seed,
                               double scale = 1e-3);

// A board of rows x cols tags (edge `tag` [m], spacing tag/4) whose printed
// side faces the point `station`: centre `distance` metres away from it in
// direction `phi` (SPEC 1: clockwise from +y) and `height` metres above it,
// turned by `tilt` [rad] about the board's own vertical axis.
TagBoard FacingBoard(const Eigen::Vector3d& station, int first_id, int rows, int cols, double tag,
                     double distance, double phi, double height, double tilt);

// A scene that suits every zoom level of `truth` (the camera images differ
// by focal length): per zoom two boards of rows x cols tags, at `distance`
// and 1.3 `distance` from the station in two directions, tilted by +-0.5 rad
// so that planes are not parallel, each spanning about half the view of its
// zoom. Tag ids: 1000 z + 0.., 1000 z + 500.. (so at most 500 tags a board).
TargetScene ZoomScene(const InstrumentModel& truth, int rows, int cols, double distance);

// Records of the plan for a given model without noise (used for held-out
// checks and by `Simulate`).
std::vector<Record> PlanRecords(const AcquisitionPlan& plan, const InstrumentModel& model);

}  // namespace rtscalib
