#include "render/scene_renderer.h"

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkMatrix4x4.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTexture.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <list>
#include <random>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "libcalib/camera/opencv_model.h"

namespace rtscalib::render {
namespace {

template <typename T>
using Ptr = vtkSmartPointer<T>;

bool HasDistortion(const CameraTool& cam) {
  for (double d : cam.distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

// The ideal (undistorted) image the distortion map samples from: the
// intrinsics fx, fy with the principal point shifted so that canvas pixel
// (0, 0) is ideal pixel (u0, v0).
struct Canvas {
  int width = 0, height = 0;
  double u0 = 0, v0 = 0;
};

struct DistortionMap {
  std::array<double, kNumIntrinsics> intrinsics{};
  std::array<double, kNumDistortion> distortion{};
  int width = 0, height = 0;
  bool identity = true;
  int supersample = 1;
  Canvas canvas;  // in supersampled pixels (Supersampled(cam, supersample))
  // CV_32FC1, output pixel -> supersampled canvas pixel of its ideal point
  // (-10: none, its back-projection failed or lies beyond the canvas cap).
  cv::Mat map_x, map_y;

  // Built by solving the distortion (BuildDistortionMap), not derived from
  // another map (DeriveDistortionMap): only such maps are derived from, so
  // that interpolation errors do not add up over a refocusing session.
  bool solved = true;

  // The same lens: distortion, image size and supersampling, any intrinsics.
  bool SameLens(const CameraTool& cam, int k) const {
    return cam.distortion == distortion && cam.width == width && cam.height == height &&
           k == supersample;
  }
  bool Matches(const CameraTool& cam, int k) const {
    return cam.intrinsics == intrinsics && SameLens(cam, k);
  }
};

// The camera of the supersampled image: k x k pixels for every pixel of
// `cam`, over the same field (u_k + 1/2 = k (u + 1/2), docs/rendering.md).
CameraTool Supersampled(const CameraTool& cam, int k) {
  CameraTool fine = cam;
  fine.width = cam.width * k;
  fine.height = cam.height * k;
  fine.intrinsics[0] = k * cam.intrinsics[0];
  fine.intrinsics[1] = k * cam.intrinsics[1];
  fine.intrinsics[2] = k * (cam.intrinsics[2] + 0.5) - 0.5;
  fine.intrinsics[3] = k * (cam.intrinsics[3] + 0.5) - 0.5;
  return fine;
}

DistortionMap EmptyMap(const CameraTool& cam, int supersample) {
  DistortionMap m;
  m.intrinsics = cam.intrinsics;
  m.distortion = cam.distortion;
  m.width = cam.width;
  m.height = cam.height;
  m.supersample = supersample;
  m.identity = !HasDistortion(cam);
  m.canvas = {cam.width, cam.height, 0, 0};
  return m;
}

// Ideal pixel of output pixel (u, v) of `cam`, solved; NaN where
// back-projection fails.
cv::Vec2d SolvedIdeal(const CameraTool& cam, double u, double v) {
  const double pixel[2] = {u, v};
  double xn, yn;
  if (UndistortPixel(cam.intrinsics.data(), cam.distortion.data(), pixel, &xn, &yn) &&
      std::isfinite(xn) && std::isfinite(yn)) {
    return cv::Vec2d(cam.intrinsics[0] * xn + cam.intrinsics[2],
                     cam.intrinsics[1] * yn + cam.intrinsics[3]);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return cv::Vec2d(nan, nan);
}

// Canvas and sampling maps of `m` from the ideal pixel of every output pixel
// (CV_64FC1 each, NaN: none).
void FinishMap(const cv::Mat& ideal_u, const cv::Mat& ideal_v, double max_canvas_factor,
               DistortionMap* map) {
  DistortionMap& m = *map;
  // Canvas: the bounding box of all ideal pixels, clipped to
  // max_canvas_factor times the image around the image itself, in
  // supersampled pixels (u_k = k (u + 1/2) - 1/2), plus 2 of them: the
  // supersamples lie up to 1/2 - 1/(2k) output pixels beyond the pixel
  // centres, and bilinear sampling needs one more.
  double umin = 0, umax = m.width - 1, vmin = 0, vmax = m.height - 1;
  const double lim_u0 = -(max_canvas_factor - 1) / 2 * m.width;
  const double lim_u1 = m.width - 1 - lim_u0;
  const double lim_v0 = -(max_canvas_factor - 1) / 2 * m.height;
  const double lim_v1 = m.height - 1 - lim_v0;
  for (int v = 0; v < m.height; ++v) {
    const double* iu_row = ideal_u.ptr<double>(v);
    const double* iv_row = ideal_v.ptr<double>(v);
    for (int u = 0; u < m.width; ++u) {
      const double iu = iu_row[u], iv = iv_row[u];
      if (!(iu >= lim_u0 && iu <= lim_u1 && iv >= lim_v0 && iv <= lim_v1)) continue;
      umin = std::min(umin, iu);
      umax = std::max(umax, iu);
      vmin = std::min(vmin, iv);
      vmax = std::max(vmax, iv);
    }
  }
  const int k = m.supersample;
  auto fine = [k](double x) { return k * (x + 0.5) - 0.5; };
  m.canvas.u0 = std::floor(fine(umin - 0.5)) - 2;
  m.canvas.v0 = std::floor(fine(vmin - 0.5)) - 2;
  m.canvas.width = static_cast<int>(std::ceil(fine(umax + 0.5)) + 2 - m.canvas.u0) + 1;
  m.canvas.height = static_cast<int>(std::ceil(fine(vmax + 0.5)) + 2 - m.canvas.v0) + 1;

  m.map_x.create(m.height, m.width, CV_32FC1);
  m.map_y.create(m.height, m.width, CV_32FC1);
  for (int v = 0; v < m.height; ++v) {
    const double* iu_row = ideal_u.ptr<double>(v);
    const double* iv_row = ideal_v.ptr<double>(v);
    float* mx = m.map_x.ptr<float>(v);
    float* my = m.map_y.ptr<float>(v);
    for (int u = 0; u < m.width; ++u) {
      const double iu = iu_row[u], iv = iv_row[u];
      const bool ok = iu >= lim_u0 && iu <= lim_u1 && iv >= lim_v0 && iv <= lim_v1;
      mx[u] = ok ? static_cast<float>(fine(iu) - m.canvas.u0) : -10.f;
      my[u] = ok ? static_cast<float>(fine(iv) - m.canvas.v0) : -10.f;
    }
  }
}

DistortionMap BuildDistortionMap(const CameraTool& cam, int supersample, double max_canvas_factor) {
  DistortionMap m = EmptyMap(cam, supersample);
  if (m.identity) return m;
  auto ideal = [&](double u, double v) { return SolvedIdeal(cam, u, v); };
  // Exact back-projection of every pixel is a Newton solve per pixel, far
  // more than a photo's render (render_benchmark's BM_Render). The map is
  // smooth, so it is solved on a grid of kStep pixels and interpolated
  // bilinearly; every cell is checked at its centre and solved pixel by pixel
  // when interpolation is off by more than kTolerance there (strong or
  // failing distortion near the rim).
  constexpr int kStep = 4;
  constexpr double kTolerance = 1e-3;  // px, far below the corner accuracy
  const int gw = (cam.width - 1 + kStep - 1) / kStep + 1,
            gh = (cam.height - 1 + kStep - 1) / kStep + 1;
  auto node_u = [&](int i) { return std::min(i * kStep, cam.width - 1); };
  auto node_v = [&](int j) { return std::min(j * kStep, cam.height - 1); };
  cv::Mat ideal_u(cam.height, cam.width, CV_64FC1), ideal_v(cam.height, cam.width, CV_64FC1);
  if (gw < 2 || gh < 2) {  // a single row or column of pixels: no cells
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const cv::Vec2d p = ideal(u, v);
        ideal_u.at<double>(v, u) = p[0];
        ideal_v.at<double>(v, u) = p[1];
      }
    }
  }
  cv::Mat grid(gh, gw, CV_64FC2);
  cv::parallel_for_(cv::Range(0, gh), [&](const cv::Range& rows) {
    for (int j = rows.start; j < rows.end; ++j) {
      for (int i = 0; i < gw; ++i) grid.at<cv::Vec2d>(j, i) = ideal(node_u(i), node_v(j));
    }
  });
  cv::parallel_for_(cv::Range(0, gh - 1), [&](const cv::Range& rows) {
    for (int j = rows.start; j < rows.end; ++j) {
      const int v0 = node_v(j), v1 = node_v(j + 1);
      for (int i = 0; i + 1 < gw; ++i) {
        const int u0 = node_u(i), u1 = node_u(i + 1);
        const cv::Vec2d a = grid.at<cv::Vec2d>(j, i), b = grid.at<cv::Vec2d>(j, i + 1);
        const cv::Vec2d d = grid.at<cv::Vec2d>(j + 1, i), e = grid.at<cv::Vec2d>(j + 1, i + 1);
        auto interp = [&](double u, double v) {
          const double s = (u - u0) / (u1 - u0), t = (v - v0) / (v1 - v0);
          return (1 - t) * ((1 - s) * a + s * b) + t * ((1 - s) * d + s * e);
        };
        const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
        const cv::Vec2d exact = ideal(um, vm);
        const bool smooth = cv::norm(interp(um, vm) - exact) <= kTolerance;  // false for NaNs
        // Each cell fills its pixels [u0, u1) x [v0, v1), the last ones up to the edge.
        const int u_end = i + 2 == gw ? u1 + 1 : u1, v_end = j + 2 == gh ? v1 + 1 : v1;
        for (int v = v0; v < v_end; ++v) {
          double* iu_row = ideal_u.ptr<double>(v);
          double* iv_row = ideal_v.ptr<double>(v);
          if (!smooth) {
            for (int u = u0; u < u_end; ++u) {
              const cv::Vec2d p = ideal(u, v);
              iu_row[u] = p[0];
              iv_row[u] = p[1];
            }
            continue;
          }
          // interp(u, v) per component, its row factors taken once per row.
          const double t = (v - v0) / static_cast<double>(v1 - v0);
          for (int c = 0; c < 2; ++c) {
            double* row = c == 0 ? iu_row : iv_row;
            const double ac = a[c], bc = b[c], dc = d[c], ec = e[c];
            for (int u = u0; u < u_end; ++u) {
              const double sc = (u - u0) / static_cast<double>(u1 - u0);
              row[u] = (1 - t) * ((1 - sc) * ac + sc * bc) + t * ((1 - sc) * dc + sc * ec);
            }
          }
        }
      }
    }
  });

  FinishMap(ideal_u, ideal_v, max_canvas_factor, &m);
  return m;
}

// The map of `cam` from `base`, the solved map (BuildDistortionMap) of the
// same lens with other intrinsics: a camera that refocuses (SPEC 4.1) changes
// fx, fy, cx, cy from photo to photo, not its distortion. With K the
// intrinsics and U the undistortion in normalised coordinates (tilt
// included), the ideal pixel of output pixel p is K U(K^-1 p), so
//   ideal(p) = K K_base^-1 ideal_base(K_base K^-1 p):
// the base's ideal pixels (read back from its float maps, ~1e-4 px) taken
// bilinearly at p's position in the base image (the ideal map is smooth:
// its bilinear error over one pixel is ~1e-5 px for the lenses here),
// scaled and shifted. Pixels whose four base samples are not all there (the
// image edge, failed back-projections, the canvas cap) are solved. Deriving
// the map is cheaper than solving it for every photo of a refocusing camera
// (render_benchmark --benchmark_filter=RenderRefocusing times a photo;
// docs/rendering.md). Checked against
// solved pixels every kCheckStep pixels: false (the caller solves the map)
// when one of them is off by more than kTolerance, or when only one of the
// two has an ideal pixel. Also false for a scale more than kMaxScaleChange
// away from the base's (two zooms that happen to share their distortion
// coefficients): most of the image would then lie outside the base image and
// be solved pixel by pixel, slower than BuildDistortionMap's grid.
bool DeriveDistortionMap(const DistortionMap& base, const CameraTool& cam, double max_canvas_factor,
                         DistortionMap* out) {
  constexpr double kTolerance = 1e-3;  // px, as BuildDistortionMap's cells
  constexpr int kCheckStep = 16;
  constexpr double kMaxScaleChange = 0.02;  // refocusing: ~0.1 % (rendered_focus_test.cc)
  if (std::abs(cam.intrinsics[0] / base.intrinsics[0] - 1) > kMaxScaleChange ||
      std::abs(cam.intrinsics[1] / base.intrinsics[1] - 1) > kMaxScaleChange) {
    return false;
  }
  DistortionMap m = EmptyMap(cam, base.supersample);
  const double k = base.supersample;
  // Base ideal pixel from its maps (the inverse of FinishMap's `fine`).
  const double off_u = base.canvas.u0 + 0.5, off_v = base.canvas.v0 + 0.5;
  const double bfx = base.intrinsics[0], bfy = base.intrinsics[1];
  const double bcx = base.intrinsics[2], bcy = base.intrinsics[3];
  const double fx = cam.intrinsics[0], fy = cam.intrinsics[1];
  const double cx = cam.intrinsics[2], cy = cam.intrinsics[3];
  const int w = cam.width, h = cam.height;
  // Both maps are affine per axis: the base position bu = pu + qu u, and the
  // ideal pixel iu = ru + su mx from the base's map value mx (likewise v).
  const double qu = bfx / fx, pu = bcx - qu * cx;
  const double qv = bfy / fy, pv = bcy - qv * cy;
  const double su = fx / (bfx * k), ru = cx + fx / bfx * (off_u / k - 0.5 - bcx);
  const double sv = fy / (bfy * k), rv = cy + fy / bfy * (off_v / k - 0.5 - bcy);
  cv::Mat ideal_u(h, w, CV_64FC1), ideal_v(h, w, CV_64FC1);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      double* iu_row = ideal_u.ptr<double>(v);
      double* iv_row = ideal_v.ptr<double>(v);
      const double bv = pv + qv * v;
      // Truncation is the floor for bv >= 0, and bv < 0 is solved anyway.
      const int v0 = bv >= 0 ? static_cast<int>(bv) : -1;
      const double tv = bv - v0;
      const bool row_ok = v0 >= 0 && v0 + 1 < h;
      const float* x0 = row_ok ? base.map_x.ptr<float>(v0) : nullptr;
      const float* x1 = row_ok ? base.map_x.ptr<float>(v0 + 1) : nullptr;
      const float* y0 = row_ok ? base.map_y.ptr<float>(v0) : nullptr;
      const float* y1 = row_ok ? base.map_y.ptr<float>(v0 + 1) : nullptr;
      for (int u = 0; u < w; ++u) {
        const double bu = pu + qu * u;
        const int u0 = bu >= 0 ? static_cast<int>(bu) : -1;
        if (row_ok && u0 >= 0 && u0 + 1 < w && x0[u0] > -5 && x0[u0 + 1] > -5 && x1[u0] > -5 &&
            x1[u0 + 1] > -5) {
          const double tu = bu - u0;
          const double mx = (1 - tv) * ((1 - tu) * x0[u0] + tu * x0[u0 + 1]) +
                            tv * ((1 - tu) * x1[u0] + tu * x1[u0 + 1]);
          const double my = (1 - tv) * ((1 - tu) * y0[u0] + tu * y0[u0 + 1]) +
                            tv * ((1 - tu) * y1[u0] + tu * y1[u0 + 1]);
          iu_row[u] = ru + su * mx;
          iv_row[u] = rv + sv * my;
        } else {
          const cv::Vec2d p = SolvedIdeal(cam, u, v);
          iu_row[u] = p[0];
          iv_row[u] = p[1];
        }
      }
    }
  });
  // The check: solved pixels every kCheckStep, the last row and column too.
  auto checked = [](int size) {
    std::vector<int> at;
    for (int i = 0; i < size; i += kCheckStep) at.push_back(i);
    if (at.back() != size - 1) at.push_back(size - 1);
    return at;
  };
  const std::vector<int> check_u = checked(w), check_v = checked(h);
  for (const int v : check_v) {
    for (const int u : check_u) {
      const cv::Vec2d p = SolvedIdeal(cam, u, v);
      const cv::Vec2d q(ideal_u.at<double>(v, u), ideal_v.at<double>(v, u));
      const bool neither = std::isnan(p[0]) && std::isnan(q[0]);
      if (!neither && !(cv::norm(p - q) <= kTolerance)) return false;  // NaN: false too
    }
  }
  m.solved = false;
  FinishMap(ideal_u, ideal_v, max_canvas_factor, &m);
  *out = std::move(m);
  return true;
}

