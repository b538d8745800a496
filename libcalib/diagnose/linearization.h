// The fitted model, linearised: whitened residuals and their derivatives with
// respect to (a) the parameters the fit left free, (b) every candidate
// effect's parameters at their current value, (c) probes of structure outside
// the catalogue. Every diagnostic (ranking, harmonics, outliers) is a question
// about these columns; asking it costs one Jacobian evaluation instead of one
// refinement per question.
//
//   r_i        = (model_i - observed_i) / sigma_g          (g = edm, cam, pixel group)
//   base       = d r / d (free parameters of the fit)      tangent space of each block
//   extra      = [d r / d (effect e's parameters)]_e  [d r / d (probe p's coefficients)]_p
//
// (a) and (b) use the cost functions, the observation groups and the
// `Parameterization` of the refinement (libcalib/fit/parameterization.h): the
// candidates are enabled in a copy of the model, the fit's parameterisation of
// that copy decides every block, and the columns that belong to a candidate
// effect (its own block, or its coefficients in a zoom's distortion block) go
// to `extra`, all others to `base`. Nothing is decided here.
//
// (c) A probe is a generic error of one reading (phi, theta or d) that is a
// harmonic of one variable on the rows of one face:
//   reading* = reading + a cos(k x) + b sin(k x),   x = phi, theta [rad] or 2 pi d / U
// Its columns are d r / d reading * [cos(k x), sin(k x)] (central differences).
// Catalogue effects are probes too (hz_eccentricity = phi error, harmonic 1 of
// phi); testing probes on top of the whole catalogue isolates structure that
// no catalogue effect can produce.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libcalib/diagnose/statistics.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

const char* GroupName(ObsGroup g);

enum class Reading { kPhi, kTheta, kDistance };
const char* ReadingName(Reading r);

struct Probe {
  Reading reading = Reading::kPhi;   // which reading is in error
  Reading variable = Reading::kPhi;  // the error is periodic in this variable
  int harmonic = 1;                  // k
  int face = 1;                      // rows of this face only
};

// One row of the stacked residual vector.
struct ResidualRow {
  ObsGroup group = ObsGroup::kEdm;
  int index = 0;      // into obs.records (edm, cam) or obs.pixels
  int component = 0;  // x, y, z (records) or u, v (pixels)
  int cluster = 0;    // rows that share a pointing (records) or a shot (pixels)
  int face = 1;
};

// A contiguous block of columns of `extra`.
struct ColumnBlock {
  std::string name;
  int first = 0;
  int size = 0;
  std::vector<std::string> param_names;
  // Catalogue effects: which effect; distortion groups: which (zoom, index)
  // each column is.
  bool is_effect = false;
  Effect effect = Effect::kCollimation;
  std::vector<std::pair<int, int>> distortion;  // (zoom, coefficient index)
  // Probes.
  bool is_probe = false;
  Probe probe;
};

struct LinearizeOptions {
  FitOptions fit;  // as used by the fit (zenith limits, fit_intrinsics, threads)
  double sigma[3] = {1e-5, 1e-5, 0.5};  // whitening per ObsGroup (the fit's a-posteriori sigmas)
  std::vector<Effect> candidates;       // effects not in the model whose columns to add
  std::vector<Probe> probes;
};

struct Linearization {
  Eigen::VectorXd r;
  Eigen::MatrixXd base;
  std::vector<std::string> base_names;
  std::vector<FreeColumn> base_columns;  // per base column: its name, effect, zoom, index
  Eigen::MatrixXd extra;
  std::vector<ColumnBlock> blocks;
  std::vector<ResidualRow> rows;
  int num_clusters = 0;
  std::vector<std::string>
      cluster_names;  // "face 1, phi 30.0 deg, theta 90.0 deg" or "shot z0f1s3"
  double sigma[3] = {1, 1, 1};
  int num_observations[3] = {0, 0, 0};  // records (edm, cam) and pixel points used
  int excluded_critical = 0;
  int not_evaluable = 0;                // groups the model could not evaluate (skipped)
  double edm_cyclic_unit_length = 1.5;  // U of the distance probes [m]

  const ColumnBlock* Find(const std::string& name) const;
  int NumRows() const { return static_cast<int>(r.size()); }
};

// Throws std::invalid_argument for bad options, like Refine.
Linearization Linearize(const Observations& obs, const InstrumentModel& model,
                        const LinearizeOptions& options);

// The linearisation with the fit's own directions projected out: `r` is what
// remains after one more Gauss-Newton step of the fit's parameters (at the
// fitted model it differs from lin.r only by round-off and by the last sigma
// update of Refine), `extra` what of each candidate column the fit's
// parameters cannot absorb.
struct Reduced {
  Eigen::VectorXd r;
  Eigen::MatrixXd extra;
  Projector base;
  std::vector<int> cluster;
  // |column of extra after projection| / |column before|, per column (0 when
  // the column is zero: the data do not see that parameter at all).
  Eigen::VectorXd kept_fraction;
  Eigen::VectorXd column_norm;
  explicit Reduced(int rows) : base(rows) {}
};
Reduced Reduce(const Linearization& lin);

}  // namespace rtscalib
