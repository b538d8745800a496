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
// (c) A probe is a generic error outside the catalogue, of one of four kinds
// (ProbeKind), each a few columns of `extra`:
//   harmonic       one reading's error as a harmonic of one variable on the
//                  rows of one face:
//                    reading* = reading + a cos(k x) + b sin(k x),  x = phi, theta [rad] or 2 pi d / U
//                  columns d r / d reading * [cos(k x), sin(k x)]
//   reading trend  one reading's error as a function of a session variable
//                  (SessionVariable: the order of the rows or photos, a
//                  covariate column such as temperature), both faces:
//                    reading* = reading + sum_j b_j f_j(x)
//                  columns d r / d reading * f_j(x) (for the distance also
//                  times d: a scale that changes with x)
//   image motion   the image of one zoom scaled about the principal point,
//                  shifted in u and v and turned about the principal point,
//                  by amounts that are functions of a session variable (the
//                  target distance D as 1/D or D, the photo order, a
//                  covariate, the board or placement):
//                    pixel* = pixel + sum_j f_j(x) [s (pixel - c) + (a, b) + w J (pixel - c)]
//                  columns d r / d (s, a, b, w) * f_j(x): analytic for image
//                  points, central differences of F_CAM for camera records
//   image field    a displacement field over the image of one zoom: the
//                  monomials of degree 2 and 3 in the image position
//                  (x, y in [-1, 1] over the image), or radial and
//                  tangential terms in the radius rho (1 at the corners):
//                  rho^n along (n = 3, 5, 7, 9) and across (n = 3, 5) the radius
// f_j (TrendForm): x - mean (linear), 1/x - mean (inverse), the Legendre
// polynomials P1, P2 over the variable's range (quadratic), or one indicator
// per category. Reading derivatives are central differences of the model's
// predictions. Catalogue effects are probes too (hz_eccentricity = phi error,
// harmonic 1 of phi; focus = image scale and shift as 1/D); testing probes
// on top of the whole catalogue isolates structure that no catalogue effect
// can produce.
#pragma once

#include <Eigen/Core>
#include <optional>
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

enum class ProbeKind { kHarmonic, kReadingTrend, kImageMotion, kImageField };
// How a trend probe's error depends on its variable (the functions f_j above).
enum class TrendForm { kLinear, kInverse, kQuadratic, kCategories };
enum class ImageField { kPosition, kRadius };
// The four image motions of an image-motion probe, in column order.
constexpr int kNumImageMotions = 4;  // scale, shift u, shift v, rotation
// At most this many functions f_j per trend probe (categories of a
// categorical variable beyond it are not tested, SessionVariables).
constexpr int kMaxTrendFunctions = 32;

struct Probe {
  ProbeKind kind = ProbeKind::kHarmonic;
  Reading reading = Reading::kPhi;   // harmonic, reading trend: which reading is in error
  Reading variable = Reading::kPhi;  // harmonic: the error is periodic in this variable
  int harmonic = 1;                  // k
  int face = 1;                      // harmonic: rows of this face only
  // Reading trends and image motions: the session variable (index into
  // LinearizeOptions::variables) and how the error depends on it.
  int session_variable = -1;
  TrendForm form = TrendForm::kLinear;
  bool per_metre = false;  // distance trends: the error is proportional to d
  int zoom = -1;           // image motions and fields: the zoom
  ImageField field = ImageField::kPosition;
};

// A variable of the session that the residuals are tested against (beyond
// phi and theta): one value per record and per image observation, NaN where
// a row has none. Categorical variables hold category indices.
struct SessionVariable {
  std::string name;  // "target distance", "photo order", "temperature", "placement"
  std::string unit;  // "m", "" (orders, covariates of unknown unit)
  bool categorical = false;
  std::vector<std::string> categories;
  std::vector<double> record;  // per obs.records
  std::vector<double> pixel;   // per obs.pixels
};

// One row of the stacked residual vector.
struct ResidualRow {
  ObsGroup group = ObsGroup::kEdm;
  int index = 0;      // into obs.records (edm, cam) or obs.pixels
  int component = 0;  // x, y, z (records) or u, v (pixels)
  int cluster = 0;    // rows that share a pointing (records) or a shot (pixels)
  int face = 1;
};

// The functions f_j of a trend probe (TrendForm), with the statistics of its
// variable over the rows the probe applies to.
struct TrendBasis {
  TrendForm form = TrendForm::kLinear;
  double mean = 0;         // of x (linear) or of 1/x (inverse)
  double lo = 0, hi = 1;   // range of x
  int size = 1;            // number of functions
  // f[0 .. size) at x.
  void Evaluate(double x, double* f) const;
};

