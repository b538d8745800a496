// Gross errors found before any fit (docs/screening.md):
// rows that no instrument could have produced together with the others are
// taken out, listed with their lines and the numbers that betray them, so
// that the extraction and the fit start from the rest. What is left is found
// by the robust fit (libcalib/fit/robust.h).
//
//  - Records whose point does not lie at its distance from the instrument:
//    every EDM point x_i at distance d_i lies on a sphere about the
//    instrument centre c, |x_i - c| = d_i + k0, up to the EDM tool's offset
//    (millimetres); camera rows of one zoom likewise about the camera's
//    centre, up to the camera tool's offset. c and k0 (a linear problem in
//    c, k0 and k0^2 - |c|^2) come from least median of squares over random
//    5-row samples, which ignores up to half the rows; a row whose
//    |x - c| - d - k0 departs from the rows' median by more than
//    GrossScreenOptions::sphere_threshold robust sigmas (and at least
//    `sphere_floor_m`) is gross: a point or a distance off by centimetres
//    to kilometres.
//  - Rows whose face label contradicts their zenith angle (SPEC 1: face 1
//    has theta in [0, pi], face 2 in [pi, 2 pi]) when they are a minority
//    of that face's rows (FewEnoughToBeGross): single wrong labels.
//    More is a convention mistake, which screen.h reports as an error; so
//    are many points too far for their distances (millimetres), while a
//    few are gross rows found by the sphere test above.
#pragma once

#include <vector>

#include "libcalib/model/observations.h"
#include "libcalib/screen/options.h"

namespace rtscalib {

// SPEC 1's face convention: face 1 reads theta in [0, pi], face 2 in [pi, 2 pi].
bool FaceContradictsTheta(int face, double theta);
// Whether `offending` of `rows` rows that break one of SPEC 1-3's
// conventions are single wrong rows (gross errors, taken out and listed)
// rather than a convention or unit mistake of the file (an error,
// screen.h): at most one in ten of them, and not all.
bool FewEnoughToBeGross(size_t offending, size_t rows);

// Exact copies of earlier rows (duplicates.h, found also with options.enabled
// false), then the rows above, in file order (records first). Throws std::invalid_argument
// when options.Check() fails.
std::vector<ExcludedRow> FindGrossRows(const Observations& obs, const GrossScreenOptions& options);

// `obs` without the rows listed in `rows` (ExcludedRow::index into `obs`).
// `record_from` and `pixel_from`, when given, receive for each row kept its
// index in `obs`.
Observations WithoutRows(const Observations& obs, const std::vector<ExcludedRow>& rows,
                         std::vector<int>* record_from = nullptr,
                         std::vector<int>* pixel_from = nullptr);

}  // namespace rtscalib