// The distorted image: every output pixel is the mean of k x k samples of the
// supersampled ideal `canvas` (CV_32FC1), one per supersampled pixel of its
// area, at (u + (a + 1/2)/k - 1/2, v + (b + 1/2)/k - 1/2) for a, b = 0..k-1,
// each taken bilinearly at the ideal point of its position. Around the ideal
// point (map_x, map_y) of the pixel centre, those samples lie at offsets
// a - (k - 1)/2, b - (k - 1)/2 canvas pixels (up to the distortion's
// change of scale across one pixel, a few percent: second order, symmetric),
// and the mean of bilinear samples at such offsets is exactly one bilinear
// sample of the canvas box-filtered over k x k pixels (separably: the mean of
// two linear interpolations one pixel apart is the linear interpolation of
// the two-pixel means). So: a k x k box filter, then one bilinear sample per
// output pixel at the map's position (+1/2 for even k, where the box's centre
// lies between pixels), at the position as computed (a float, ~1e-4 px).
// cv::remap rounds positions to 1/32 px (INTER_BITS), an error that stays
// constant along an edge wherever the map's fractional part drifts slowly: it
// moved detected corners systematically by up to 0.008 px and fitted zoom 2's
// fx 27-43 ppm off on every seed. Box-averaging down to the output size first
// and sampling that (the interpolation then spans output pixels) makes each
// edge's profile depend on the map's sub-pixel phase, which drifts slowly
// over the image: gradient-based corner detectors (cv::cornerSubPix) then
// moved ChArUco and chessboard corners by up to 0.04 px with the position in
// the image. Pixels without an ideal point, and samples outside the canvas,
// take `background`.
// `box` is scratch space (reused between calls: no page faults per image).
void SampleDistorted(const cv::Mat& canvas, const cv::Mat& map_x, const cv::Mat& map_y, int k,
                     float background, cv::Mat* box_out, cv::Mat* out) {
  out->create(map_x.size(), CV_32FC1);
  cv::blur(canvas, *box_out, cv::Size(k, k), cv::Point(-1, -1), cv::BORDER_REPLICATE);
  const cv::Mat& box = *box_out;
  // cv::blur's anchor is pixel k/2 of the window: the box centred on pixel
  // i lies at i - 1/2 for even k.
  const float shift = k % 2 == 0 ? 0.5f : 0.0f;
  const int w = box.cols, h = box.rows;
  cv::parallel_for_(cv::Range(0, map_x.rows), [&](const cv::Range& rows) {
    auto at = [&](int x, int y) {
      return x >= 0 && y >= 0 && x < w && y < h ? box.at<float>(y, x) : background;
    };
    for (int v = rows.start; v < rows.end; ++v) {
      const float* mx = map_x.ptr<float>(v);
      const float* my = map_y.ptr<float>(v);
      float* dst = out->ptr<float>(v);
      for (int u = 0; u < map_x.cols; ++u) {
        const double x = mx[u] + shift, y = my[u] + shift;
        // No ideal point (map < -5), or a cell [x0, x0 + 1] x [y0, y0 + 1]
        // entirely outside the box image (x0 = floor(x) < -1 or >= w).
        if (mx[u] < -5 || !(x >= -1 && y >= -1 && x < w && y < h)) {
          dst[u] = background;
          continue;
        }
        // floor by truncation (x, y >= -1 here): no libm call per sample.
        int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
        if (x < x0) --x0;
        if (y < y0) --y0;
        const double a = x - x0, b = y - y0;
        float p00, p10, p01, p11;
        if (x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h) {  // all four inside
          const float* r0 = box.ptr<float>(y0) + x0;
          const float* r1 = box.ptr<float>(y0 + 1) + x0;
          p00 = r0[0];
          p10 = r0[1];
          p01 = r1[0];
          p11 = r1[1];
        } else {
          p00 = at(x0, y0);
          p10 = at(x0 + 1, y0);
          p01 = at(x0, y0 + 1);
          p11 = at(x0 + 1, y0 + 1);
        }
        dst[u] =
            static_cast<float>((1 - b) * ((1 - a) * p00 + a * p10) + b * ((1 - a) * p01 + a * p11));
      }
    }
  });
}

