// One photo of a run with its observed corners and scaled residual arrows
// (report.html's worst photos, `rtscalib show --shot ID`), as a Vega spec
// (plot/vega_spec.h).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "app/pipeline.h"
#include "app/plot/vega_spec.h"
#include "libcalib/diagnose/residuals.h"

namespace rtscalib::app {

// One photo with its observed corners and scaled residual arrows. `rows`:
// the residual table's pixel rows of that shot (any status: only fitted
// rows get arrows, the others are marked); `image` the photo file ("" or
// unreadable: the corners on a blank image of width x height).
Figure PhotoFigure(const std::string& shot, const std::vector<ObservationResidual>& rows,
                   const std::string& image, int width, int height);

// The photo files of a run by shot id (the photo session's shots.csv rows,
// resolved against its folder).
std::map<std::string, std::string> PhotoFiles(const PhotoSessionSummary& photos);

}  // namespace rtscalib::app
