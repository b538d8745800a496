#include "detect/tag_pattern_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace rtscalib::detect {
namespace {

// Parameters: h0..h7 of H (h8 = 1), ink, paper, log(optics blur) (BlurOf).
constexpr int kParams = 11;
using Vec = Eigen::Matrix<double, kParams, 1>;
using Mat = Eigen::Matrix<double, kParams, kParams>;

// Code images are at most 11 bits wide (tagCircle49h12); arrays below hold
// one entry per bit boundary.
constexpr int kMaxWidth = 16;

// The homography (h(2,2) = 1) that maps src[k] to dst[k], k = 0..3.
bool HomographyFrom4(const std::array<Eigen::Vector2d, 4>& src,
                     const std::array<Eigen::Vector2d, 4>& dst, Eigen::Matrix3d* h) {
  Eigen::Matrix<double, 8, 8> a;
  Eigen::Matrix<double, 8, 1> b;
  for (int k = 0; k < 4; ++k) {
    const double x = src[k].x(), y = src[k].y(), u = dst[k].x(), v = dst[k].y();
    a.row(2 * k) << x, y, 1, 0, 0, 0, -u * x, -u * y;
    a.row(2 * k + 1) << 0, 0, 0, x, y, 1, -v * x, -v * y;
    b(2 * k) = u;
    b(2 * k + 1) = v;
  }
  const Eigen::FullPivLU<Eigen::Matrix<double, 8, 8>> lu(a);
  if (!lu.isInvertible()) return false;
  const Eigen::Matrix<double, 8, 1> x = lu.solve(b);
  *h << x(0), x(1), x(2), x(3), x(4), x(5), x(6), x(7), 1.0;
  return h->allFinite();
}

// The standard normal CDF and density, tabulated on [-kTableRange,
// kTableRange] in steps of 1/kTableScale and interpolated linearly: the error
// of Phi is below h^2/8 max|phi'| = 2e-6 (h = 1/128), a thousandth of a grey
// level at any contrast, at a tenth of the cost of erfc and exp per call.
constexpr double kTableRange = 6.0;
constexpr int kTableScale = 128;
constexpr int kTableSize = static_cast<int>(2 * kTableRange * kTableScale) + 2;

struct NormalTable {
  double cdf[kTableSize], pdf[kTableSize];
  NormalTable() {
    for (int i = 0; i < kTableSize; ++i) {
      const double u = -kTableRange + static_cast<double>(i) / kTableScale;
      cdf[i] = 0.5 * std::erfc(-u * M_SQRT1_2);
      pdf[i] = 0.5 * M_2_SQRTPI * M_SQRT1_2 * std::exp(-0.5 * u * u);
    }
  }
  // Phi(u) and phi(u).
  void At(double u, double* phi_cdf, double* phi_pdf) const {
    if (u <= -kTableRange) {
      *phi_cdf = *phi_pdf = 0;
      return;
    }
    if (u >= kTableRange) {
      *phi_cdf = 1;
      *phi_pdf = 0;
      return;
    }
    const double x = (u + kTableRange) * kTableScale;
    const int i = static_cast<int>(x);
    const double f = x - i;
    *phi_cdf = cdf[i] + f * (cdf[i + 1] - cdf[i]);
    *phi_pdf = pdf[i] + f * (pdf[i + 1] - pdf[i]);
  }
};

const NormalTable& Normal() {
  static const NormalTable table;
  return table;
}

// The blurred profile of one axis: for the bits c = lo..hi along it, the
// weight g_c = Phi((q - c)/s) - Phi((q - c - 1)/s) of bit c at coordinate q
// with blur s [bits], and its derivatives with respect to q and s.
struct AxisWeights {
  int lo = 0, hi = -1;
  double g[kMaxWidth], dg_dq[kMaxWidth], dg_ds[kMaxWidth];

