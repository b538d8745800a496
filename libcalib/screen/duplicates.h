// Rows that repeat an earlier row of the same file exactly (every column but
// the line number equal): a file appended to itself, a block pasted twice, a
// photo listed twice in shots.csv. A copy is no second measurement: kept, it
// would count twice and shrink every sigma by up to 1/sqrt(2), and a gross
// row present twice can outvote the robust tests. So each later copy is
// taken out before the fit (listed with the gross rows, libcalib/screen/
// gross.h, its reason naming the line it repeats) and the screening says so
// in a notice (docs/screening.md, "Duplicate rows"). A genuine repeat
// measurement that agrees with the first to the last digit of every column
// loses only its weight: the model is the same, its sigmas a little larger.
//
// Rows of pixels.csv or of detected photos compare every field of the
// observation (shot, placement, target, corner, point, pixel, readings,
// covariates); the corners of one photo share its shots.csv line, so a photo
// listed twice shows as line pairs of shots.csv.
#pragma once

#include <string>
#include <vector>

#include "libcalib/model/observations.h"

namespace rtscalib {

// Every later copy, records first, each in file order; ExcludedRow::reason
// names the line the row repeats.
std::vector<ExcludedRow> FindDuplicateRows(const Observations& obs);

// One notice per file with copies: the file, how many rows, the first few
// line pairs and that the copies are taken out; empty without copies.
std::vector<std::string> DuplicateRowNotices(const Observations& obs);

}  // namespace rtscalib
