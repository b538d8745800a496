#include "libcalib/fit/refine.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/cost_functions.h"
#include "libcalib/fit/manifolds.h"
#include "libcalib/fit/observation_loss.h"
#include "libcalib/fit/parameter_layout.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/fit/unknowns.h"

namespace rtscalib {

std::string FitOptions::Check() const {
  if (!(sigma_edm_m > 0) || !(sigma_cam_m > 0) || !(sigma_pixel_px > 0)) {
    return "fit.sigmas must all be > 0";
  }
  if (!(loss_scale > 0)) return "fit.robust_loss.scale must be > 0";
  if (max_iterations < 1) return "fit.max_iterations must be >= 1";
  if (translation_bound_m < 0) return "fit.translation_bound_m must be >= 0";
  if (const std::string region = critical_region.Check(); !region.empty()) {
    return "fit.critical_region: " + region;
  }
  if (num_threads < 1) return "fit.threads must be >= 1";
  return gross_errors.Check();
}

namespace {

// Residuals x parameters above which the solver uses the sparse normal
// equations instead of dense QR (docs/refinement.md, "Speed").
constexpr double kDenseQrLimit = 4e6;

// The free blocks by address, named (covariance and correlation names); the
// address order is the covariance's column order.
using NamedBlocks = std::map<const double*, std::string>;

struct ResidualRef {
  ceres::ResidualBlockId id;
  ObsGroup group;
  std::vector<int> indices;  // into records or pixels
  int slot = 0;              // its variance component (VarianceSlot)
};

// The variance components: EDM points, camera points and the pixels of each
// zoom level apart (a detector's noise depends on the zoom: the rendered
// demo's corners scatter 0.013, 0.016 and 0.031 px at zooms 0, 1, 2).
constexpr int kPixelSlots = 2;  // slots 2 + zoom
int VarianceSlot(ObsGroup group, int zoom) {
  return group == ObsGroup::kPixel ? kPixelSlots + std::max(zoom, 0) : static_cast<int>(group);
}
std::vector<double> AprioriSigmas(const FitOptions& options, int num_zooms) {
  std::vector<double> sigma(kPixelSlots + std::max(num_zooms, 1), options.sigma_pixel_px);
  sigma[0] = options.sigma_edm_m;
  sigma[1] = options.sigma_cam_m;
  return sigma;
}

// The a-posteriori sigmas of `earlier` where it has them, else `apriori`.
std::vector<double> StartSigmas(const FitSummary& earlier, std::vector<double> apriori) {
  if (earlier.sigma_edm_m > 0) apriori[0] = earlier.sigma_edm_m;
  if (earlier.sigma_cam_m > 0) apriori[1] = earlier.sigma_cam_m;
  for (size_t z = 0; z < earlier.sigma_pixel_px_zoom.size(); ++z) {
    if (kPixelSlots + z < apriori.size() && earlier.sigma_pixel_px_zoom[z] > 0) {
      apriori[kPixelSlots + z] = earlier.sigma_pixel_px_zoom[z];
    }
  }
  return apriori;
}

// The clusters of observations whose errors may be correlated (the
// cluster-robust covariance, FitOptions::covariance_clusters): every record
// alone; the pixels of one photo together (kShot: a detector's errors share
// the photo's blur, exposure and sampling; the corners of one tag share its
// quad fit) or the pixels of one tag over all photos of its zoom (kTag: a
// detector's bias that follows the tag). `clusters[i][k]` is the cluster of
// refs[i]'s k-th observation.
std::vector<std::vector<int>> AssignClusters(const Observations& obs,
                                             const std::vector<ResidualRef>& refs,
                                             CovarianceClusters by) {
  std::map<std::tuple<std::string, int, int>, int> key_cluster;
  std::vector<std::vector<int>> out(refs.size());
  int next = 0;
  for (size_t i = 0; i < refs.size(); ++i) {
    for (int index : refs[i].indices) {
      if (refs[i].group != ObsGroup::kPixel) {
        out[i].push_back(next++);
        continue;
      }
      const PixelObservation& p = obs.pixels[index];
      const auto key = by == CovarianceClusters::kTag ? std::make_tuple(std::string(), p.zoom, p.target)
                                                      : std::make_tuple(p.shot, p.zoom, 0);
      const auto [it, added] = key_cluster.emplace(key, next);
      if (added) ++next;
      out[i].push_back(it->second);
    }
  }
  return out;
}

// The cluster-robust part of TangentCovariance (see there): returns the
// number of clusters and widens `cov`, which holds C (the pseudo-inverse of
// J^T J) on entry. `scale`, `eig`, `inv` are the Jacobi scaling and the
// eigen-decomposition of the scaled J^T J with its pseudo-inverse
// eigenvalues; `reported` marks the columns of the parameters the model
// reports (ParameterLayout: not the boards and points, the session's
// nuisance parameters).
//
// 1. Leverage (Bell & McCaffrey 2002, "CR2"): each cluster's residuals are
//    corrected, r_c -> (I - H_cc)^-1/2 r_c with H_cc = J_c C J_c^T. A fit
//    pulls every observation towards itself, and a cluster that alone
//    informs some direction (the photos that see the image corners, a
//    camera-only session of six photos) is pulled most: its residuals
//    understate its errors, and the plain sandwich with G/(G-1) (Liang &
//    Zeger's CR1) then claims up to ~1.5x too little on 16 photos. With the
//    correction E[M] = J^T J for independent errors of the assumed sigmas,
//    whatever the number of clusters. H_cc is formed in the columns the
//    cluster touches (k of them): J_c = Q R (thin QR), H_cc = Q S Q^T with
//    S = R C_kk R^T, so (I - H_cc)^-1/2 = I + Q U ((1 - s)^-1/2 - 1) U^T Q^T
//    (S = U diag(s) U^T) costs m k^2 per cluster of m rows. Directions with
//    1 - s ~ 0 are the cluster's own parameters (its board pose): its
//    residuals have no component there at the solution and are left as
//    they are.
// 2. The clusters' influence on the reported parameters, whitened by their
//    independent-error covariance C_LL: w_c = C_LL^-1/2 (C g_c)_L, g_c =
//    J_c^T r_c (corrected). W = sum_c w_c w_c^T is the sandwich relative to
//    C_LL: identity in expectation for independent errors.
// 3. Shrinkage (Ledoit & Wolf 2004): W is a sample covariance of G
//    influences and scatters around its truth, the more the fewer clusters
//    there are per reported direction (six photos tell nine directions
//    apart poorly). It is pulled towards its mean eigenvalue k = tr(W) / p
//    (at least 1) by the weight the clusters' own scatter gives, alpha =
//    min(1, b^2 / d^2) with d^2 = |S - mu I|^2, b^2 = sum_c |w_c w_c^T -
//    S|^2 / G^2 (S = W / G, mu = tr(S) / p): W* = alpha max(k, 1) I + (1 -
//    alpha) W. Few
//    clusters leave a common inflation k of all reported directions, many
//    clusters the direction each error really has (a photo's reading error
//    in the directions of the camera's pointing).
// 4. Taken where larger: C_LL + C_LL^1/2 V diag(max(0, l_i - 1)) V^T
//    C_LL^1/2 (W* = V diag(l) V^T), so that no reported direction is claimed
//    more precise than independent errors allow; the nuisance parameters
//    follow through their regression on the reported ones (the widening
//    D of C_LL enters the whole covariance as C_:L C_LL^+ D C_LL^+ C_L:).
int ClusterRobust(const ceres::CRSMatrix& j, const std::vector<double>& residuals,
                  const std::vector<ResidualRef>& refs,
                  const std::vector<std::vector<int>>& clusters, ceres::Problem* problem,
                  const Eigen::VectorXd& scale,
                  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>& eig,
                  const Eigen::VectorXd& inv, const std::vector<char>& reported,
                  Eigen::MatrixXd* cov) {
  const int n = j.num_cols;
  // The residual rows sorted by cluster (counting sort, stable): memory is
  // two ints per row, and each cluster is handled on its own (a million
  // records, each its own cluster, would hold 224 MB of dense scores).
  int num_clusters = 0;
  for (const std::vector<int>& of_ref : clusters) {
    for (int c : of_ref) num_clusters = std::max(num_clusters, c + 1);
  }
  std::vector<int> cluster_of_row(j.num_rows, -1);
  int row = 0;
  for (size_t i = 0; i < refs.size(); ++i) {
    const int rows = problem->GetCostFunctionForResidualBlock(refs[i].id)->num_residuals();
    const int per_obs = rows / static_cast<int>(clusters[i].size());  // 2 (pixel) or 3 (record)
    for (int r = row; r < row + rows; ++r) cluster_of_row[r] = clusters[i][(r - row) / per_obs];
    row += rows;
  }
  std::vector<int> start(num_clusters + 1, 0);
  for (int c : cluster_of_row) {
    if (c >= 0) ++start[c + 1];
  }
  for (int c = 0; c < num_clusters; ++c) start[c + 1] += start[c];
  std::vector<int> rows_by_cluster(start.back());
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (int r = 0; r < j.num_rows; ++r) {
      if (cluster_of_row[r] >= 0) rows_by_cluster[next[cluster_of_row[r]]++] = r;
    }
  }
  // C in the scaled coordinates (the scaled J^T J's pseudo-inverse), and
  // the whitening of its reported block: C_LL^-1/2 over the directions C_LL
  // has (a reported direction the data do not determine has none).
  const Eigen::MatrixXd c_scaled =
      eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  std::vector<int> l_cols;
  for (int i = 0; i < n; ++i) {
    if (reported[i]) l_cols.push_back(i);
  }
  const int nl = static_cast<int>(l_cols.size());
  if (nl == 0) return num_clusters;
  Eigen::MatrixXd c_ll(nl, nl), c_all(n, nl);
  for (int b = 0; b < nl; ++b) {
    c_all.col(b) = c_scaled.col(l_cols[b]);
    for (int a = 0; a < nl; ++a) c_ll(a, b) = c_scaled(l_cols[a], l_cols[b]);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> le(c_ll);
  if (le.info() != Eigen::Success) return num_clusters;
  const double l_max = le.eigenvalues().maxCoeff();
  std::vector<int> kept;
  for (int i = 0; i < nl; ++i) {
    if (le.eigenvalues()[i] > 1e-12 * l_max) kept.push_back(i);
  }
  const int p = static_cast<int>(kept.size());
  if (p == 0) return num_clusters;
  // Rows of `white`: the kept eigen-directions, scaled by l^-1/2 (w = white u).
  Eigen::MatrixXd white(p, nl), root(nl, p), pinv = Eigen::MatrixXd::Zero(nl, nl);
  for (int a = 0; a < p; ++a) {
    const double l = le.eigenvalues()[kept[a]];
    const Eigen::VectorXd v = le.eigenvectors().col(kept[a]);
    white.row(a) = v.transpose() / std::sqrt(l);
    root.col(a) = v * std::sqrt(l);
    pinv += v * v.transpose() / l;
  }

  // A score g (scaled coordinates) moves the whitened reported parameters
  // by influence * g: C_LL^-1/2 (C g)_L, one p x n product for all clusters.
  const Eigen::MatrixXd influence = white * c_all.transpose();
  Eigen::MatrixXd w_sum = Eigen::MatrixXd::Zero(p, p);
  double fourth = 0;  // sum_c |w_c|^4
  std::vector<int> touched;
  std::vector<int> local(n, -1);
  int used = 0;
  for (int c = 0; c < num_clusters; ++c) {
    if (start[c] == start[c + 1]) continue;
    ++used;
    touched.clear();
    for (int k = start[c]; k < start[c + 1]; ++k) {
      const int r = rows_by_cluster[k];
      for (int a = j.rows[r]; a < j.rows[r + 1]; ++a) touched.push_back(j.cols[a]);
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    const int kc = static_cast<int>(touched.size());
    const int mc = start[c + 1] - start[c];
    for (int a = 0; a < kc; ++a) local[touched[a]] = a;
    Eigen::MatrixXd jc = Eigen::MatrixXd::Zero(mc, kc);
    Eigen::VectorXd rc(mc);
    for (int k = start[c]; k < start[c + 1]; ++k) {
      const int r = rows_by_cluster[k];
      rc[k - start[c]] = residuals[r];
      for (int a = j.rows[r]; a < j.rows[r + 1]; ++a) {
        jc(k - start[c], local[j.cols[a]]) = j.values[a] * scale[j.cols[a]];
      }
    }
    for (int a : touched) local[a] = -1;
    // 1. The leverage correction in the cluster's column space.
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(jc);
    const int rank = std::min(mc, kc);
    const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(mc, rank);
    const Eigen::MatrixXd rr = qr.matrixQR().topRows(rank).triangularView<Eigen::Upper>();
    Eigen::MatrixXd c_kk(kc, kc);
    for (int a = 0; a < kc; ++a) {
      for (int b = 0; b < kc; ++b) c_kk(a, b) = c_scaled(touched[a], touched[b]);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> se(rr * c_kk * rr.transpose());
    const Eigen::VectorXd qr_c = q.transpose() * rc;
    Eigen::VectorXd stretch(rank);
    for (int a = 0; a < rank; ++a) {
      const double free = 1.0 - se.eigenvalues()[a];
      stretch[a] = free > 1e-10 ? 1.0 / std::sqrt(free) - 1.0 : 0.0;
    }
    const Eigen::VectorXd adjusted =
        rc + q * (se.eigenvectors() * stretch.cwiseProduct(se.eigenvectors().transpose() * qr_c));
    const Eigen::VectorXd g = jc.transpose() * adjusted;
    // 2. Its influence on the reported parameters, whitened.
    Eigen::VectorXd w = Eigen::VectorXd::Zero(p);
    for (int a = 0; a < kc; ++a) w += influence.col(touched[a]) * g[a];
    w_sum += w * w.transpose();
    fourth += w.squaredNorm() * w.squaredNorm();
  }
  if (used < 2) return used;
  // 3. Shrinkage towards the mean eigenvalue.
  const double g_count = used;
  const Eigen::MatrixXd s_mean = w_sum / g_count;
  const double mu = s_mean.trace() / p;
  const double s_norm2 = s_mean.squaredNorm();
  const double d2 = s_norm2 - p * mu * mu;
  const double b2 = std::max(0.0, (fourth - g_count * s_norm2) / (g_count * g_count));
  const double alpha = d2 > 0 ? std::min(1.0, b2 / d2) : 1.0;
  // The target: the mean eigenvalue, or the independent-error covariance
  // when the clusters scatter less than it (no direction is taken below it
  // anyway, and a small mean would drag the directions that do exceed it).
  const Eigen::MatrixXd shrunk =
      alpha * std::max(mu * g_count, 1.0) * Eigen::MatrixXd::Identity(p, p) + (1.0 - alpha) * w_sum;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> we(shrunk);
  if (we.info() != Eigen::Success) return used;
  // 4. The widening where the shrunk sandwich exceeds C_LL.
  const Eigen::VectorXd excess = (we.eigenvalues().array() - 1.0).max(0.0).matrix();
  if (excess.maxCoeff() <= 0) return used;
  const Eigen::MatrixXd widen_white =
      we.eigenvectors() * excess.asDiagonal() * we.eigenvectors().transpose();
  const Eigen::MatrixXd widen_ll = root * widen_white * root.transpose();
  const Eigen::MatrixXd lift = c_all * pinv;  // C_:L C_LL^+
  *cov += scale.asDiagonal() * (lift * widen_ll * lift.transpose()) * scale.asDiagonal();
  return used;
}

// Covariance of `blocks` in their tangent spaces: the pseudo-inverse of
// J^T J (J whitened, after the robust loss's reweighting), as
// ceres::Covariance's DENSE_SVD with null_space_rank = -1 gives it, but
// from the block-sparse Jacobian: forming J^T J costs m k^2 (k = parameters
// per residual row, ~40) where the SVD of the dense J costs m n^2 (n = all
// free parameters), the difference between a fraction of a second and
// seconds on joint_refine_benchmark's session of many zooms. J^T J is Jacobi-scaled before the eigen-decomposition so that
// units (pixels, metres, radians) do not decide which directions count as
// undetermined: eigenvalues below 1e-14 of the largest are dropped and
// counted in `dropped`.
//
// With `refs` (the cluster-robust covariance, FitOptions::covariance_clusters)
// the covariance of the parameters in `reported` is widened to the sandwich
// C M C (Liang & Zeger 1986), M = sum_c g_c g_c^T with g_c = J_c^T
// (I - H_cc)^-1/2 r_c over the whitened rows of cluster c: the scatter of
// the clusters' scores measured from the residuals instead of assumed from
// the sigmas, so that errors correlated within a cluster (a photo's
// detector bias, a camera whose principal point moves from photo to photo)
// count once per cluster, not once per row. For independent errors of the
// assumed sigmas its expectation is C. ClusterRobust says how: the leverage
// correction (I - H_cc)^-1/2, the shrinkage of a sandwich of few clusters
// towards its mean, and the widening only where it is larger than C, so
// that no direction is claimed more precise than the independent-error
// covariance says.
bool TangentCovariance(ceres::Problem* problem, const std::vector<const double*>& blocks, int n,
                       int num_threads, const std::vector<ResidualRef>* refs,
                       const std::vector<std::vector<int>>* clusters,
                       const std::vector<char>& reported, Eigen::MatrixXd* cov, int* dropped,
                       int* num_clusters) {
  ceres::Problem::EvaluateOptions eo;
  for (const double* p : blocks) eo.parameter_blocks.push_back(const_cast<double*>(p));
  if (refs) {
    for (const ResidualRef& ref : *refs) eo.residual_blocks.push_back(ref.id);
  }
  eo.apply_loss_function = true;
  eo.num_threads = num_threads;
  ceres::CRSMatrix j;
  std::vector<double> residuals;
  if (n == 0) return false;
  if (!problem->Evaluate(eo, nullptr, refs ? &residuals : nullptr, nullptr, &j) ||
      j.num_cols != n) {
    return false;
  }
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(n, n);
  for (int r = 0; r < j.num_rows; ++r) {
    for (int a = j.rows[r]; a < j.rows[r + 1]; ++a) {
      const double va = j.values[a];
      const int ca = j.cols[a];
      for (int b = a; b < j.rows[r + 1]; ++b) jtj(ca, j.cols[b]) += va * j.values[b];
    }
  }
  // Columns within a row are ascending, so the upper triangle is filled.
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) scale[i] = jtj(i, i) > 0 ? 1.0 / std::sqrt(jtj(i, i)) : 0.0;
  const Eigen::MatrixXd scaled =
      scale.asDiagonal() * jtj.selfadjointView<Eigen::Upper>().toDenseMatrix() * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  if (eig.info() != Eigen::Success) return false;
  const Eigen::VectorXd& lambda = eig.eigenvalues();  // ascending
  const double limit = 1e-14 * lambda[n - 1];
  Eigen::VectorXd inv(n);
  *dropped = 0;
  for (int i = 0; i < n; ++i) {
    inv[i] = lambda[i] > limit ? 1.0 / lambda[i] : 0.0;
    if (!(lambda[i] > limit)) ++*dropped;
  }
  *cov = scale.asDiagonal() *
         (eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose()) *
         scale.asDiagonal();
  if (refs) {
    *num_clusters =
        ClusterRobust(j, residuals, *refs, *clusters, problem, scale, eig, inv, reported, cov);
  }
  return true;
}

// The joint covariance `c` of the free blocks (fit tangent order) in the
// order and coordinates of ParameterLayout: T c T^T with T identity for the
// rotations (the layout's manifolds are the fit's) and the manifold's
// PlusJacobian for Euclidean blocks the fit held in part (SubsetManifold);
// held blocks, boards and points get no rows (the covariance is marginal
// over the boards and points).
Eigen::MatrixXd LayoutCovariance(ceres::Problem* problem, const std::vector<const double*>& free,
                                 const std::vector<int>& offsets, const Eigen::MatrixXd& c,
                                 InstrumentModel* model) {
  const std::vector<LayoutBlock> layout = ParameterLayout(*model);
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(LayoutSize(layout), c.rows());
  for (const LayoutBlock& lb : layout) {
    const double* p = lb.data(*model);
    for (size_t b = 0; b < free.size(); ++b) {
      if (free[b] != p) continue;
      const int ts = problem->ParameterBlockTangentSize(p);
      const ceres::Manifold* man = problem->GetManifold(const_cast<double*>(p));
      if (lb.tangent != LayoutTangent::kEuclidean || !man) {
        // Same coordinates in the fit and the layout.
        if (ts == lb.size) t.block(lb.offset, offsets[b], ts, ts).setIdentity();
      } else if (lb.ambient == lb.size) {
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jr(lb.size, ts);
        man->PlusJacobian(p, jr.data());
        t.block(lb.offset, offsets[b], lb.size, ts) = jr;
      }
    }
  }
  Eigen::MatrixXd out = t * c * t.transpose();
  // Exactly symmetric, so that a file round-trip and J P J^T keep it so.
  out = 0.5 * (out + out.transpose()).eval();
  return out;
}

void FillSigmas(ceres::Problem* problem, const NamedBlocks& blocks,
                const std::vector<ResidualRef>* refs,
                const std::vector<std::vector<int>>* clusters, InstrumentModel* model,
                FitSummary* summary, int num_threads) {
  std::vector<const double*> free_blocks;
  for (const auto& [p, name] : blocks) {
    if (!problem->IsParameterBlockConstant(const_cast<double*>(p))) free_blocks.push_back(p);
  }
  // Joint tangent-space covariance of all free blocks.
  std::vector<int> offsets;
  int n = 0;
  for (const double* p : free_blocks) {
    offsets.push_back(n);
    n += problem->ParameterBlockTangentSize(p);
  }
  model->sigmas.covariance.resize(0, 0);
  // The sandwich measures the scatter of the clusters' scores in the
  // directions several clusters share; a cluster's own parameters (a photo's
  // board pose in a camera-only session) have a zero score at the solution
  // and add no unknown to it. Its middle term has rank <= G - 1 there (the
  // scores sum to zero): where it cannot measure a direction, the widening
  // below keeps the independent-error covariance. Two clusters give one
  // number for every direction (their scores are opposite), too little to
  // widen anything by.
  if (refs && clusters) {
    std::set<int> distinct;
    for (const std::vector<int>& of_ref : *clusters) distinct.insert(of_ref.begin(), of_ref.end());
    if (distinct.size() < 3) {
      summary->message += " covariance: independent errors (" + std::to_string(distinct.size()) +
                          " cluster(s) cannot measure a scatter; fit.covariance_clusters not "
                          "applied);";
      refs = nullptr;
      clusters = nullptr;
    }
  }
  // The columns of the parameters the model reports (ParameterLayout; not
  // the boards, points and board warps, which are the session's own).
  std::vector<char> reported(n, 0);
  for (const LayoutBlock& lb : ParameterLayout(*model)) {
    const double* data = lb.data(*model);
    for (size_t k = 0; k < free_blocks.size(); ++k) {
      if (free_blocks[k] != data) continue;
      const int ts = problem->ParameterBlockTangentSize(free_blocks[k]);
      std::fill(reported.begin() + offsets[k], reported.begin() + offsets[k] + ts, 1);
    }
  }
  Eigen::MatrixXd c;
  int dropped = 0;
  if (!TangentCovariance(problem, free_blocks, n, num_threads, refs, clusters, reported, &c,
                         &dropped, &summary->covariance_clusters)) {
    summary->message += " covariance could not be computed;";
    return;
  }
  if (dropped > 0) {
    summary->message += " covariance: " + std::to_string(dropped) +
                        " parameter direction(s) not determined by the data (pseudo-inverse);";
  }

  // Parameter names in tangent order (for the correlation list).
  std::vector<std::string> names(n);
  for (size_t b = 0; b < free_blocks.size(); ++b) {
    const std::string& name = blocks.at(free_blocks[b]);
    const int ts = problem->ParameterBlockTangentSize(free_blocks[b]);
    for (int i = 0; i < ts; ++i) names[offsets[b] + i] = name + "[" + std::to_string(i) + "]";
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double d = std::sqrt(c(i, i) * c(j, j));
      if (d <= 0) continue;
      const double rho = c(i, j) / d;
      if (std::abs(rho) > 0.95)
        summary->strong_correlations.push_back({names[i] + " ~ " + names[j], rho});
    }
  }

  ModelSigmas& s = model->sigmas;
  s.valid = true;
  s.covariance = LayoutCovariance(problem, free_blocks, offsets, c, model);
  s.cam_tools.assign(model->NumZooms(), PoseSigma{});
  s.intrinsics.assign(model->NumZooms(), {});
  s.distortion.assign(model->NumZooms(), {});
  if (model->effects.Has(Effect::kFocus)) s.focus.assign(model->NumZooms(), {});
  auto block_cov = [&](const double* p, Eigen::MatrixXd* out) -> bool {
    for (size_t b = 0; b < free_blocks.size(); ++b) {
      if (free_blocks[b] != p) continue;
      const int ts = problem->ParameterBlockTangentSize(p);
      *out = c.block(offsets[b], offsets[b], ts, ts);
      return true;
    }
    return false;
  };
  // Ambient sigmas for Euclidean/subset blocks via the manifold's PlusJacobian.
  auto ambient_sigma = [&](double* p, int size, double* sigma) {
    Eigen::MatrixXd tc;
    if (!block_cov(p, &tc)) return;
    const ceres::Manifold* man = problem->GetManifold(p);
    Eigen::MatrixXd j = Eigen::MatrixXd::Identity(size, tc.rows());
    if (man) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jr(size, tc.rows());
      man->PlusJacobian(p, jr.data());
      j = jr;
    }
    const Eigen::MatrixXd ac = j * tc * j.transpose();
    for (int i = 0; i < size; ++i) sigma[i] = std::sqrt(std::max(ac(i, i), 0.0));
  };
  auto pose_sigma = [&](PoseBlock& pose, PoseSigma* out) {
    ambient_sigma(pose.t.data(), 3, out->t.data());
    Eigen::MatrixXd rc;
    if (!block_cov(pose.q.data(), &rc)) return;
    // Tangent-space sigmas (rotation about axes) and Euler sigmas by numeric
    // propagation through the manifold.
    const ceres::Manifold* man = problem->GetManifold(pose.q.data());
    const int ts = static_cast<int>(rc.rows());
    for (int i = 0; i < std::min(ts, 3); ++i) out->rotation[i] = std::sqrt(std::max(rc(i, i), 0.0));
    Eigen::MatrixXd je(3, ts);
    const Eigen::Vector3d e0 = pose.Euler();
    for (int k = 0; k < ts; ++k) {
      const double h = 1e-7;
      Eigen::VectorXd delta = Eigen::VectorXd::Zero(ts);
      delta[k] = h;
      PoseBlock moved = pose;
      man->Plus(pose.q.data(), delta.data(), moved.q.data());
      Eigen::Vector3d e1 = moved.Euler();
      for (int i = 0; i < 3; ++i) je(i, k) = WrapAngle(e1[i] - e0[i]) / h;
    }
    const Eigen::Matrix3d ec = je * rc * je.transpose();
    for (int i = 0; i < 3; ++i) out->euler[i] = std::sqrt(std::max(ec(i, i), 0.0));
  };
  pose_sigma(model->base, &s.base);
  pose_sigma(model->edm, &s.edm);
  for (int k = 0; k < 2; ++k) ambient_sigma(model->links[k].p.data(), 4, s.links[k].data());
  for (int z = 0; z < model->NumZooms(); ++z) {
    pose_sigma(model->cams[z].flange_from_cam, &s.cam_tools[z]);
    ambient_sigma(model->cams[z].intrinsics.data(), 4, s.intrinsics[z].data());
    ambient_sigma(model->cams[z].distortion.data(), kNumDistortion, s.distortion[z].data());
    if (!s.focus.empty()) ambient_sigma(model->cams[z].focus.data(), kNumFocus, s.focus[z].data());
  }
  for (EstimatedBoard& b : model->boards) pose_sigma(b.pose, &b.sigma);
  for (BoardWarp& w : model->board_warps) {
    Eigen::MatrixXd wc;
    w.cov = {0, 0, 0, 0};
    if (!block_cov(w.w.data(), &wc)) continue;
    const double c01 = 0.5 * (wc(0, 1) + wc(1, 0));
    w.cov = {wc(0, 0), c01, c01, wc(1, 1)};
  }
  for (EstimatedPoint& p : model->points) ambient_sigma(p.x.data(), 3, p.sigma.data());
  for (Effect e : model->effects.List()) {
    if (!IsKinematic(e)) continue;
    Eigen::MatrixXd ec;
    if (!block_cov(model->EffectValue(e).data(), &ec)) continue;
    auto& out = s.effect_cov[static_cast<int>(e)];
    // Ceres's block covariance is symmetric only to round-off; model.yaml
    // states one covariance, exactly symmetric.
    const double c01 = ec.rows() > 1 ? 0.5 * (ec(0, 1) + ec(1, 0)) : 0.0;
    out = {ec(0, 0), c01, c01, ec.rows() > 1 ? ec(1, 1) : 0.0};
  }
}

// Effects that the kinematics already contain are never fitted twice
// (ContainedInKinematics); they are removed from the model and named.
void RemoveEffectsTheKinematicsContain(InstrumentModel* m, FitSummary* summary) {
  for (Effect e : RemoveContainedEffects(m)) {
    summary->message +=
        std::string(" ") + Info(e).name + " is redundant with the dh model (not fitted);";
  }
}

// With a robust loss, each record its own group. A pointing's records
// share little (one EDM row, a camera row per zoom), and on a record of its
// own Ceres's LossFunction takes Triggs's corrected steps, which converge
// in fewer iterations than the rescaled residuals of ObservationLoss (the
// gross-error scenes, tests/calibrate/gross_errors_test.cc: 12 against 49).
// Photos stay whole: their corners share the chain's derivatives.
std::vector<ObservationGroup> RecordsApart(std::vector<ObservationGroup> groups) {
  std::vector<ObservationGroup> out;
  for (ObservationGroup& g : groups) {
    if (g.kind == ObsGroup::kPixel || g.indices.size() == 1) {
      out.push_back(std::move(g));
      continue;
    }
    for (int i : g.indices) {
      ObservationGroup one = g;
      one.indices = {i};
      out.push_back(std::move(one));
    }
  }
  return out;
}

// One residual block per observation group, each whitened by its group's
// current sigma, parameterised by `param`; fills `refs` for the variance
// components and the robust-loss report.
std::unique_ptr<ceres::Problem> BuildProblem(const Observations& obs,
                                             const std::vector<ObservationGroup>& groups,
                                             const Parameterization& param,
                                             const std::vector<double>& sigma,
                                             const FitOptions& options, bool with_bounds,
                                             InstrumentModel* m, std::vector<ResidualRef>* refs) {
  ceres::Problem::Options popt;
  popt.manifold_ownership = ceres::TAKE_OWNERSHIP;
  auto problem = std::make_unique<ceres::Problem>(popt);
  refs->clear();
  for (const ObservationGroup& g : groups) {
    const int slot = VarianceSlot(g.kind, g.zoom);
    std::vector<double*> blocks;
    ceres::CostFunction* cost = MakeGroupCost(obs, g, 1.0 / sigma[slot], param, m, &blocks);
    // A robust loss acts on each observation: Ceres's on a block of one,
    // ObservationLoss inside a block of many (a photo's corners).
    ceres::LossFunction* loss = nullptr;
    if (options.loss != RobustLoss::kNone && g.indices.size() == 1) {
      loss = options.loss == RobustLoss::kHuber
                 ? static_cast<ceres::LossFunction*>(new ceres::HuberLoss(options.loss_scale))
                 : new ceres::CauchyLoss(options.loss_scale);
    } else if (options.loss != RobustLoss::kNone) {
      cost = new ObservationLoss(cost, g.kind == ObsGroup::kPixel ? 2 : 3, options.loss,
                                 options.loss_scale);
    }
    refs->push_back({problem->AddResidualBlock(cost, loss, blocks), g.kind, g.indices, slot});
  }
  param.Apply(problem.get(), with_bounds);
  return problem;
}

ceres::Solver::Options SolverOptions(const ceres::Problem& problem, const FitOptions& options) {
  ceres::Solver::Options sopt;
  // Dense QR is the most accurate, but costs ~2 m n^2 per iteration (m
  // residuals, n parameters), which makes a session of many zooms and
  // photos unaffordable (joint_refine_benchmark's sessions).
  // The normal equations from the block-sparse Jacobian cost ~m k^2 (k ~ 40
  // parameters per residual block) and are well conditioned here thanks to
  // Ceres's Jacobi scaling; they take over for large problems.
  sopt.linear_solver_type =
      static_cast<double>(problem.NumResiduals()) * problem.NumParameters() > kDenseQrLimit
          ? ceres::SPARSE_NORMAL_CHOLESKY
          : ceres::DENSE_QR;
  sopt.max_num_iterations = options.max_iterations;
  sopt.num_threads = options.num_threads;
  // Tight enough that exact data are fitted to round-off (the 1e-9 m
  // held-out test), loose enough not to spin on round-off noise.
  sopt.function_tolerance = 1e-10;
  sopt.gradient_tolerance = 1e-14;
  sopt.parameter_tolerance = 1e-10;
  // The start (extraction) is close: begin near Gauss-Newton instead of
  // growing the trust region from Ceres's default 1e4 over many iterations
  // along the weakly determined directions (camera roll from 1-px rows).
  sopt.initial_trust_region_radius = 1e10;
  sopt.minimizer_progress_to_stdout = options.verbose;
  return sopt;
}

// Variance-component estimate per group: s0^2 = sum r^2 / redundancy. The
// redundancy of group g is its number of residuals n_g less the parameters
// only its residuals see (e.g. the points of unknown position for the
// records, the board poses and intrinsics for pixels-only data) and its
// share n_g / n of the parameters several groups see. Updates `sigma`;
// returns whether any sigma moved by more than kSigmaSettled (another round
// is needed).
bool ReestimateSigmas(ceres::Problem* problem, const std::vector<ResidualRef>& refs,
                      std::vector<double>* sigmas) {
  std::vector<double>& sigma = *sigmas;
  const int slots = static_cast<int>(sigma.size());
  std::vector<double> sum2(slots, 0.0), exclusive(slots, 0.0);
  std::vector<int> count(slots, 0);
  std::map<ceres::ResidualBlockId, int> group_of;
  std::vector<double> r;
  for (const ResidualRef& ref : refs) {
    if (EvaluateWithoutLoss(*problem, ref.id, &r)) {
      for (double x : r) sum2[ref.slot] += x * x;
    }
    count[ref.slot] +=
        (ref.group == ObsGroup::kPixel ? 2 : 3) * static_cast<int>(ref.indices.size());
    group_of[ref.id] = ref.slot;
  }
  double shared = 0;
  std::vector<double*> blocks;
  problem->GetParameterBlocks(&blocks);
  for (double* b : blocks) {
    if (problem->IsParameterBlockConstant(b)) continue;
    std::vector<ceres::ResidualBlockId> ids;
    problem->GetResidualBlocksForParameterBlock(b, &ids);
    std::set<int> groups;
    for (ceres::ResidualBlockId id : ids) groups.insert(group_of[id]);
    const int size = problem->ParameterBlockTangentSize(b);
    if (groups.size() == 1) {
      exclusive[*groups.begin()] += size;
    } else {
      shared += size;
    }
  }
  int n_obs = 0;
  for (int c : count) n_obs += c;
  bool changed = false;
  for (int g = 0; g < slots; ++g) {
    if (count[g] == 0) continue;
    const double params = exclusive[g] + shared * count[g] / std::max(n_obs, 1);
    const double redundancy = std::max(0.05 * count[g], count[g] - params);
    const double f = std::sqrt(sum2[g] / redundancy);
    // Never shrink below a floor that would make exact data ill-posed.
    const double floor = g >= kPixelSlots ? 1e-9 : 1e-15;
    const double next = std::max(sigma[g] * f, floor);
    if (std::abs(next / sigma[g] - 1.0) > kSigmaSettled) changed = true;
    sigma[g] = next;
  }
  return changed;
}

// Robust loss: the observations whose whitened residual exceeds the loss
// scale (reported as down-weighted, file:line of the row).
std::vector<std::string> Downweighted(const ceres::Problem& problem,
                                      const std::vector<ResidualRef>& refs,
                                      const Observations& obs, const FitOptions& options) {
  std::vector<std::string> out;
  std::vector<double> r;
  for (const ResidualRef& ref : refs) {
    if (!EvaluateWithoutLoss(problem, ref.id, &r)) continue;
    const int dim = ref.group == ObsGroup::kPixel ? 2 : 3;
    for (size_t k = 0; k < ref.indices.size(); ++k) {
      double s = 0;
      for (int c = 0; c < dim; ++c) s += r[dim * k + c] * r[dim * k + c];
      if (std::sqrt(s) <= options.loss_scale) continue;
      out.push_back(ref.group == ObsGroup::kPixel
                        ? obs.pixels_source + ":" + std::to_string(obs.pixels[ref.indices[k]].line)
                        : obs.records_source + ":" +
                              std::to_string(obs.records[ref.indices[k]].line));
    }
  }
  return out;
}

// The solver's outcome and the final sigmas, into the summary.
void Summarize(const ceres::Solver::Summary& solver_summary, const ceres::Problem& problem,
               const std::vector<double>& sigma, const std::vector<ResidualRef>& refs,
               const FitOptions& options, FitSummary* summary) {
  summary->converged = solver_summary.termination_type == ceres::CONVERGENCE ||
                       solver_summary.termination_type == ceres::USER_SUCCESS;
  summary->iterations = static_cast<int>(solver_summary.iterations.size());
  summary->final_cost = solver_summary.final_cost;
  summary->num_residuals = problem.NumResiduals();
  summary->num_parameters = problem.NumParameters();
  summary->sigma_edm_m = sigma[0];
  summary->sigma_cam_m = sigma[1];
  // Pixels: per zoom, and pooled (the root mean square over the pixels).
  std::vector<int> count(sigma.size(), 0);
  for (const ResidualRef& ref : refs) count[ref.slot] += static_cast<int>(ref.indices.size());
  summary->sigma_pixel_px_zoom.assign(sigma.size() - kPixelSlots, 0.0);
  double sum2 = 0;
  int n = 0;
  for (size_t g = kPixelSlots; g < sigma.size(); ++g) {
    if (count[g] == 0) continue;
    summary->sigma_pixel_px_zoom[g - kPixelSlots] = sigma[g];
    sum2 += count[g] * sigma[g] * sigma[g];
    n += count[g];
  }
  summary->sigma_pixel_px = n > 0 ? std::sqrt(sum2 / n) : options.sigma_pixel_px;
  summary->sigma0_records = sigma[0] / options.sigma_edm_m;
  summary->sigma0_pixels = summary->sigma_pixel_px / options.sigma_pixel_px;
  summary->message += " " + solver_summary.message;
}

// The free blocks present in `problem`, named, for the covariance.
NamedBlocks FreeBlocks(const Parameterization& param, const ceres::Problem& problem) {
  NamedBlocks out;
  for (const BlockDecision& d : param.Blocks()) {
    if (d.kind != BlockKind::kConstant && problem.HasParameterBlock(d.block)) out[d.block] = d.name;
  }
  return out;
}

}  // namespace