// splitmix64: decorrelates (seed, image_seed) pairs for the noise generator.
std::uint64_t Mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

struct BoardActors {
  Ptr<vtkActor> front, back;
  Rigid3 ref_from_board;
  std::array<Eigen::Vector3d, 4> outline;  // texture rectangle corners, board frame
};

}  // namespace

std::string RenderOptions::Check() const {
  if (supersample < 1 || supersample > 8) {
    return "supersample: expected 1..8, got " + std::to_string(supersample);
  }
  if (!(background >= 0 && background <= 255))
    return "background: expected a grey level in [0, 255]";
  if (ink >= paper) return "ink/paper: expected ink < paper";
  if (!(exposure > 0)) return "exposure: expected > 0";
  if (!(blur_sigma >= 0)) return "blur_sigma: expected >= 0";
  if (!(noise_sigma >= 0)) return "noise_sigma: expected >= 0";
  if (max_anisotropy < 1 || max_anisotropy > 16) {
    return "max_anisotropy: expected 1..16, got " + std::to_string(max_anisotropy);
  }
  if (!(max_canvas_factor >= 1)) return "max_canvas_factor: expected >= 1";
  if (const std::string t = texture.Check(); !t.empty()) return "texture." + t;
  return "";
}

Eigen::Matrix4d OpenGlProjection(double fx, double fy, double cx, double cy, int width, int height,
                                 double near_z, double far_z) {
  // View coordinates (x_v, y_v, z_v) = (x, -y, -z); clip w = -z_v = z.
  //   x_ndc = 2 (u + 1/2) / W - 1           (GL samples pixel centres at i + 1/2)
  //   y_ndc = 1 - 2 (v + 1/2) / H           (GL window rows count from the bottom)
  // with u = fx x/z + cx, v = fy y/z + cy give the first two rows.
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = 2.0 * fx / width;
  p(0, 2) = 1.0 - 2.0 * (cx + 0.5) / width;
  p(1, 1) = 2.0 * fy / height;
  p(1, 2) = 2.0 * (cy + 0.5) / height - 1.0;
  p(2, 2) = -(far_z + near_z) / (far_z - near_z);
  p(2, 3) = -2.0 * far_z * near_z / (far_z - near_z);
  p(3, 2) = -1.0;
  return p;
}

