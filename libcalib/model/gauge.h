// One physical instrument, other parameter values: the re-expressions that
// leave every prediction unchanged (the EDM point and the camera ray at any
// readings, the pixel of any board corner or estimated point), so that two
// models fitted in different gauges can be compared, and a truth can be put
// into the gauge a fit held (a photo-only fit compared with its truth).
//
// Reference frame (SPEC 1, SPEC 7). With ref'_from_ref = (R', t'):
//   base   <- ref'_from_ref * base
//   boards <- ref'_from_ref * ref_from_board,  points <- ref'_from_ref * x
//   axis_wobble (turns about the reference frame's x and y axes, SPEC 4):
//     R' W(phi) R'^T; for R' = Rz(psi) exactly phi_w' = phi_w - psi, i.e.
//     [w0', w1'] = [w0 cos psi + w1 sin psi, w1 cos psi - w0 sin psi];
//     psi is read off R''s x-y block, so a tilt of R' (levelling, mrad) is
//     left out: an error of order w * tilt (1e-5 * 1e-3 rad), negligible.
//   Everything else (links, tools, intrinsics, other effects) is frame-free.
//
// dh offsets (kinematics.h: Z_i = Tz(d_i) Rz(q_i + gamma_i), X_i = Tx(a_i) Rx(alpha_i)):
//   link 1's d and gamma_offset: Tz(d) Rz(gamma) commutes with the joint's
//     Rz(q), so base * Tz(d) Rz(gamma) is one instrument for any split:
//     base' = base Tz(d) Rz(gamma) (Tz(d') Rz(gamma'))^-1 (exact);
//   link 2 (all four): Z2 X2 = Rz(q) M2 with M2 = Tz(d2) Rz(gamma2) Tx(a2) Rx(alpha2),
//     so link 2 and the tools trade exactly: tool' = M2'^-1 M2 tool for the EDM
//     and every camera.
//
// The instrument's ideal base frame (SPEC 7: origin on the vertical axis at
// the foot of the common perpendicular of the two axes (their intersection
// for an ideal instrument), z up the vertical axis, phi = 0 towards +y) is the
// frame in which base and, dh, link 1's d and gamma_offset are IdealModel's:
// the gauge of a fit with no known position (libcalib/fit/unknowns.h).
//
// Sigmas (ModelSigmas, boards' and points' sigma) are NOT transformed: they
// stay those of the parameters the fit had. Callers that compare
// uncertainties across gauges decide what carries over (libcalib/api/compare.cc).
#pragma once

#include <Eigen/Core>

#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

// The linear map of axis_wobble's [w0, w1] under `new_from_old` (above):
// [[cos psi, sin psi], [-sin psi, cos psi]], psi its turn about z. A
// covariance of [w0, w1] maps with it too.
Eigen::Matrix2d AxisWobbleMap(const Rigid3& new_from_old);

// Moves `m` into the reference frame ref' given by `new_from_old`.
// Throws std::invalid_argument when axis_wobble is enabled and the two
// frames' z axes point more than 90 degrees apart (the wobble's turning sense
// would flip: not a re-expression of the same parameters).
void ChangeReferenceFrame(const Rigid3& new_from_old, InstrumentModel* m);

// dh: link 1's d and gamma_offset set to the given values, the base takes up
// the difference. No-op for spherical models.
void SetFirstJointOffsets(double d, double gamma_offset, InstrumentModel* m);

// dh: link 2 set to `link`, the EDM and camera tools take up the difference.
// No-op for spherical models.
void SetSecondLink(const DhLink& link, InstrumentModel* m);

// Puts `m` into its ideal base frame (above); returns ref'_from_ref.
Rigid3 ToIdealBaseFrame(InstrumentModel* m);

}  // namespace rtscalib
