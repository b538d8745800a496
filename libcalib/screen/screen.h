// Screening of the observations before any fit: mistakes that a fit would
// turn into a wrong model, a hang or an allocation failure are caught here
// with the file, the line and the likely cause (docs/screening.md).
//
// Errors (the data break SPEC 1-3):
//   - phi or theta outside [-2 pi, 4 pi) once converted from data.angle_unit
//     (Observations::angle_unit): degrees or gon read as radians (the cause
//     names which, from the values' range and where face-1 zenith angles
//     cluster, and the `data.angle_unit: deg` / `gon` line that reads them so);
//   - face 2 with theta < pi (written the face-1 way) and face 1 with
//     theta > pi (a face-2 reading): SPEC 1's faces, when more than one in
//     ten rows of the face do so (fewer are gross rows: gross.h);
//   - pixels outside their zoom's image (model.cameras) by more than
//     ScreenOptions::pixel_margin_px, or u and v swapped (every u fits the
//     height and every v the width, while at least 3 rows and 1/20 of the
//     zoom's rows leave the image);
//   - record points farther from the other points than their distances d
//     allow (|x - m| > 2 (d + sqrt(3) d_max) + 1 m, m the coordinate-wise
//     median of the points: every point lies within d of the instrument, so
//     m lies within sqrt(3) d_max of it): millimetres when the excess is
//     about 1000-fold; when more than one in ten rows do so (fewer are
//     gross rows: gross.h);
//   - known points of pixels.csv beyond ScreenOptions::max_extent_m;
//   - zoom levels beyond the data's count of levels (or model.cameras) plus
//     ScreenOptions::max_missing_zooms (SPEC 2: levels are 0..N-1).
// Warnings (the data may be legitimate): phi in [2 pi, 4 pi), zoom levels
// without data below the largest, records with only camera rows or only EDM
// rows (the other tool is not determined), rows that repeat an earlier row
// exactly (duplicates.h: taken out before the fit with the gross rows).
//
// Each check reports once per file and column, at the first offending line,
// with the count and the next few lines; all errors come together.
#pragma once

#include <string>
#include <vector>

#include "libcalib/text/errors.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"
#include "libcalib/screen/options.h"

namespace rtscalib {

struct ScreenFindings {
  std::vector<InputError> errors;
  std::vector<std::string> warnings;
};

// Every finding; `cameras` are the configured cameras (model.cameras, index
// = zoom), which give the image sizes. Throws std::invalid_argument when
// options.Check() fails.
ScreenFindings FindDataMistakes(const Observations& obs, const std::vector<CameraTool>& cameras,
                                const ScreenOptions& options);

// FindDataMistakes, with its errors thrown as one InputError
// (InputError::Combine); returns the warnings, each prefixed "screening: ".
std::vector<std::string> ScreenObservations(const Observations& obs,
                                            const std::vector<CameraTool>& cameras,
                                            const ScreenOptions& options);

}  // namespace rtscalib
