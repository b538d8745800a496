// Which catalogue effect is missing: every effect not in the model, added to
// it one at a time, scored and sorted best first (SPEC 6 diagnosis.ranking).
//
// For effect e with columns T_e (linearization.h) and the fitted model's own
// parameters projected out (Reduced):
//   estimate      b_e, cov_e          TestColumns (statistics.h), conditional on the
//                                     unexplained harmonics (harmonics.h) so that an
//                                     effect is not credited with structure that is not its own
//   delta_bic     sum_g n_g log(RSS_g,after / RSS_g,before) + k log n
//                 g = observation group (edm, cam, pixels) with its own variance, n_g its
//                 residual rows, n = sum n_g, k = rank of T_e; negative = better. With one
//                 free variance per group this is the BIC of the Gaussian likelihood, so a
//                 group whose fitted sigma the missing effect inflated still counts fully.
//   significant   p(Wald) < significance / (number of effects tested) and delta_bic < 0
//                 and the rms falls by more than the numerical floor (kPointFloorM,
//                 kPixelFloor): exact data must not make round-off significant
//   rms after     from a refinement with the effect added (Refine from the fitted model,
//                 the effect at its linear estimate, the estimated boards and points free,
//                 the fit's weights held) for the best `refine_top` significant effects:
//                 the fall the user will see; delta_bic, gain and the order follow the
//                 refit. From the linear prediction (one Gauss-Newton step) for the others.
//   gain          the largest relative fall of a group's rms, (before - after) / before;
//                 worthwhile when >= min_gain (2 %): with thousands of corners a term
//                 that buys a thousandth of the rms is significant and changes nothing
//   recommended   significant, worthwhile and not redundant: what the verdict says to
//                 add; a significant effect that is not worthwhile is said as such
//   redundant     the model's parameters absorb T_e entirely (|P T_e| < redundant_fraction |T_e|),
//                 or SPEC 4 says the kinematics contain it (dh: collimation, tilting_axis,
//                 vertical_index, edm_offset); then `equivalent` holds the value read off
//                 the model (equivalents.h)
//   identifiable  observable, not redundant, and |rho| <= identifiable_rho with every
//                 parameter of the model (covariance of the model with e added)
//   aliases       other significant effects that make e insignificant when added
//                 first (and vice versa): the data cannot tell them apart
// Effect values are reported in report units (ToReportUnits); distortion groups
// per zoom and coefficient.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "libcalib/diagnose/coverage.h"
#include "libcalib/diagnose/equivalents.h"
#include "libcalib/diagnose/linearization.h"