  void Set(double q, double s, int width) {
    // Bits further than 5 s from q weigh < 3e-7.
    lo = std::max(0, static_cast<int>(std::floor(q - 5 * s)));
    hi = std::min(width - 1, static_cast<int>(std::floor(q + 5 * s)));
    if (lo > hi) return;
    const NormalTable& normal = Normal();
    double cdf[kMaxWidth + 1], pdf_u[kMaxWidth + 1], pdf[kMaxWidth + 1];
    for (int b = lo; b <= hi + 1; ++b) {
      const double u = (q - b) / s;
      normal.At(u, &cdf[b - lo], &pdf[b - lo]);
      pdf_u[b - lo] = u * pdf[b - lo];
    }
    for (int c = lo; c <= hi; ++c) {
      const int k = c - lo;
      g[k] = cdf[k] - cdf[k + 1];
      dg_dq[k] = (pdf[k] - pdf[k + 1]) / s;
      dg_ds[k] = -(pdf_u[k] - pdf_u[k + 1]) / s;
    }
  }
};

// The model's Gaussian [px] for log(optics blur) `log_optics`: the pixel's
// own area, a 1 px box of variance 1/12 px^2, and the optics' Gaussian
// together, so that the fit can never make the pattern sharper than a pixel
// sees it (a model sampled at pixel centres with less blur than that turns
// the cost into steps in the geometry).
double BlurOf(double log_optics) {
  const double optics = std::exp(log_optics);
  return std::sqrt(1.0 / 12.0 + optics * optics);
}

struct Pixel {
  Eigen::Vector2d p;  // relative to the tag's centre [px]
  double value;
};

class PatternModel {
 public:
  PatternModel(const cv::Mat& code, const Eigen::Vector2d& code_centre)
      : width_(code.cols), centre_(code_centre), ink_(code.rows * code.cols) {
    for (int y = 0; y < code.rows; ++y) {
      for (int x = 0; x < code.cols; ++x) ink_[y * width_ + x] = code.at<uint8_t>(y, x) < 128;
    }
  }

  // The code-image point under image point p (relative to the tag centre)
  // for H = h (which maps centred code coordinates to centred pixels).
  static Eigen::Vector2d CodePoint(const Eigen::Matrix3d& h_inv, const Eigen::Vector2d& p) {
    return (h_inv * p.homogeneous()).hnormalized();
  }

