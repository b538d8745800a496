// The tests of every probe of structure outside the catalogue (harmonics of
// phi and theta, trends against the session's other variables, image
// motions and fields; linearization.h defines them), in three steps:
//  1. before the catalogue: each probe tested against the fitted model alone;
//  2. unexplained: forward selection of probes on top of ALL catalogue effects
//     that the data can see (each step adds the most significant probe, until
//     none is significant or `max_terms`): what remains significant is
//     structure that no catalogue effect can produce;
//  3. a probe significant in (1) but not in (2) on top of the catalogue is
//     explained by the catalogue; `explained_by` names the single effect that
//     removes most of it. One still significant on top of the catalogue but
//     not selected describes structure a selected probe holds (`same_as`).
// A probe's column that a projection (the fit's parameters, the catalogue,
// the probes selected) leaves with less than kAbsorbed of its norm is
// absorbed: it is dropped from the test, as a candidate effect is redundant
// (ranking.h), so that round-off of an absorbed direction never tests as
// structure.
// Tests are the robust Wald tests of statistics.h at level significance /
// (number of probes) (Bonferroni). One joint selection over every kind of
// probe, so that two kinds that describe the same structure (a drift of the
// horizontal index and a harmonic of phi) are not both reported.
// harmonics.h and structure.h turn the results into words.
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/diagnose/statistics.h"

namespace rtscalib {

// A probe's column that keeps less than this fraction of its norm once the
// fit's own parameters are projected out is theirs, not the probe's: what
// is left of it is too little of its shape to be named after it (an image
// rotation in photos that each have their own board pose, which turns with
// the photo: a coefficient fitted to the remaining 1 % would state a
// rotation of hundreds of pixels).
constexpr double kAbsorbed = 0.05;

struct ProbeResult {
  const ColumnBlock* block = nullptr;
  ColumnTest raw;  // (1) against the fitted model alone
  bool raw_significant = false;
  bool selected = false;     // (2) significant on top of the whole catalogue
  ColumnTest joint;          // (2) with the other selected probes (selected only)
  // (2) the test where the selection took it (on top of the catalogue and
  // the probes selected before it) and its columns there: what it adds to
  // them. Two probes of one structure (a focus seen against the target and
  // the focus distance) each add little on top of the other, but the first
  // selected carries it: its gain and size are the structure's.
  ColumnTest at_selection;
  Eigen::MatrixXd selection_columns;
  std::string explained_by;  // (3) raw significant, not significant on top of the catalogue
  std::string same_as;       // (3) significant on top of the catalogue, but a selected probe holds it
};

struct ProbeAnalysis {
  std::vector<ProbeResult> probes;  // every probe block of the linearisation, in its order
  std::vector<int> selected;        // (2) indices into `probes`, most significant first
  double level = 0;                 // per-test level
  int tests = 0;
};

// `catalogue` = column blocks of the candidate effects the data can see.
ProbeAnalysis AnalyseProbes(const Linearization& lin, const Reduced& red,
                            const std::vector<const ColumnBlock*>& catalogue, double significance,
                            int max_terms = 6);

}  // namespace rtscalib