struct SceneRenderer::Impl {
  RenderOptions options;
  Ptr<vtkRenderWindow> window;
  Ptr<vtkRenderer> renderer;
  // Per scene; the selected one's are visible, and `boards` points to them.
  std::vector<std::vector<BoardActors>> scene_boards;
  const std::vector<BoardActors>* boards = nullptr;
  Ptr<vtkUnsignedCharArray> pixels;
  // Maps of the cameras seen last (one per zoom level, typically), most
  // recent first: a shot list alternating between zooms must not rebuild them.
  std::list<DistortionMap> maps;
  static constexpr size_t kMaxMaps = 8;
  MapCounts map_counts;
  cv::Mat canvas;     // CV_32FC1 ideal image (supersampled when distorted)
  cv::Mat box;        // CV_32FC1, the supersampled canvas box-filtered
  cv::Mat distorted;  // CV_32FC1
  cv::Mat red, red_flipped;  // CV_8UC1 scratch of RenderCanvas
  cv::Mat noise;             // CV_32FC1 sensor noise, drawn per photo into the same buffer

  // The window and renderer, and every scene's boards (the first selected).
  void Build(const std::vector<TargetScene>& scenes);
  // The actors of `scene`'s boards, added to the renderer.
  std::vector<BoardActors> BuildBoards(const TargetScene& scene, const TagTextureOptions& topt);
  void Select(int index);
  // Renders the ideal image of `cam`'s intrinsics on `canvas` (in `cam`'s
  // pixels) at `box` times its size and box-averages it back into `out`.
  void RenderCanvas(const Rigid3& ref_from_cam, const CameraTool& cam, const Canvas& canvas,
                    int box, cv::Mat* out);
};