// A contiguous block of columns of `extra`.
struct ColumnBlock {
  std::string name;
  int first = 0;
  int size = 0;
  std::vector<std::string> param_names;
  // Catalogue effects: which effect; camera effects (distortion groups,
  // focus): which (zoom, index in the zoom's block) each column is.
  bool is_effect = false;
  Effect effect = Effect::kCollimation;
  std::vector<std::pair<int, int>> distortion;  // (zoom, coefficient or focus index)
  // Per-board effects (board_warp): which (board first_id, index) each column is.
  std::vector<std::pair<int, int>> boards;
  // Probes.
  bool is_probe = false;
  Probe probe;
  TrendBasis basis;  // reading trends and image motions
};

struct LinearizeOptions {
  FitOptions fit;  // as used by the fit (zenith limits, fit_intrinsics, threads)
  double sigma[3] = {1e-5, 1e-5, 0.5};  // whitening per ObsGroup (the fit's a-posteriori sigmas)
  std::vector<Effect> candidates;       // effects not in the model whose columns to add
  std::vector<Probe> probes;
  std::vector<SessionVariable> variables;  // what trend probes refer to
  // Boards and points of unknown pose or position as base columns instead of
  // projected out (LocalColumns): a caller that sums the information of
  // subsets of the rows (the session planner, libcalib/plan) needs their
  // columns, since a subset's Schur complement is not the whole data's.
  bool local_as_base = false;
  // What the data determine (DataFacts), when the rows linearised are not
  // the session whose parameterisation is meant (the planner's image grid of
  // known points beside a session without any): the session's facts.
  std::optional<DataFacts> facts;
};

// The fit's parameters split in two (Linearization): the global ones that
// many observations share (the chain, cameras, effects) are `base`; the
// local ones that only a few observations see, each board of unknown pose
// (6 tangent columns per placement, SPEC 7) and each point of unknown
// position (3), are projected out of every other column on their own rows
// (Frisch-Waugh-Lovell, block by block): a camera-only session of 186
// photos has 1,116 of them, which as dense base columns would cost a QR of
// n x 1,125 instead of 186 small ones. Boards whose rows overlap (a photo's
// focus distance from the centroid of all its boards, SPEC 4.1) are one
// block.
struct LocalColumns {
  // One block of rows and the orthonormal basis of its local columns there.
  struct Block {
    std::vector<int> rows;
    Eigen::MatrixXd q;  // rows.size() x rank
  };
  std::vector<Block> blocks;
  int columns = 0;  // tangent columns of the boards and points
  int rank = 0;     // directions they span in these data
  // Per row: |Q_L row|^2, the local parameters' share of its leverage.
  Eigen::VectorXd leverage;
  // v := (I - Q_L Q_L') v, block by block.
  void Project(Eigen::Ref<Eigen::VectorXd> v) const;
};

struct Linearization {
  // The residual at the fitted model, as it is (the fit quality and the
  // current rms read it).
  Eigen::VectorXd r;
  // base and extra are projected off the local parameters (LocalColumns):
  // base' base is then the normal matrix of the global parameters with the
  // local ones estimated alongside (the Schur complement), and every test
  // below sees exactly the freedom the fit had (Reduce projects r too).
  Eigen::MatrixXd base;
  std::vector<std::string> base_names;
  std::vector<FreeColumn> base_columns;  // per base column: its name, effect, zoom, index
  Eigen::MatrixXd extra;
  // |column of extra| before the local projection: what an absorbed column
  // is measured against (Reduced::column_norm).
  Eigen::VectorXd extra_norm;
  LocalColumns local;
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
  std::vector<SessionVariable> variables;  // LinearizeOptions::variables

  const ColumnBlock* Find(const std::string& name) const;
  int NumRows() const { return static_cast<int>(r.size()); }
};

// `obs` as the fit saw it: pixels on boards of unknown pose (SPEC 7) leave
// X, Y, Z empty and the model's estimated boards hold them, free here as in
// the fit. Throws std::invalid_argument for bad options, like Refine.
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
  int local_rank = 0;  // Linearization::local.rank
  explicit Reduced(int rows) : base(rows) {}
  // Directions of the fit's parameters in these data, global and local:
  // the degrees of freedom every test subtracts.
  int Rank() const { return base.rank() + local_rank; }
};
Reduced Reduce(const Linearization& lin);

}  // namespace rtscalib
