// Model simplification of Klug et al. Sec. 4.1: an extracted model whose
// translations are close to zero and whose rotations are close to multiples
// of pi/2 is snapped to the idealised instrument, and its end-to-end rotation
// M_B,T(phi, theta) is written in closed form (Eq. 84-91).
//
// Snapping (SnapModel):
//   translations  base t, DH d and a, EDM and camera tool t      -> 0
//   DH angles     alpha_i and gamma_offset_i                      -> nearest k pi/2
//   base, tools   Euler angles [a, b, g] of R = Rz(g) Ry(b) Rx(a) (Eq. 83), each
//                 -> nearest k pi/2, R rebuilt from the snapped angles
//   effects       kinematic effects (collimation, eccentricities, EDM terms, ...)
//                 are removed; camera intrinsics and distortion are kept.
// Snapping Euler angles one by one is the paper's recipe; near gimbal lock
// (|b| ~ pi/2) a and g are individually ill-conditioned, so the notes report
// each block's largest angle change (a change near pi/4 means the snap is
// ambiguous).
//
// Closed form (FitTrigForm): every entry of R(phi, theta) of a snapped model is
// an integer combination of the nine products
//   1, cos(phi), sin(phi), cos(theta), sin(theta), cos(phi) cos(theta),
//   cos(phi) sin(theta), sin(phi) cos(theta), sin(phi) sin(theta)
// (the joints turn about axes that the snapped transforms map onto coordinate
// axes). The coefficients are found numerically: R is sampled at a 5 x 5 grid
// of (phi, theta), the 9 coefficients of each entry solved by least squares and
// rounded to integers; `exact` says whether the rounded form reproduces the
// samples to 1e-9 (true for every snapped model).
// Euler form (RecogniseEulerForm): R = Rz(s1 phi + k1 pi/2) Ry(k2 pi/2)
// Rx(s3 theta + k3 pi/2) with s = +-1 (Eq. 91), the first match in the order
// k in {0, 1, -1, 2} (k1, then k2, then k3), s in {-1, +1}.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"

namespace rtscalib {

// Returns the snapped model; `notes` (optional) receives one line per block.
InstrumentModel SnapModel(const InstrumentModel& model, std::vector<std::string>* notes = nullptr);
// The nearest multiple of pi/2 (ties away from zero).
double SnapToQuarterTurn(double angle_rad);

constexpr int kNumTrigTerms = 9;
// Names of the nine products above, in order: "1", "cos(phi)", ..., "sin(phi)*sin(theta)".
const std::array<const char*, kNumTrigTerms>& TrigTermNames();

struct TrigForm {
  // R(phi, theta)(row, col) = sum_k coeff[row][col][k] * term_k(phi, theta)
  std::array<std::array<std::array<int, kNumTrigTerms>, 3>, 3> coeff{};
  double max_rounding = 0.0;  // largest |least-squares coefficient - rounded|
  double max_error = 0.0;     // largest |R - rounded form| over the samples
  bool exact = false;         // max_error <= 1e-9

  Eigen::Matrix3d Evaluate(double phi, double theta) const;
  // Eq. 90 style, one bracketed row per line:
  //   [ cos(phi), sin(phi)*cos(theta), sin(phi)*sin(theta) ]
  std::string ToString() const;
  bool operator==(const TrigForm& o) const { return coeff == o.coeff; }
};

// `rotation` must return a Matrix3d (a lambda returning an Eigen product
// expression such as `Rz(p) * Rx(t)` would dangle: declare `-> Eigen::Matrix3d`).
TrigForm FitTrigForm(const std::function<Eigen::Matrix3d(double phi, double theta)>& rotation);

struct EulerForm {
  int phi_sign = 1, phi_quarter_turns = 0;      // Rz(phi_sign phi + k pi/2)
  int beta_quarter_turns = 0;                   // Ry(k pi/2)
  int theta_sign = 1, theta_quarter_turns = 0;  // Rx(theta_sign theta + k pi/2)
  Eigen::Matrix3d Evaluate(double phi, double theta) const;
  std::string ToString() const;  // e.g. "Rz(-phi) Ry(0) Rx(-theta)"
};

std::optional<EulerForm> RecogniseEulerForm(const TrigForm& form);

struct SimplifiedModel {
  InstrumentModel model;           // snapped
  TrigForm rotation;               // of M_B,T = ref_from_tool (Eq. 84, 90)
  std::optional<EulerForm> euler;  // Eq. 91, when R has that form
  std::vector<std::string> notes;
};

// Snaps `model` and writes the closed form of ref_from_tool's rotation for the
// EDM tool (camera_zoom < 0) or the camera of `camera_zoom`.
SimplifiedModel Simplify(const InstrumentModel& model, int camera_zoom = -1);

}  // namespace rtscalib