void SceneRenderer::Impl::Build(const std::vector<TargetScene>& scenes) {
  window = Ptr<vtkRenderWindow>::New();
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->SetAlphaBitPlanes(0);
  // Read-back is from the render framebuffer (front = 0): no copy to the
  // display framebuffer at the end of every frame.
  window->SwapBuffersOff();
  window->SetSize(64, 64);
  renderer = Ptr<vtkRenderer>::New();
  const double bg = options.background / 255.0;
  renderer->SetBackground(bg, bg, bg);
  renderer->SetUseFXAA(false);
  renderer->SetAutomaticLightCreation(true);
  renderer->LightFollowCameraOn();
  window->AddRenderer(renderer);

  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(0, 0, 0);
  camera->SetFocalPoint(0, 0, -1);
  camera->SetViewUp(0, 1, 0);
  camera->UseExplicitProjectionTransformMatrixOn();

  TagTextureOptions topt = options.texture;
  topt.black = options.ink;
  topt.white = options.paper;
  for (const TargetScene& scene : scenes) {
    scene_boards.push_back(BuildBoards(scene, topt));
  }
  pixels = Ptr<vtkUnsignedCharArray>::New();
  Select(0);
}

void SceneRenderer::Impl::Select(int index) {
  if (index < 0 || index >= static_cast<int>(scene_boards.size())) {
    throw std::out_of_range("SceneRenderer::SelectScene: scene " + std::to_string(index) + " of " +
                            std::to_string(scene_boards.size()));
  }
  for (size_t i = 0; i < scene_boards.size(); ++i) {
    for (const BoardActors& b : scene_boards[i]) {
      b.front->SetVisibility(static_cast<int>(i) == index);
      b.back->SetVisibility(static_cast<int>(i) == index);
    }
  }
  boards = &scene_boards[index];
}

