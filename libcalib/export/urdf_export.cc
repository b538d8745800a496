#include "libcalib/export/urdf_export.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "libcalib/text/number_text.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// + 0.0 writes -0 as 0.
std::string Num(double x) { return FormatDouble(x + 0.0); }

std::string Vec(const Eigen::Vector3d& v) {
  return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z());
}

// Report-unit text of an effect's value, e.g. "e = 12.3 arcsec, phi_e = 45 deg".
std::string ValueText(const InstrumentModel& model, Effect e) {
  const EffectInfo& info = Info(e);
  const EffectReportValue r = ToReportUnits(e, model.EffectValue(e), {0, 0, 0, 0});
  std::string out;
  for (int i = 0; i < info.num_params; ++i) {
    if (i) out += ", ";
    std::ostringstream v;
    v << std::setprecision(6) << r.value[i];
    out += std::string(info.param_names[i]) + " = " + v.str() + " " + info.report_units[i];
  }
  return out;
}

// XML comments must not contain "--".
std::string CommentSafe(std::string s) {
  for (size_t p = s.find("--"); p != std::string::npos; p = s.find("--")) s.replace(p, 2, "- -");
  return s;
}

void EmitJoint(std::ostringstream& x, const char* name, const char* type, const std::string& parent,
               const std::string& child, const Rigid3& origin, const char* axis) {
  x << "  <joint name=\"" << name << "\" type=\"" << type << "\">\n";
  x << "    <parent link=\"" << parent << "\"/>\n";
  x << "    <child link=\"" << child << "\"/>\n";
  x << "    <origin xyz=\"" << Vec(origin.translation) << "\" rpy=\""
    << Vec(UrdfRpy(origin.rotation)) << "\"/>\n";
  if (axis) x << "    <axis xyz=\"" << axis << "\"/>\n";
  x << "  </joint>\n";
}

Rigid3 Tz(double d) { return {Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, d)}; }
Rigid3 Tx(double a) { return {Eigen::Matrix3d::Identity(), Eigen::Vector3d(a, 0, 0)}; }
Rigid3 Rot(const Eigen::Matrix3d& r) { return {r, Eigen::Vector3d::Zero()}; }

}  // namespace

std::string UrdfCameraLink(int zoom) { return "camera_zoom" + std::to_string(zoom); }

Eigen::Vector3d UrdfRpy(const Eigen::Matrix3d& r) {
  const double roll = std::atan2(r(2, 1), r(2, 2));  // 0 when both vanish (gimbal lock)
  const Eigen::Matrix3d m = r * Rx(-roll);           // = Rz(yaw) Ry(pitch) up to rounding
  const double pitch = std::atan2(-m(2, 0), m(2, 2));
  const double yaw = std::atan2(-m(0, 1), m(1, 1));
  return {roll, pitch, yaw};
}

std::array<double, 2> UrdfJointPositions(const InstrumentModel& model, double phi, double theta) {
  double phi_s, theta_s;
  TrueAngles(ViewOf(model), phi, theta, &phi_s, &theta_s);
  if (model.effects.Has(Effect::kVerticalIndex)) {
    theta_s -= model.EffectValue(Effect::kVerticalIndex)[0];
  }
  return {phi_s, theta_s};
}