FitSummary Refine(const Observations& obs, const FitOptions& options, InstrumentModel* model,
                  const FitSummary* earlier) {
  const std::string msg = options.Check();
  if (!msg.empty()) throw std::invalid_argument(msg);
  const auto t0 = std::chrono::steady_clock::now();
  FitSummary summary;
  InstrumentModel& m = *model;
  RemoveEffectsTheKinematicsContain(&m, &summary);

  const UsedRows rows = SelectRows(obs, options, m.NumZooms(), UnknownZoom::kThrow);
  summary.excluded_critical = rows.excluded_critical;
  if (rows.records.empty() && rows.pixels.empty()) {
    // Name the files and what became of their rows (SelectRows: the
    // critical region, zoom levels without a camera).
    std::ostringstream what;
    what << "nothing to fit: " << obs.records_source << " gave " << obs.records.size()
         << " rows and " << obs.pixels_source << " " << obs.pixels.size() << " rows";
    if (obs.records.empty() && obs.pixels.empty()) {
      what << " (give data.records, data.pixels or data.shots rows)";
    } else if (rows.excluded_critical > 0) {
      what << "; " << rows.excluded_critical << " of them lie in the critical region (zenith "
           << "angle outside fit.critical_region's " << options.critical_region.min_zenith_rad * 180 / M_PI
           << " to " << options.critical_region.max_zenith_rad * 180 / M_PI << " deg)";
    }
    throw std::invalid_argument(what.str());
  }
  const std::vector<ObservationGroup> groups =
      options.loss == RobustLoss::kNone ? GroupObservations(obs, rows)
                                        : RecordsApart(GroupObservations(obs, rows));

  // The variance components start a priori, or at an earlier fit's estimate:
  // the fixed-point iteration below moves each group's sigma by the share of
  // the misfit its weight leaves it, which from a start far off can take more
  // rounds than kSigmaRounds (the demo's photo session, report.json: the
  // full set, started at the reduced set's sigmas, fit.sigma_rounds 3 and
  // settled; the reduced set from the a-priori sigmas, reduced_fit, 4 and
  // still moving).
  std::vector<double> start_sigma = AprioriSigmas(options, m.NumZooms());
  if (earlier != nullptr && options.reestimate_sigmas)
    start_sigma = StartSigmas(*earlier, start_sigma);
  std::vector<double> sigma = start_sigma;
  constexpr int kSigmaRounds = 4;
  const int rounds = options.reestimate_sigmas ? kSigmaRounds : 1;
  ceres::Solver::Summary solver_summary;
  std::vector<ResidualRef> refs;
  std::unique_ptr<ceres::Problem> problem;
  // SPEC 7: boards and points of unknown position get starting values, and
  // what the data cannot determine is held (DataFacts).
  const DataFacts facts = FactsOf(obs, rows);
  for (const std::string& note : StartUnknowns(obs, rows, facts, &m)) {
    summary.message += " " + note + ";";
  }
  const InstrumentModel start = m;
  const Parameterization param(&m, options, facts);
  summary.fixed_gauges = param.FixedGauges();
  // Klug Eq. 98's translation bounds: Ceres's projected steps stall on this
  // problem even when no bound is active, so the bounds are imposed as hard
  // constraints only when an unconstrained solution leaves its window (then
  // the refinement is repeated from the start with the bounds on).
  bool with_bounds = false;
  for (int round = 0; round < rounds; ++round) {
    // Each round warm-starts from the previous one; bounds stay around `start`.
    problem = BuildProblem(obs, groups, param, sigma, options, with_bounds, &m, &refs);
    ceres::Solve(SolverOptions(*problem, options), problem.get(), &solver_summary);
    if (round == 0) summary.initial_cost = solver_summary.initial_cost;
    if (!with_bounds) {
      const std::vector<std::string> outside = param.OutsideBounds();
      if (!outside.empty()) {
        std::string names;
        for (const std::string& n : outside) names += (names.empty() ? "" : ", ") + n;
        summary.message += " Eq. 98 bounds (" + std::to_string(options.translation_bound_m) +
                           " m around the start) imposed: " + names + " left its window;";
        with_bounds = true;
        m = start;
        sigma = start_sigma;
        round = -1;  // start over, bounded
        continue;
      }
    }
    if (!options.reestimate_sigmas) break;
    summary.sigma_rounds = round + 1;
    if (!ReestimateSigmas(problem.get(), refs, &sigma)) {
      summary.sigmas_converged = true;
      break;
    }
  }

  Summarize(solver_summary, *problem, sigma, refs, options, &summary);
  if (options.loss != RobustLoss::kNone) {
    summary.downweighted = Downweighted(*problem, refs, obs, options);
  }
  if (options.compute_covariance) {
    const bool clustered = options.covariance_clusters != CovarianceClusters::kNone;
    std::vector<std::vector<int>> clusters;
    if (clustered) clusters = AssignClusters(obs, refs, options.covariance_clusters);
    FillSigmas(problem.get(), FreeBlocks(param, *problem), clustered ? &refs : nullptr,
               &clusters, &m, &summary, options.num_threads);
  }
  for (EstimatedBoard& b : m.boards) b.board.ref_from_board = b.pose.ToRigid();
  SyncBoardWarps(&m);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

int RobustSearchIterations(const Observations& obs) { return obs.pixels.empty() ? 8 : 50; }

}  // namespace rtscalib