std::vector<BoardActors> SceneRenderer::Impl::BuildBoards(const TargetScene& scene,
                                                          const TagTextureOptions& topt) {
  std::vector<BoardActors> boards;
  for (const TagBoard& board : scene.boards) {
    const TagTexture tex = MakeTagTexture(board, topt);
    const int nx = static_cast<int>(tex.x_board.size()), ny = static_cast<int>(tex.y_board.size());
    auto points = Ptr<vtkPoints>::New();
    points->SetDataTypeToDouble();
    auto tcoords = Ptr<vtkFloatArray>::New();
    tcoords->SetNumberOfComponents(2);
    tcoords->SetName("tcoords");
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        points->InsertNextPoint(tex.x_board[i], tex.y_board[j], 0.0);
        const float st[2] = {static_cast<float>(tex.x_texel[i] / tex.image.cols),
                             static_cast<float>(tex.y_texel[j] / tex.image.rows)};
        tcoords->InsertNextTuple(st);
      }
    }
    // Counter-clockwise in the GL window (= front) when seen from the board's
    // -z side, the printed side (targets.h).
    auto quads = Ptr<vtkCellArray>::New();
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        const vtkIdType a = j * nx + i;
        const vtkIdType ids[4] = {a, a + nx, a + nx + 1, a + 1};
        quads->InsertNextCell(4, ids);
      }
    }
    auto poly = Ptr<vtkPolyData>::New();
    poly->SetPoints(points);
    poly->SetPolys(quads);
    poly->GetPointData()->SetTCoords(tcoords);
    auto normals = Ptr<vtkFloatArray>::New();
    normals->SetNumberOfComponents(3);
    for (vtkIdType k = 0; k < points->GetNumberOfPoints(); ++k) normals->InsertNextTuple3(0, 0, -1);
    poly->GetPointData()->SetNormals(normals);

    auto image = Ptr<vtkImageData>::New();
    image->SetDimensions(tex.image.cols, tex.image.rows, 1);
    image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
    // vtkImageData row 0 is texture t = 0, which the tcoords give to board y_min.
    auto* dst = static_cast<unsigned char*>(image->GetScalarPointer());
    for (int r = 0; r < tex.image.rows; ++r) {
      std::memcpy(dst + static_cast<size_t>(r) * tex.image.cols, tex.image.ptr<uint8_t>(r),
                  tex.image.cols);
    }
    auto texture = Ptr<vtkTexture>::New();
    texture->SetInputData(image);
    texture->SetColorModeToDirectScalars();
    texture->InterpolateOn();
    texture->MipmapOn();
    texture->SetMaximumAnisotropicFiltering(static_cast<float>(options.max_anisotropy));
    texture->RepeatOff();
    texture->EdgeClampOn();

    auto mapper = Ptr<vtkPolyDataMapper>::New();
    mapper->SetInputData(poly);
    mapper->ScalarVisibilityOff();
    BoardActors ba;
    ba.ref_from_board = board.ref_from_board;
    ba.outline = {
        Eigen::Vector3d(tex.x_min(), tex.y_min(), 0), Eigen::Vector3d(tex.x_max(), tex.y_min(), 0),
        Eigen::Vector3d(tex.x_max(), tex.y_max(), 0), Eigen::Vector3d(tex.x_min(), tex.y_max(), 0)};
    ba.front = Ptr<vtkActor>::New();
    ba.front->SetMapper(mapper);
    ba.front->SetTexture(texture);
    vtkProperty* prop = ba.front->GetProperty();
    prop->SetColor(1, 1, 1);
    prop->SetSpecular(0);
    prop->BackfaceCullingOn();
    if (options.lighting) {
      prop->SetAmbient(0.3);
      prop->SetDiffuse(0.7);
    } else {
      prop->SetAmbient(1.0);
      prop->SetDiffuse(0.0);
    }
    // The unprinted back: plain, a little darker than the paper.
    // Its own mapper: a mapper shared by a textured and an untextured actor
    // keeps one actor's shader for both (VTK 9.1).
    auto back_mapper = Ptr<vtkPolyDataMapper>::New();
    back_mapper->SetInputData(poly);
    back_mapper->ScalarVisibilityOff();
    ba.back = Ptr<vtkActor>::New();
    ba.back->SetMapper(back_mapper);
    vtkProperty* back = ba.back->GetProperty();
    const double grey = 0.6 * options.paper / 255.0;
    back->SetColor(grey, grey, grey);
    back->SetAmbient(1.0);
    back->SetDiffuse(0.0);
    back->SetSpecular(0);
    back->FrontfaceCullingOn();
    renderer->AddActor(ba.front);
    renderer->AddActor(ba.back);
    boards.push_back(ba);
  }
  return boards;
}