UrdfExport ExportUrdf(const InstrumentModel& model, const UrdfOptions& options) {
  UrdfExport out;
  const bool dh = model.kinematics == Kinematics::kDh;
  const EffectSet& fx = model.effects;
  auto value = [&](Effect e) { return fx.Has(e) ? model.EffectValue(e)[0] : 0.0; };
  const double v0 = value(Effect::kVerticalIndex);

  Rigid3 vertical_origin, tilting_origin, telescope_from_flange;
  const char* vertical_axis;
  const char* tilting_axis;
  const Rigid3 base = model.base.ToRigid();
  if (dh) {
    const auto& l1 = model.links[0].p;
    const auto& l2 = model.links[1].p;
    vertical_origin = base * Tz(l1[kDhD]) * Rot(Rz(l1[kDhGamma]));
    tilting_origin =
        Tx(l1[kDhA]) * Rot(Rx(l1[kDhAlpha])) * Tz(l2[kDhD]) * Rot(Rz(l2[kDhGamma] + v0));
    telescope_from_flange = Tx(l2[kDhA]) * Rot(Rx(l2[kDhAlpha]));
    vertical_axis = "0 0 1";
    tilting_axis = "0 0 1";
  } else {
    vertical_origin = base;
    tilting_origin = Rot(Ry(value(Effect::kTiltingAxis)) * Rx(-v0));
    telescope_from_flange = Rot(Ry(value(Effect::kCollimation)));
    vertical_axis = "0 0 -1";
    tilting_axis = "-1 0 0";
  }

  // What was folded, and what the URDF cannot hold.
  for (Effect e : fx.List()) {
    const EffectInfo& info = Info(e);
    const std::string name = info.name;
    if (IsDistortion(e)) {
      out.not_held.push_back(name + ": " + info.definition +
                             ", per zoom; in the OpenCV export (format opencv)");
      continue;
    }
    if (e == Effect::kFocus) {
      out.not_held.push_back(name + ": " + info.definition +
                             "; the camera's intrinsics, in the OpenCV export (format opencv)");
      continue;
    }
    const std::string what = name + " (" + ValueText(model, e) + ")";
    switch (e) {
      case Effect::kVerticalIndex:
        out.folded.push_back(what + ": into the tilting_axis origin (a rotation about the axis)");
        break;
      case Effect::kTiltingAxis:
      case Effect::kCollimation:
        if (dh) {
          out.not_held.push_back(what +
                                 ": not part of the dh chain (its links and tools hold it); "
                                 "rtscalib ignores it there too");
        } else if (e == Effect::kTiltingAxis) {
          out.folded.push_back(what + ": into the tilting_axis origin, Ry(i)");
        } else {
          out.folded.push_back(what + ": into the edm and camera origins, Ry(c)");
        }
        break;
      case Effect::kAxisWobble:
        out.not_held.push_back(what + ": " + info.definition +
                               "; turns with phi, so no fixed origin holds it");
        break;
      case Effect::kEdmOffset:
      case Effect::kEdmScale:
      case Effect::kEdmCyclic:
        out.not_held.push_back(
            what + ": " + info.definition +
            (e == Effect::kEdmCyclic
                 ? " with U = " + FormatShortestDouble(model.edm_cyclic_unit_length) + " m"
                 : std::string()) +
            "; the EDM point is edm * [0 0 d*]");
        break;
      default:  // reading-dependent angle corrections
        out.not_held.push_back(what + ": " + info.definition +
                               "; apply it to the reading to get the joint value");
        break;
    }
  }

  // The reading-dependent terms of phi* and theta* (kinematics.h), values listed below.
  std::string vertical_value = "phi", tilting_value = "theta";
  if (fx.Has(Effect::kHzEccentricity)) vertical_value += " + e sin(phi - phi_e)";
  if (fx.Has(Effect::kHzScale)) vertical_value += " + s phi";
  if (fx.Has(Effect::kVEccentricity)) tilting_value += " + e sin(theta - theta_e)";
  if (fx.Has(Effect::kVScale)) tilting_value += " + s theta";

  std::ostringstream x;
  x << "<?xml version=\"1.0\"?>\n";
  std::ostringstream c;
  c << "Written by rtscalib export" << (options.source.empty() ? "" : " from " + options.source)
    << ".\n"
    << "Kinematics: " << KinematicsName(model.kinematics)
    << ". Metres and radians; origins rpy with R = Rz(yaw) Ry(pitch) Rx(roll).\n"
    << "Frames: " << kUrdfReferenceLink << " = rtscalib's reference frame (x east, y north, z up); "
    << kUrdfEdmLink << " = the EDM frame (ray along +z); camera_zoom<z> = the camera frame "
    << "(z optical axis, x image right, y image down). " << kUrdfAlidadeLink << " and "
    << kUrdfTelescopeLink << " are joint frames.\n"
    << "Joint values: " << kUrdfVerticalJoint << " = " << vertical_value << " (phi: horizontal "
    << "reading, clockwise seen from above; axis " << vertical_axis << " in its frame)\n"
    << "              " << kUrdfTiltingJoint << " = " << tilting_value
    << " (theta: zenith reading; axis " << tilting_axis << " in its frame)\n";
  c << "Folded in exactly:" << (out.folded.empty() ? " nothing" : "") << "\n";
  for (const std::string& s : out.folded) c << "  " << s << "\n";
  c << "Not held by this URDF (apply them yourself):" << (out.not_held.empty() ? " nothing" : "")
    << "\n";
  for (const std::string& s : out.not_held) c << "  " << s << "\n";
  c << "Camera intrinsics and distortion: the OpenCV export (format opencv, one file per zoom).";
  x << "<!--\n" << CommentSafe(c.str()) << "\n-->\n";

  x << "<robot name=\"" << options.robot_name << "\">\n";
  for (const std::string& link : {std::string(kUrdfReferenceLink), std::string(kUrdfAlidadeLink),
                                  std::string(kUrdfTelescopeLink), std::string(kUrdfEdmLink)}) {
    x << "  <link name=\"" << link << "\"/>\n";
  }
  for (int z = 0; z < model.NumZooms(); ++z)
    x << "  <link name=\"" << UrdfCameraLink(z) << "\"/>\n";
  EmitJoint(x, kUrdfVerticalJoint, "continuous", kUrdfReferenceLink, kUrdfAlidadeLink,
            vertical_origin, vertical_axis);
  EmitJoint(x, kUrdfTiltingJoint, "continuous", kUrdfAlidadeLink, kUrdfTelescopeLink,
            tilting_origin, tilting_axis);
  EmitJoint(x, "edm_mount", "fixed", kUrdfTelescopeLink, kUrdfEdmLink,
            telescope_from_flange * model.edm.ToRigid(), nullptr);
  for (int z = 0; z < model.NumZooms(); ++z) {
    const std::string name = "camera_zoom" + std::to_string(z) + "_mount";
    EmitJoint(x, name.c_str(), "fixed", kUrdfTelescopeLink, UrdfCameraLink(z),
              telescope_from_flange * model.cams[z].flange_from_cam.ToRigid(), nullptr);
  }
  x << "</robot>\n";
  out.xml = x.str();
  return out;
}

}  // namespace rtscalib
