// The focus of an image-assisted instrument's telescope camera (SPEC 4.1,
// catalogue effect `focus`).
//
// The camera focuses on its target: the focusing lens moves with the target's
// distance, and with it the camera constant and the principal point. With
// fx, fy, cx, cy the intrinsics focused at infinity and D [m] the photo's
// focus distance, the intrinsics of the photo are
//   fx* = fx (1 + kf / D)      fy* = fy (1 + kf / D)
//   cx* = cx + au / D          cy* = cy + av / D
// Parameters per zoom level, in this order (CameraTool::focus):
//   kf  [m]     relative growth of the camera constant times D (report: mm);
//               for a thin lens of focal length f the image distance is
//               f D / (D - f) = f (1 + f/D + ...), so kf is about f
//   au  [px m]  principal point shift in u times D
//   av  [px m]  principal point shift in v times D
// Valid region: D > 0; the model is the first term in 1/D of the lens's
// focusing, accurate while kf / D << 1 (a 5 % change of the camera constant
// leaves a second-order error of 0.25 %, which a near target shows).
// Without the effect (the block held at zero) D plays no role.
//
// D of a photo (SPEC 4.1): its `focus_distance` (shots.csv / pixels.csv; what
// the instrument reports), else the distance from the camera centre to the
// centroid of the points the photo sees, as the model places them (boards of
// estimated pose included). D of a `cam` record: its ray length d.
#pragma once

#include <vector>

namespace rtscalib {

struct InstrumentModel;
struct PixelObservation;
struct TargetScene;

enum FocusIndex { kFocusKf = 0, kFocusAu = 1, kFocusAv = 2 };
constexpr int kNumFocus = 3;
// Names (model.yaml keys, fit columns) and report units with their scale
// from SI (kf in mm; au, av in px m as stored).
inline constexpr const char* kFocusParamNames[kNumFocus] = {"kf", "au", "av"};
inline constexpr const char* kFocusReportUnits[kNumFocus] = {"mm", "px m", "px m"};
inline constexpr double kFocusReportScale[kNumFocus] = {1e3, 1.0, 1.0};

// The intrinsics at focus distance D (formula above); `focus` may be null
// (no focus effect): then out = intrinsics. Returns false for D <= 0.
template <typename T>
bool FocusedIntrinsics(const T* intrinsics, const T* focus, const T& distance, T* out) {
  if (!focus) {
    for (int i = 0; i < 4; ++i) out[i] = intrinsics[i];
    return true;
  }
  if (!(distance > T(0))) return false;
  const T inv = T(1.0) / distance;
  const T scale = T(1.0) + focus[kFocusKf] * inv;
  out[0] = intrinsics[0] * scale;
  out[1] = intrinsics[1] * scale;
  out[2] = intrinsics[2] + focus[kFocusAu] * inv;
  out[3] = intrinsics[3] + focus[kFocusAv] * inv;
  return true;
}

// D of every pixel observation's photo (SPEC 4.1, above), in the order of
// `pixels`: focus_distance when given, else the distance from the camera of
// the photo (the model's chain at its readings) to the centroid of the
// photo's points as the model places them (X when known, else the corner of
// the model's estimated board, else of a surveyed board of `targets`; a
// point that cannot be placed is left out of the centroid). A photo is the rows that share (shot, zoom, phi, theta), as
// the fit groups them (libcalib/fit/parameterization.h). 0 where nothing can
// be computed (no point placed, or a zoom without a camera): a prediction
// then uses the point's own distance.
// With `use_given` false the focus_distance column is ignored: the target
// distance of each photo (the diagnosis tests against both).
std::vector<double> PhotoFocusDistances(const InstrumentModel& model,
                                        const std::vector<PixelObservation>& pixels,
                                        const TargetScene* targets = nullptr,
                                        bool use_given = true);
// What a prediction of `pixels` with `model` needs (PredictPixel's
// focus_distance): PhotoFocusDistances when the model has the focus effect,
// zeros otherwise (D plays no role then, and is not computed).
std::vector<double> PredictionFocusDistances(const InstrumentModel& model,
                                             const std::vector<PixelObservation>& pixels,
                                             const TargetScene* targets = nullptr);

}  // namespace rtscalib