void SceneRenderer::Impl::RenderCanvas(const Rigid3& ref_from_cam, const CameraTool& cam,
                                       const Canvas& cv_canvas, int box, cv::Mat* out) {
  const int k = box;
  const int w = cv_canvas.width * k, h = cv_canvas.height * k;
  out->create(cv_canvas.height, cv_canvas.width, CV_32FC1);

  // Pose: VTK's camera sits at the origin looking down -z with +y up, so every
  // board gets view_from_board = diag(1, -1, -1) * cam_from_ref * ref_from_board.
  const Rigid3 cam_from_ref = ref_from_cam.Inverse();
  double z_min = std::numeric_limits<double>::infinity(), z_max = 0;
  for (const BoardActors& b : *boards) {
    const Rigid3 cam_from_board = cam_from_ref * b.ref_from_board;
    for (const Eigen::Vector3d& p : b.outline) {
      const double z = (cam_from_board * p).z();
      if (z > 0) z_min = std::min(z_min, z);
      z_max = std::max(z_max, z);
    }
    Eigen::Matrix4d view = cam_from_board.Matrix();
    view.row(1) *= -1;
    view.row(2) *= -1;
    auto m = Ptr<vtkMatrix4x4>::New();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m->SetElement(r, c, view(r, c));
    }
    b.front->SetUserMatrix(m);
    b.back->SetUserMatrix(m);
  }
  if (!(z_max > 0)) {  // every board behind the camera
    out->setTo(options.background);
    return;
  }
  // Depth range: a board may cross the camera plane; near then falls back to a
  // small fraction of the far distance (24-bit depth keeps ample resolution).
  const double far_z = 1.5 * z_max;
  const double near_z = std::max(0.5 * std::min(z_min, z_max), 1e-5 * z_max);

  // Supersampled pixel i covers output pixel i / k: u_k + 1/2 = k (u + 1/2).
  const double fx = cam.intrinsics[0] * k, fy = cam.intrinsics[1] * k;
  const double cx = k * (cam.intrinsics[2] - cv_canvas.u0 + 0.5) - 0.5;
  const double cy = k * (cam.intrinsics[3] - cv_canvas.v0 + 0.5) - 0.5;
  const Eigen::Matrix4d p = OpenGlProjection(fx, fy, cx, cy, w, h, near_z, far_z);
  auto proj = Ptr<vtkMatrix4x4>::New();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) proj->SetElement(r, c, p(r, c));
  }
  renderer->GetActiveCamera()->SetExplicitProjectionTransformMatrix(proj);

  const int* size = window->GetSize();
  if (size[0] != w || size[1] != h) window->SetSize(w, h);
  window->Render();
  if (window->GetRGBACharPixelData(0, 0, w - 1, h - 1, /*front=*/0, pixels) == 0) {
    throw std::runtime_error("SceneRenderer: reading back the rendered image failed");
  }
  const unsigned char* rgba = pixels->GetPointer(0);

  // k x k box average of the red channel (the scene is grey), flipping GL's
  // bottom-up rows to image rows.
  if (k == 1) {
    // No averaging (the distorted path averages after sampling): the red
    // channel, flipped, as float (OpenCV's vectorised loops).
    const cv::Mat gl(h, w, CV_8UC4, const_cast<unsigned char*>(rgba));
    cv::extractChannel(gl, red, 0);
    cv::flip(red, red_flipped, 0);
    red_flipped.convertTo(*out, CV_32F);
    return;
  }
  const float scale = 1.0f / (k * k);
  cv::parallel_for_(cv::Range(0, cv_canvas.height), [&](const cv::Range& rows) {
    std::vector<int> acc(cv_canvas.width);
    for (int r = rows.start; r < rows.end; ++r) {
      std::fill(acc.begin(), acc.end(), 0);
      for (int i = 0; i < k; ++i) {
        const int gl_row = h - 1 - (r * k + i);
        const unsigned char* src = rgba + static_cast<size_t>(gl_row) * w * 4;
        if (k == 2) {
          for (int c = 0; c < cv_canvas.width; ++c) acc[c] += src[8 * c] + src[8 * c + 4];
        } else {
          for (int c = 0; c < cv_canvas.width; ++c) {
            for (int j = 0; j < k; ++j) acc[c] += src[4 * (c * k + j)];
          }
        }
      }
      float* dst = out->ptr<float>(r);
      for (int c = 0; c < cv_canvas.width; ++c) dst[c] = acc[c] * scale;
    }
  });
}

