// Base and tool transforms of the extraction (Klug et al. Sec. 3.1.9-3.1.11),
// all through the point-set alignment of libcalib/geometry/kabsch.h.
//
// Base (Eq. 58-61): ref_from_base maps the reference axes at the origin onto
// frame 1: S_a = {0, x_0, y_0, z_0} -> S_b = {o_1, o_1 + x_1, o_1 + y_1, o_1 + z_1}.
// The paper uses the three axis tips only; the origin pair is added so that
// the centred sets are not coplanar (the result is the same for exact frames).
//
// Camera tool of one zoom (Eq. 62-73). At every usable pose with camera rows
// at the principal point c and at c + [1, 0] and c + [0, 1] (Eq. 67 prints
// c + [1, 0] twice; the second is c + [0, 1]) with the same ray length d, the
// three points are taken into the flange frame,
//   x~_k = (M_B M_{1,M}(phi, theta))^-1 x_k                                 (Eq. 65, 66)
// and matched with camera-frame points; all poses go into one alignment.
//   exact rays (default):  a_k = d * ray(u_k) from the intrinsics and
//                          distortion (libcalib/camera), b_k = x~_k: exact for
//                          any camera.
//   paper (Eq. 69, 70):    a = {c_t, c_t + [1 0 0], c_t + [0 1 0]}, c_t = [0 0 d],
//                          b = {x~_1, (x_1 + unit(x_2 - x_1))~, (x_1 + unit(x_3 - x_1))~},
//                          which assumes the ray through c + [1, 0] at length d
//                          ends at d [1/f, 0, 1] (Eq. 72/73 drop the length
//                          correction sqrt(1 + 1/f^2)); the normalised axis is
//                          then tilted towards -z by ~1/(2 f) rad.
// When no pose has the triplet but the intrinsics are given (and exact rays
// are on), every usable camera row of the zoom is a correspondence
// d * ray(u, v) <-> x~: exact too, and it needs no particular pixels.
// Without given intrinsics, fx and fy are estimated from the chord between
// the rays through c and c + [1, 0] (c + [0, 1]):
//   f = 1 / tan(2 asin(|x_2 - x_1| / (2 d))),
// exact for a pinhole camera, averaged over the poses.
//
// EDM tool (Eq. 74-82). At every usable pose with EDM rows at two distances
// d_a < d_b (the two smallest at that pose):
//   z_EDM = unit(x_b - x_a)
//   x_EDM = (x_r - (x_r^T z_EDM) z_EDM) / |.|                               (Eq. 79)
// where x_r is the camera's x axis at that pose (lowest zoom with a camera
// tool), its y axis when x is within 1e-3 of z_EDM (footnote 8), and the
// flange's x (then y) axis when there is no camera. Eq. 79 prints z_CAM^T in
// the numerator's projection; x_CAM^T is meant (projecting x_CAM onto the
// plane normal to z_EDM).
//   a = {[0 0 d_a], [1 0 d_a], [0 0 d_a + 1]},
//   b = {x_a~, (x_a + x_EDM)~, (x_a + z_EDM)~}                              (Eq. 80-82)
// The rotation about the EDM ray is a convention (it does not change any EDM
// point); everything else is exact.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "libcalib/extract/dh_frames.h"
#include "libcalib/extract/options.h"
#include "libcalib/extract/sweeps.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"

namespace rtscalib {

// Eq. 58-61.
Rigid3 BaseFromFirstFrame(const LinkFrame& frame1);

struct CameraToolEstimate {
  CameraTool camera;  // flange_from_cam set; intrinsics as given or estimated
  int poses = 0;      // poses with a complete pixel triplet
  double rms = 0.0;   // Kabsch residual RMS [m]
  bool intrinsics_estimated = false;
  std::string note;
};

// Eq. 62-73 for one zoom. `model` must hold the base and links already.
// `given` is the configured camera of this zoom (nullptr: none; then the
// intrinsics are estimated as above and the distortion is zero).
// Returns std::nullopt when the zoom has no usable camera rows at all; throws
// ExtractionError when its rows cannot give the tool (no complete triplet and
// no intrinsics, or rows along a single camera-frame line).
std::optional<CameraToolEstimate> ExtractCameraTool(const std::vector<Record>& records,
                                                    const std::vector<int>& usable,
                                                    const InstrumentModel& model, int zoom,
                                                    const PrincipalPoint& principal_point,
                                                    const CameraTool* given,
                                                    const ExtractOptions& options);

struct EdmToolEstimate {
  PoseBlock flange_from_edm;
  int poses = 0;
  double rms = 0.0;
  std::string x_reference;  // "camera x (zoom 0)", "camera y (zoom 0)", "flange x", ...
};

// Eq. 74-82. `model` must hold the base, links and the camera tools found so
// far (reference_zoom < 0: no camera). Returns std::nullopt when no usable
// pose has EDM rows at two distances.
std::optional<EdmToolEstimate> ExtractEdmTool(const std::vector<Record>& records,
                                              const std::vector<int>& usable,
                                              const InstrumentModel& model, int reference_zoom,
                                              const ExtractOptions& options);

}  // namespace rtscalib
