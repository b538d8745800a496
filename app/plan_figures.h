// The figure of a session plan (`rtscalib plan`, docs/plan.md): where the
// shots point, a panel per face, a shape per zoom, coloured by what they
// determine, joined in the order they are taken; for a camera on its own,
// where the board is held, its outline in the image of each zoom. A Vega
// spec like the run's figures (app/figures.h), written by WriteFigureFiles.
#pragma once

#include "app/figures.h"
#include "libcalib/plan/planner.h"

namespace rtscalib::app {

Figure PlanFigure(const PlanResult& plan);

}  // namespace rtscalib::app
