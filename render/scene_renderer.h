// Renders a TargetScene as the instrument camera sees it: exact OpenCV
// intrinsics and all 14 distortion coefficients, 8-bit grayscale.
//
// Pipeline of Render() (docs/rendering.md derives each step):
//   1. ideal pinhole image with VTK/OpenGL through an explicit projection
//      matrix built from fx, fy, cx, cy (pixel (0,0) = centre of the top-left
//      pixel, camera x = +u, y = +v down, z forward), at `supersample` times
//      the size, on a canvas that covers every ray the distorted image sees;
//   2. lens distortion, at the supersampled size: for every supersampled
//      pixel the ideal pixel is found with UndistortPixel and sampled
//      bilinearly at its exact coordinates (no distortion: nothing to do);
//   3. box (area) downsampling by `supersample`;
//   4. exposure gain, optional Gaussian blur, optional Gaussian noise, 8 bit.
// The boards (AprilTag, ChArUco or chessboards) are textured rectangles
// (tag_texture.h) with linear, mipmapped texture filtering; only their
// printed (-z) side is drawn.
//
// One SceneRenderer owns one offscreen VTK render window reused across calls
// (and across its scenes);
// not thread-safe. It needs an X display (headless.h) for its whole lifetime.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/targets.h"
#include "render/tag_texture.h"

namespace rtscalib::render {

struct RenderOptions {
  int supersample = 2;        // render at k x the size, then k x k box average
  double background = 90;     // grey level of everything but the boards [0, 255]
  unsigned char ink = 20;     // printed black [0, 255]
  unsigned char paper = 235;  // printed white [0, 255]
  bool lighting = false;      // false: flat (paper = `paper` at any angle);
                              // true: ambient 0.3 + diffuse 0.7 from a headlight
  double exposure = 1.0;      // gain on all grey levels before noise (> 0)
  double blur_sigma = 0;      // Gaussian optical blur, output pixels (0 = off)
  double noise_sigma = 0;     // Gaussian sensor noise, grey levels (0 = off)
  std::uint64_t seed = 1;     // noise seed, mixed with Render()'s image seed
  int max_anisotropy = 1;     // anisotropic texture filtering (1 = isotropic mipmaps)
  // Largest canvas side for the ideal image, as a multiple of the output side;
  // rays of strongly distorted lenses beyond it show `background`.
  double max_canvas_factor = 3.0;
  TagTextureOptions texture;

  std::string Check() const;  // empty when valid
};

class SceneRenderer {
 public:
  // Builds the VTK scene (one textured rectangle set per board). Throws
  // std::invalid_argument for invalid options or boards, std::runtime_error
  // when no OpenGL context can be created.
  SceneRenderer(const TargetScene& scene, const RenderOptions& options = {});
  // Several scenes in one window, the first one selected: the placements of
  // one board moved between sets of shots (SPEC 7.1). Each scene's boards
  // are built once; the window, its framebuffers and the distortion maps
  // serve them all, so a session of many placements costs one OpenGL
  // context and one map per lens, not one per placement.
  SceneRenderer(const std::vector<TargetScene>& scenes, const RenderOptions& options = {});
  ~SceneRenderer();
  // The scene that Render and RenderPinhole draw from now on (an index into
  // the constructor's scenes); the others are hidden.
  void SelectScene(int index);
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // What camera `cam` at pose `ref_from_cam` sees (cam.flange_from_cam is not
  // used: the pose is the camera's own). CV_8UC1, cam.height x cam.width.
  // `image_seed` varies the noise between images (same seed = same image).
  cv::Mat Render(const Rigid3& ref_from_cam, const CameraTool& cam, std::uint64_t image_seed = 0);

  // Step 1 and 2 only, as 32-bit float grey levels: the undistorted pinhole
  // image at `cam`'s intrinsics and size (distortion ignored, no canvas).
  cv::Mat RenderPinhole(const Rigid3& ref_from_cam, const CameraTool& cam);

  const RenderOptions& options() const;
  // Distortion maps made so far: solved pixel by pixel (a new lens), or
  // derived from the solved map of the same lens (a camera that refocuses
  // changes its intrinsics only; scene_renderer.cc, DeriveDistortionMap).
  struct MapCounts {
    int solved = 0, derived = 0;
  };
  MapCounts map_counts() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The OpenGL projection matrix (row-major, acting on column vectors of VTK/
// OpenGL view coordinates: x right, y up, looking down -z) that puts camera
// point (x, y, z) = (x_v, -y_v, -z_v) at OpenCV pixel (fx x/z + cx, fy y/z + cy)
// of a width x height image whose GL window row 0 is the image's bottom row.
// Depth maps [near, far] to NDC [-1, 1].
Eigen::Matrix4d OpenGlProjection(double fx, double fy, double cx, double cy, int width, int height,
                                 double near_z, double far_z);

}  // namespace rtscalib::render