  // Model value at pixel p; with `grad`, its derivatives with respect to the
  // parameters (H entries, ink, paper, log optics blur).
  double Value(const Vec& theta, const Eigen::Matrix3d& h, const Eigen::Matrix3d& h_inv,
               const Eigen::Vector2d& p, Vec* grad) const {
    const Eigen::Vector2d qc = CodePoint(h_inv, p);  // centred code coordinates
    const Eigen::Vector2d q = qc + centre_;
    // J = dp/dq at qc is M / d with M = [h00 - p_x h20, h01 - p_x h21;
    // h10 - p_y h20, h11 - p_y h21] (p fixed, no q in it) and d the
    // homogeneous scale; the rows of J^-1 = d M^-1 are the image gradients of
    // q_x and q_y, whose lengths scale the blur onto the tag's axes.
    const double d = h(2, 0) * qc.x() + h(2, 1) * qc.y() + 1.0;
    Eigen::Matrix2d m;
    m << h(0, 0) - p.x() * h(2, 0), h(0, 1) - p.x() * h(2, 1), h(1, 0) - p.y() * h(2, 0),
        h(1, 1) - p.y() * h(2, 1);
    const Eigen::Matrix2d m_inv = m.inverse();
    const Eigen::Matrix2d j_inv = d * m_inv;
    const double optics = std::exp(theta(10));
    const double blur = BlurOf(theta(10));
    const double n0 = m_inv.row(0).norm(), n1 = m_inv.row(1).norm();
    const double sx = blur * d * n0, sy = blur * d * n1;
    AxisWeights wx, wy;
    wx.Set(q.x(), sx, width_);
    wy.Set(q.y(), sy, width_);
    double ink = 0, d_qx = 0, d_qy = 0, d_sx = 0, d_sy = 0;
    for (int cy = wy.lo; cy <= wy.hi; ++cy) {
      const int ky = cy - wy.lo;
      double row = 0, row_dq = 0, row_ds = 0;
      for (int cx = wx.lo; cx <= wx.hi; ++cx) {
        if (!ink_[cy * width_ + cx]) continue;
        const int kx = cx - wx.lo;
        row += wx.g[kx];
        row_dq += wx.dg_dq[kx];
        row_ds += wx.dg_ds[kx];
      }
      ink += row * wy.g[ky];
      d_qx += row_dq * wy.g[ky];
      d_sx += row_ds * wy.g[ky];
      d_qy += row * wy.dg_dq[ky];
      d_sy += row * wy.dg_ds[ky];
    }
    const double w = 1.0 - ink;  // paper fraction
    const double lo = theta(8), hi = theta(9);
    if (grad != nullptr) {
      const double contrast = hi - lo;
      // dp/dh at fixed q (p = (h0 qx + h1 qy + h2, h3 qx + h4 qy + h5) / d).
      Eigen::Matrix<double, 2, 8> dp_dh;
      dp_dh << qc.x() / d, qc.y() / d, 1 / d, 0, 0, 0, -p.x() * qc.x() / d, -p.x() * qc.y() / d,
          0, 0, 0, qc.x() / d, qc.y() / d, 1 / d, -p.y() * qc.x() / d, -p.y() * qc.y() / d;
      // p fixed: J dq + dp/dh dh = 0.
      const Eigen::Matrix<double, 2, 8> dq_dh = -j_inv * dp_dh;
      // The blurs move with H too: sx = blur d |row 0 of M^-1|, with
      // d(M^-1) = -M^-1 dM M^-1 and dd = q_x dh20 + q_y dh21 + h20 dq_x + h21 dq_y.
      Eigen::Matrix<double, 1, 8> dd_dh = h(2, 0) * dq_dh.row(0) + h(2, 1) * dq_dh.row(1);
      dd_dh(6) += qc.x();
      dd_dh(7) += qc.y();
      // dn_i = a_i . d(a_i) / n_i with a_i = row i of A = M^-1, d(A) = -A dM A,
      // and G = A A^T: an entry (r, c) of M moved by 1 (h0, h1, h3, h4) gives
      // dn_i = -A(i, r) G(i, c) / n_i; h20 and h21 move column c = 0, 1 of M
      // by -p, giving dn_i = (A(i, :) p) G(i, c) / n_i.
      const Eigen::Matrix2d gram = m_inv * m_inv.transpose();
      const double ap0 = m_inv.row(0).dot(p), ap1 = m_inv.row(1).dot(p);
      Eigen::Matrix<double, 1, 8> dn0_dh, dn1_dh;
      dn0_dh << -m_inv(0, 0) * gram(0, 0), -m_inv(0, 0) * gram(0, 1), 0,
          -m_inv(0, 1) * gram(0, 0), -m_inv(0, 1) * gram(0, 1), 0, ap0 * gram(0, 0),
          ap0 * gram(0, 1);
      dn1_dh << -m_inv(1, 0) * gram(1, 0), -m_inv(1, 0) * gram(1, 1), 0,
          -m_inv(1, 1) * gram(1, 0), -m_inv(1, 1) * gram(1, 1), 0, ap1 * gram(1, 0),
          ap1 * gram(1, 1);
      dn0_dh /= n0;
      dn1_dh /= n1;
      const Eigen::Matrix<double, 1, 8> dsx_dh = blur * (dd_dh * n0 + d * dn0_dh);
      const Eigen::Matrix<double, 1, 8> dsy_dh = blur * (dd_dh * n1 + d * dn1_dh);
      // W = 1 - ink: its derivatives are minus those of the ink sum.
      const Eigen::RowVector2d dw_dq(-d_qx, -d_qy);
      grad->head<8>() =
          contrast * (dw_dq * dq_dh - d_sx * dsx_dh - d_sy * dsy_dh).transpose();
      (*grad)(8) = 1.0 - w;
      (*grad)(9) = w;
      // d(sx)/d(log optics) = sx / blur * optics^2 / blur.
      const double dblur = optics * optics / (blur * blur);
      (*grad)(10) = contrast * (-d_sx * sx - d_sy * sy) * dblur;
    }
    return lo + (hi - lo) * w;
  }

 private:
  int width_;
  Eigen::Vector2d centre_;
  std::vector<char> ink_;
};

Eigen::Matrix3d HomographyOf(const Vec& theta) {
  Eigen::Matrix3d h;
  h << theta(0), theta(1), theta(2), theta(3), theta(4), theta(5), theta(6), theta(7), 1.0;
  return h;
}

}  // namespace

std::string PatternFitOptions::Check() const {
  if (max_iterations < 1) return "max_iterations: expected >= 1";
  if (!(tolerance_px > 0)) return "tolerance_px: expected > 0";
  if (!(max_residual_fraction > 0)) return "max_residual_fraction: expected > 0";
  if (!(min_contrast >= 0)) return "min_contrast: expected >= 0";
  return "";
}

