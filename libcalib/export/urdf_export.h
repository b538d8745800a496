// The instrument's rigid kinematic chain as a URDF (robot description XML).
//
// Links (frames):
//   reference        the reference frame (SPEC 1: x east, y north, z up), the root
//   alidade          after the vertical-axis joint
//   telescope        after the tilting-axis joint
//   edm              rtscalib's EDM frame (ray = +z), fixed to the telescope
//   camera_zoom<z>   rtscalib's camera frame of zoom z (z optical axis, x image
//                    right, y image down), fixed to the telescope
// Joints (type "continuous": revolute without limits; both axes turn fully):
//   vertical_axis  reference -> alidade, joint value = phi* (the corrected reading)
//   tilting_axis   alidade -> telescope, joint value = theta* - v0
// Joint axes and origins per kinematics (kinematics.h has the chains):
//   dh:        vertical_axis: origin Base Tz(d1) Rz(gamma1), axis +z (DH z_1; it points down
//              in the ideal instrument, Base = Rx(pi), so phi turns clockwise seen from above)
//              tilting_axis:  origin Tx(a1) Rx(alpha1) Tz(d2) Rz(gamma2 + v0), axis +z
//              tools:         Tx(a2) Rx(alpha2) flange_from_tool
//   spherical: vertical_axis: origin Base, axis -z (Rz(-phi*): clockwise seen from above)
//              tilting_axis:  origin Ry(i) Rx(-v0), axis -x (Rx(-theta*))
//              tools:         Ry(c) flange_from_tool
// so that reference_from_tool(joint values) = rtscalib's RefFromEdm / RefFromCam
// exactly. Folded in exactly (constant rigid rotations): vertical_index v0
// (about the tilting axis itself), tilting_axis i and collimation c (spherical).
// Not representable in a URDF, listed in an XML comment and in `not_held`:
// the angle effects that depend on the reading (eccentricities, scales: they
// make phi*, theta*, see UrdfJointPositions), axis_wobble (a tilt of the
// vertical axis that turns with phi), the EDM constants (the EDM point is
// edm * [0 0 d*], d* = d + k0 + m d + cyclic), intrinsics and distortion
// (--format opencv). Origins are written as xyz and rpy with
// R = Rz(yaw) Ry(pitch) Rx(roll), URDF's convention and Klug Eq. 83's.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"

namespace rtscalib {

constexpr const char* kUrdfReferenceLink = "reference";
constexpr const char* kUrdfAlidadeLink = "alidade";
constexpr const char* kUrdfTelescopeLink = "telescope";
constexpr const char* kUrdfEdmLink = "edm";
constexpr const char* kUrdfVerticalJoint = "vertical_axis";
constexpr const char* kUrdfTiltingJoint = "tilting_axis";
std::string UrdfCameraLink(int zoom);  // camera_zoom<z>

struct UrdfOptions {
  std::string robot_name = "rtscalib_instrument";
  std::string source;  // where the model came from, for the header comment
};

struct UrdfExport {
  std::string xml;
  std::vector<std::string> folded;    // effects folded exactly into joint origins
  std::vector<std::string> not_held;  // effects the URDF cannot hold, with values and formulas
};

UrdfExport ExportUrdf(const InstrumentModel& model, const UrdfOptions& options = {});

// The joint values {vertical_axis, tilting_axis} at which the URDF's edm and
// camera frames equal rtscalib's at readings (phi, theta): phi* and theta* - v0
// (the reading-dependent angle effects applied; v0 lives in the origin).
// Exact for every model without axis_wobble.
std::array<double, 2> UrdfJointPositions(const InstrumentModel& model, double phi, double theta);

// [roll, pitch, yaw] with R = Rz(yaw) Ry(pitch) Rx(roll) that reproduce `r` to
// rounding also near pitch = +-pi/2 (where the ideal dh tools sit): roll from
// the last row, then pitch and yaw from R Rx(-roll), whose entries there are of
// order one, so that an ill-determined roll is absorbed by yaw.
Eigen::Vector3d UrdfRpy(const Eigen::Matrix3d& r);

}  // namespace rtscalib