SceneRenderer::SceneRenderer(const TargetScene& scene, const RenderOptions& options)
    : SceneRenderer(std::vector<TargetScene>{scene}, options) {}

SceneRenderer::SceneRenderer(const std::vector<TargetScene>& scenes, const RenderOptions& options)
    : impl_(std::make_unique<Impl>()) {
  if (const std::string msg = options.Check(); !msg.empty()) {
    throw std::invalid_argument("RenderOptions: " + msg);
  }
  if (scenes.empty()) throw std::invalid_argument("SceneRenderer: no scene");
  impl_->options = options;
  impl_->Build(scenes);
}

SceneRenderer::~SceneRenderer() {
  if (impl_ && impl_->window) impl_->window->Finalize();
}

void SceneRenderer::SelectScene(int index) { impl_->Select(index); }

const RenderOptions& SceneRenderer::options() const { return impl_->options; }

SceneRenderer::MapCounts SceneRenderer::map_counts() const { return impl_->map_counts; }

cv::Mat SceneRenderer::RenderPinhole(const Rigid3& ref_from_cam, const CameraTool& cam) {
  cv::Mat out;
  impl_->RenderCanvas(ref_from_cam, cam, Canvas{cam.width, cam.height, 0, 0},
                      impl_->options.supersample, &out);
  return out;
}

cv::Mat SceneRenderer::Render(const Rigid3& ref_from_cam, const CameraTool& cam,
                              std::uint64_t image_seed) {
  Impl& im = *impl_;
  const RenderOptions& o = im.options;
  auto it = std::find_if(im.maps.begin(), im.maps.end(),
                         [&](const DistortionMap& m) { return m.Matches(cam, o.supersample); });
  if (it == im.maps.end()) {
    // A refocused camera: derived from the solved map of its lens, which
    // moves to the front so that it stays while the derived maps come and go.
    const auto base = std::find_if(im.maps.begin(), im.maps.end(), [&](const DistortionMap& m) {
      return m.solved && !m.identity && m.SameLens(cam, o.supersample);
    });
    DistortionMap derived;
    if (base != im.maps.end() && DeriveDistortionMap(*base, cam, o.max_canvas_factor, &derived)) {
      im.maps.splice(im.maps.begin(), im.maps, base);
      im.maps.push_front(std::move(derived));
      ++im.map_counts.derived;
    } else {
      im.maps.push_front(BuildDistortionMap(cam, o.supersample, o.max_canvas_factor));
      if (!im.maps.front().identity) ++im.map_counts.solved;
    }
    if (im.maps.size() > Impl::kMaxMaps) im.maps.pop_back();
  } else if (it != im.maps.begin()) {
    im.maps.splice(im.maps.begin(), im.maps, it);
  }
  const DistortionMap& map = im.maps.front();
  cv::Mat* img = &im.canvas;
  if (map.identity) {
    im.RenderCanvas(ref_from_cam, cam, map.canvas, o.supersample, &im.canvas);
  } else {
    // Distorted: the ideal canvas at the supersampled size, each output pixel
    // the mean of its k x k samples through the map (SampleDistorted).
    im.RenderCanvas(ref_from_cam, Supersampled(cam, o.supersample), map.canvas, 1, &im.canvas);
    SampleDistorted(im.canvas, map.map_x, map.map_y, o.supersample,
                    static_cast<float>(o.background), &im.box, &im.distorted);
    img = &im.distorted;
  }
  if (o.blur_sigma > 0) cv::GaussianBlur(*img, *img, cv::Size(), o.blur_sigma, o.blur_sigma);
  if (o.exposure != 1.0) *img *= o.exposure;
  if (o.noise_sigma > 0) {
    im.noise.create(img->size(), CV_32FC1);
    cv::RNG rng(Mix(o.seed ^ Mix(image_seed)));
    rng.fill(im.noise, cv::RNG::NORMAL, 0.0, o.noise_sigma);
    *img += im.noise;
  }
  cv::Mat out;
  img->convertTo(out, CV_8UC1);  // rounds and saturates
  return out;
}

}  // namespace rtscalib::render