PatternFitResult FitTagPattern(const cv::Mat& gray, const cv::Mat& code, int border_offset,
                               int width_at_border, const std::array<Eigen::Vector2d, 4>& corners,
                               const PatternFitOptions& options) {
  PatternFitResult result;
  result.corners = corners;
  const int width = code.cols;
  if (gray.type() != CV_8UC1 || code.type() != CV_8UC1 || code.rows != width ||
      width > kMaxWidth || width < 3) {
    return result;
  }
  // Quad corners in code-image coordinates, TargetCorner order (y down).
  const double b0 = border_offset, b1 = border_offset + width_at_border;
  const std::array<Eigen::Vector2d, 4> quad = {Eigen::Vector2d(b0, b1), Eigen::Vector2d(b1, b1),
                                               Eigen::Vector2d(b1, b0), Eigen::Vector2d(b0, b0)};
  // Centred coordinates on both sides keep the homography well conditioned.
  const Eigen::Vector2d code_centre(0.5 * width, 0.5 * width);
  const Eigen::Vector2d image_centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
  std::array<Eigen::Vector2d, 4> src, dst;
  for (int k = 0; k < 4; ++k) {
    src[k] = quad[k] - code_centre;
    dst[k] = corners[k] - image_centre;
  }
  Eigen::Matrix3d h;
  if (!HomographyFrom4(src, dst, &h)) return result;

  // The fitted pixels: centres at least half a bit inside the code image.
  const double margin = 0.5, half = 0.5 * width - margin;
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const double sx : {-half, half}) {
    for (const double sy : {-half, half}) {
      const Eigen::Vector2d p = (h * Eigen::Vector3d(sx, sy, 1)).hnormalized() + image_centre;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  // Of the code image, whatever the image shows is used (the quiet zone of a
  // tag at the image's edge may be cut).
  const int x0 = std::max(0, static_cast<int>(std::floor(lo.x())));
  const int x1 = std::min(gray.cols - 1, static_cast<int>(std::ceil(hi.x())));
  const int y0 = std::max(0, static_cast<int>(std::floor(lo.y())));
  const int y1 = std::min(gray.rows - 1, static_cast<int>(std::ceil(hi.y())));
  const Eigen::Matrix3d h_inv0 = h.inverse();
  // Whether code point q (centred) lies within half a bit of an unknown bit.
  bool any_unknown = false;
  for (int y = 0; y < width; ++y) {
    for (int x = 0; x < width; ++x) any_unknown |= code.at<uint8_t>(y, x) == kUnknownCodeBit;
  }
  auto near_unknown = [&](const Eigen::Vector2d& qc) {
    const Eigen::Vector2d q = qc + code_centre;
    for (const double dy : {-0.5, 0.5}) {
      for (const double dx : {-0.5, 0.5}) {
        const int bx = static_cast<int>(std::floor(q.x() + dx));
        const int by = static_cast<int>(std::floor(q.y() + dy));
        if (bx >= 0 && by >= 0 && bx < width && by < width &&
            code.at<uint8_t>(by, bx) == kUnknownCodeBit) {
          return true;
        }
      }
    }
    return false;
  };
  std::vector<Pixel> pixels;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const Eigen::Vector2d p = Eigen::Vector2d(x, y) - image_centre;
      const Eigen::Vector2d q = PatternModel::CodePoint(h_inv0, p);
      if (std::abs(q.x()) > half || std::abs(q.y()) > half) continue;
      if (any_unknown && near_unknown(q)) continue;
      pixels.push_back({p, static_cast<double>(gray.at<uint8_t>(y, x))});
    }
  }
  result.pixels = static_cast<int>(pixels.size());
  if (pixels.size() < 2 * kParams) return result;

  const PatternModel model(code, code_centre);
  Vec theta;
  theta << h(0, 0), h(0, 1), h(0, 2), h(1, 0), h(1, 1), h(1, 2), h(2, 0), h(2, 1), 0, 255,
      // A generous start blur smooths the cost while the start corners are
      // still ~0.3 px off; the fit sharpens it.
      std::log(0.8);
  // Start levels: least squares of the values on the start's paper fraction.
  {
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    for (const Pixel& px : pixels) {
      const double w = model.Value(theta, h, h_inv0, px.p, nullptr) / 255.0;
      const Eigen::Vector2d row(1 - w, w);
      a += row * row.transpose();
      rhs += row * px.value;
    }
    const Eigen::Vector2d levels = a.ldlt().solve(rhs);
    if (!levels.allFinite()) return result;
    theta(8) = levels(0);
    theta(9) = levels(1);
  }

  // One pass over the pixels: the cost and the normal equations at t.
  struct NormalEquations {
    Mat jtj = Mat::Zero();
    Vec jtr = Vec::Zero();
    double cost = 0;
  };
  auto evaluate = [&](const Vec& t, NormalEquations* n) {
    const Eigen::Matrix3d ht = HomographyOf(t);
    const Eigen::Matrix3d ht_inv = ht.inverse();
    *n = NormalEquations();
    for (const Pixel& px : pixels) {
      Vec g;
      const double m = model.Value(t, ht, ht_inv, px.p, &g);
      // A pixel at the sensor's clip level (an overexposed paper, a black
      // crushed to 0) says only that the scene was at least (at most) that
      // bright: where the model goes beyond the clip, it has no residual.
      if ((px.value >= 255 && m >= 255) || (px.value <= 0 && m <= 0)) continue;
      const double r = px.value - m;
      n->jtj.selfadjointView<Eigen::Upper>().rankUpdate(g);
      n->jtr += r * g;
      n->cost += r * r;
    }
    n->jtj.triangularView<Eigen::StrictlyLower>() = n->jtj.transpose();
  };
  auto corners_of = [&](const Vec& t) {
    const Eigen::Matrix3d ht = HomographyOf(t);
    std::array<Eigen::Vector2d, 4> c;
    for (int k = 0; k < 4; ++k) c[k] = (ht * src[k].homogeneous()).hnormalized() + image_centre;
    return c;
  };

  // Levenberg-Marquardt: a step is taken when it lowers the cost, else the
  // damping grows and the step is tried again from the same normal equations.
  double lambda = 1e-3;
  NormalEquations current;
  evaluate(theta, &current);
  bool converged = false;
  int iteration = 0;
  int rejected = 0;
  while (iteration < options.max_iterations && !converged) {
    // Marquardt's scaling by the diagonal, floored as Ceres does
    // (min_lm_diagonal), so that a parameter the data barely see (the optics
    // blur of a sharp image, its derivative vanishing as it goes to 0) still
    // takes bounded steps.
    Mat a = current.jtj;
    a.diagonal() += lambda * current.jtj.diagonal().cwiseMax(1e-6);
    const Vec step = a.ldlt().solve(current.jtr);
    if (!step.allFinite()) break;
    const Vec next = theta + step;
    NormalEquations trial;
    evaluate(next, &trial);
    if (trial.cost <= current.cost) {
      const std::array<Eigen::Vector2d, 4> before = corners_of(theta), after = corners_of(next);
      double moved = 0;
      for (int k = 0; k < 4; ++k) moved = std::max(moved, (after[k] - before[k]).norm());
      // Converged when the corners stand still or the cost does: a relative
      // decrease below 1e-6 is far below what the noise lets one tell apart.
      converged = moved < options.tolerance_px || current.cost - trial.cost < 1e-6 * current.cost;
      theta = next;
      current = trial;
      lambda = std::max(1e-9, lambda / 10);
      rejected = 0;
      ++iteration;
    } else {
      lambda *= 10;
      // Ten damped steps in a row that all raise the cost: the minimum is
      // reached within rounding.
      if (++rejected == 10) converged = true;
    }
  }
  const double cost = current.cost;
  result.iterations = iteration;
  result.ink = theta(8);
  result.paper = theta(9);
  result.blur_px = BlurOf(theta(10));
  result.residual_rms = std::sqrt(cost / pixels.size());
  const double contrast = result.paper - result.ink;
  if (!converged || !theta.allFinite() || contrast < options.min_contrast ||
      result.residual_rms > options.max_residual_fraction * contrast) {
    return result;
  }
  // The fitted corners must lie within the span of the pixel centres: the
  // fit extrapolates the pattern (well: over a homography) into a quiet zone
  // the image cuts off, but a corner beyond the image is no observation.
  const std::array<Eigen::Vector2d, 4> fitted = corners_of(theta);
  for (const Eigen::Vector2d& c : fitted) {
    if (!(c.x() >= 0 && c.y() >= 0 && c.x() <= gray.cols - 1 && c.y() <= gray.rows - 1)) {
      return result;
    }
  }
  result.corners = fitted;
  result.converged = true;
  return result;
}

}  // namespace rtscalib::detect