namespace rtscalib {

// Below these an improvement is round-off, not physics: 1 nm is 1e-9 of a
// metre-scale coordinate (double precision leaves ~1e-15); 1e-6 px likewise.
constexpr double kPointFloorM = 1e-9;
constexpr double kPixelFloor = 1e-6;
// Harmonic amplitudes below these are never reported as structure: no
// instrument resolves them (1e-3 arcsec, 1e-3 mm).
constexpr double kAngleFloorArcsec = 1e-3;
constexpr double kDistanceFloorMm = 1e-3;

// RMS per observation group over the rows the fit uses (outside the critical
// regions): records as point distances [m], pixels as sqrt(mean(du^2 + dv^2)) [px].
struct GroupRms {
  double edm_m = 0, cam_m = 0, records_m = 0, pixels_px = 0;
  int edm_n = 0, cam_n = 0, pixels_n = 0;
  double edm_ss = 0, cam_ss = 0, pixels_ss = 0;  // sums of squares [m^2], [px^2]
  // The headline figure: every record point [m] when there are records, else pixels [px].
  double Main() const { return edm_n + cam_n > 0 ? records_m : pixels_px; }
  const char* MainUnit() const { return edm_n + cam_n > 0 ? "m" : "px"; }
  // Whitened residual sum of squares with sigmas per group.
  double WhitenedRss(const double sigma[3]) const;
  // BIC with one free variance per group: sum_g n_g log(RSS_g / n_g) + k log n,
  // n_g = residual rows of group g (3 per record, 2 per image point).
  double Bic(int num_parameters) const;
};

GroupRms RmsOfWhitened(const Linearization& lin, const Eigen::VectorXd& r);
// `obs` as the fit saw them (pixels on boards of unknown pose are placed on
// the model's estimated boards).
GroupRms RmsOfModel(const Observations& obs, const InstrumentModel& model, const FitOptions& fit);
// `before` less the part `explained` takes out of each group's sum of
// squares (whitened rows of `lin`, e.g. a regression's fitted values: the
// fall of the residual sum of squares when its columns are added).
GroupRms RmsLess(const Linearization& lin, const GroupRms& before, const Eigen::VectorXd& explained);
// The largest relative fall of a group's rms, (before - after) / before,
// over the observation groups present: what adding a term buys the user,
// on the scale the fit's own residuals set.
double RelativeGain(const GroupRms& before, const GroupRms& after);

// What makes a finding (an effect to add, a structure outside the
// catalogue) worth the user's attention besides its statistical test: with
// thousands of corners a term that moves them by a hundredth of the scatter
// is significant, and adding it changes nothing a user would see.
struct Materiality {
  GroupRms current;     // the fit's rms per group: the scale of every gain
  double min_gain = 0.02;  // smallest relative fall of a group's rms worth a recommendation
  // Per zoom: the farthest observed image point from the image centre over
  // the half-diagonal (Coverage::corner_fraction): where the data end.
  std::vector<double> reach;
  bool Material(double gain) const { return gain >= min_gain; }
};

// Iterations of a refit (RankingOptions::refine_top): a wide lens's
// rational group from k1..k3 converges in ~30 (the mrcal tour's corners).
constexpr int kRefitIterations = 50;

struct RankingOptions {
  double significance = 0.01;  // family-wise level over the effects tested
  double identifiable_rho = 0.95;
  double redundant_fraction = 1e-3;
  int refine_top = 3;     // leading significant effects refitted (RankedEffect::after_source)
  double min_gain = 0.02;  // Materiality::min_gain: smallest gain worth a recommendation
};

struct DistortionValue {
  int zoom = 0;
  std::string coefficient;  // k1, p2, ...
  int index = 0;            // into the 14 OpenCV coefficients
  double value = 0, sigma = 0;
};

// One focus parameter of one zoom (SPEC 4.1), in SI (kf [m], au, av [px m];
// reports scale by kFocusReportScale).
struct FocusValue {
  int zoom = 0;
  std::string name;  // kf, au, av
  int index = 0;     // FocusIndex
  double value = 0, sigma = 0;
};

// One warp parameter of one board of estimated pose (board_warp), in SI [m]
// (reports in mm).
struct WarpValue {
  int first_id = 0;   // the board's first tag
  std::string name;   // wx, wy
  int index = 0;
  double value = 0, sigma = 0;
};

struct RankedEffect {
  Effect effect = Effect::kCollimation;
  std::string name;
  int num_params = 0;  // rank of its columns in these data
  GroupRms before, after;
  GroupRms linear_after;  // the linear prediction, kept when a refit replaced it
  double rms_before = 0, rms_after = 0;
  std::string rms_unit;
  double delta_rss = 0, delta_bic = 0, wald = 0, p_value = 1;
  bool observable = true, redundant = false, identifiable = true, significant = false;
  // The relative fall of the rms it buys (RelativeGain of before and after),
  // whether that is worth a model term (>= RankingOptions::min_gain), and
  // whether the diagnosis recommends it: significant, worth it, not redundant.
  double gain = 0;
  bool worthwhile = false, recommended = false;
  std::string correlated_with;  // the model parameter with the largest |rho|
  double rho = 0;
  std::array<double, 2> si{};  // estimate in SI (kinematic effects)
  std::array<double, 4> si_cov{};
  EffectReportValue value;  // in report units
  std::vector<DistortionValue> distortion;
  std::vector<FocusValue> focus;
  std::vector<WarpValue> board_warp;
  bool has_equivalent = false;  // redundant: value read off the model
  EffectReportValue equivalent;
  std::vector<std::string> needs;  // what data would make it identifiable / better determined
  // Other significant effects that explain the same structure in these data
  // (each one, added, leaves the other insignificant): first-order aliases
  // such as radial/rational distortion.
  std::vector<std::string> aliases;
  std::string config_line;
  // Where `after` comes from: "refined" (a refinement with the effect
  // added, as the calibration would run it: what the user will see) or
  // "linearised" (one Gauss-Newton step from the fitted model: a prediction,
  // first order in the effect).
  std::string after_source;
  std::string note;
};

// One estimated quantity of a ranked effect, in report units: the text
// report and report.html say the same numbers from these.
struct EstimatePart {
  std::string where;  // "zoom 0", "board 12"; "" for the instrument's (kinematic effects)
  std::string name;   // the parameter, e.g. "c", "wx", "kf"
  double value = 0, sigma = 0;
  std::string unit;
};

// The estimate of a kinematic, board or focus effect (value and sigma per
// parameter, per board or zoom in that order); empty for the others
// (distortion groups list their coefficients in RankedEffect::distortion).
std::vector<EstimatePart> EstimateParts(const RankedEffect& r);

struct Ranking {
  std::vector<RankedEffect> entries;  // best first
  double level = 0;                   // per-effect test level
  int tested = 0;
  // Significant effects worth adding that stay so once the best one is
  // added (what the next rungs of the ladder will likely add), judged to
  // first order; empty when the best one's refit moved the residuals far
  // from that first order (then only a new diagnosis tells).
  std::vector<std::string> also_after_best;
  bool after_best_tested = false;  // whether also_after_best was worked out
  int num_rows = 0;
  GroupRms current;
};

struct RankingInput {
  const Observations* obs = nullptr;  // as the fit used them (the refits free the boards)
  const InstrumentModel* model = nullptr;
  FitOptions fit;  // as the fit used them
  const Linearization* lin = nullptr;
  const Reduced* red = nullptr;
  const Projector* nuisance = nullptr;  // unexplained harmonics, in the reduced space
  const Coverage* coverage = nullptr;
  const EquivalentTerms* equivalents = nullptr;  // dh only
  std::vector<Effect> contained;                 // catalogue effects the kinematics already contain
};

Ranking RankEffects(const RankingInput& in, const RankingOptions& options);

// `model` with effect r.effect added at r's estimate (kinematic value,
// distortion coefficients, focus terms or board warps), the model's other parameters as
// they are.
void AddAtEstimate(const RankedEffect& r, InstrumentModel* model);

// "model.effects: [hz_eccentricity, edm_scale]": the model's effects plus `e`.
std::string ConfigLine(const InstrumentModel& model, Effect e);

}  // namespace rtscalib
