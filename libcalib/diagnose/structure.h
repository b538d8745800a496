// Structure beyond phi and theta: the residuals tested against the other
// variables a real session has, and what is found said in words.
//
// Session variables (SessionVariables, one value per record and per image
// observation):
//   target distance  [m]  a photo's D computed from the model (the distance
//                         from its camera to the centroid of its points,
//                         libcalib/model/focus.h); a record's d
//   focus distance   [m]  the photos' focus_distance column, when given and
//                         not the same as the target distance
//   photo order           the order of the photos in the file (first
//                         appearance of each shot): the order they were taken
//   record order          the row order of records.csv
//   <covariate>           each extra numeric column of records.csv and
//                         shots.csv / pixels.csv (temperature, time, ...)
//   placement, board      categorical: the photo's placement (SPEC 7.1), the
//                         board its point lies on
// Probes (StructureProbes; their columns in linearization.h):
//   reading trends   phi, theta and distance errors (the distance also as a
//                    scale) against the record order, the photo order
//                    (Legendre P1, P2: a drift) and each covariate (linear);
//                    only with a kinematic chain
//   image motions    per zoom, scale, shift and rotation of the image against
//                    the target distance (as 1/D and as D), the focus
//                    distance (1/D), the photo order (P1, P2), each covariate
//                    (linear), the placement and the board (one set per
//                    category)
//   image fields     per zoom, the displacement field over the image position
//                    (degree 2 and 3) and along/across the radius
// They are tested with the harmonics (probes.h); AnalyseStructure turns the
// significant ones into sentences: the variable, the form, the size over
// the variable's range, and the catalogue effect it points to.
#pragma once

#include <string>
#include <vector>

#include "libcalib/diagnose/linearization.h"
#include "libcalib/diagnose/probes.h"
#include "libcalib/diagnose/ranking.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

std::vector<SessionVariable> SessionVariables(const Observations& obs,
                                              const InstrumentModel& model);

// The probes of the families above for the data at hand (a variable without
// at least three distinct values, or two categories, on a probe's rows gives
// no probe). `readings`: the model has a kinematic chain (not camera-only).
std::vector<Probe> StructureProbes(const std::vector<SessionVariable>& variables,
                                   const Observations& obs, const InstrumentModel& model,
                                   bool readings);

struct StructureFinding {
  Probe probe;
  std::string block;     // the probe's column block name
  std::string variable;  // "target distance"
  std::string quantity;  // "image scale of zoom 1", "phi (horizontal angle) error"
  std::string form;      // "1/target distance", "a drift", "linear", "per placement"
  // Reading trends: the largest change of the fitted trend over the
  // variable's range (arcsec, mm, ppm). Image motions and fields: the
  // largest displacement it makes at the observed points [px] (camera
  // records: [mm]), of the part that nothing else fitted can take up; never
  // a field evaluated where no photo reached.
  double size = 0;
  std::string unit;      // "arcsec", "mm", "ppm", "px"
  double lo = 0, hi = 0;  // the variable's range
  double reach = 0;       // image findings: the data's farthest point / half-diagonal
  double wald = 0, p_value = 1;
  // The relative fall of the fit's rms (the largest over the observation
  // groups) if the structure were modelled (RelativeGain), and whether that
  // is worth a sentence (Materiality): structure within the scatter is not.
  double gain = 0;
  bool material = false;
  bool unexplained = false;   // significant on top of the whole catalogue
  std::string explained_by;   // the catalogue effect that removes it (explained ones)
  std::string same_as;        // the unexplained probe that holds the same structure
  std::string points_to;      // the catalogue effect or physical cause it suggests
  std::string description;    // the sentence
};

struct StructureAnalysis {
  // Significant on top of the catalogue and material, most significant first.
  std::vector<StructureFinding> unexplained;
  // Significant on top of the catalogue but within the scatter (gain below
  // Materiality::min_gain): statistically real, not worth a model term.
  std::vector<StructureFinding> negligible;
  // Significant alone, but removed by a catalogue effect (explained_by) or
  // held by an unexplained finding (same_as).
  std::vector<StructureFinding> explained;
};

// The reading-trend, image-motion and image-field probes of `probes`.
StructureAnalysis AnalyseStructure(const Linearization& lin, const Reduced& red,
                                   const ProbeAnalysis& probes, const InstrumentModel& model,
                                   const Materiality& scale);

}  // namespace rtscalib
