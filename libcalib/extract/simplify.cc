#include "libcalib/extract/simplify.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>

#include "libcalib/model/kinematics.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

constexpr double kExactForm = 1e-9;

std::array<double, kNumTrigTerms> Terms(double phi, double theta) {
  const double cp = std::cos(phi), sp = std::sin(phi), ct = std::cos(theta), st = std::sin(theta);
  return {1.0, cp, sp, ct, st, cp * ct, cp * st, sp * ct, sp * st};
}

// Snaps one pose block: its rotation to the nearest quarter-turn rotation (a
// signed permutation matrix, whose Euler angles are multiples of pi/2),
// translation to 0. Snapping each Euler angle on its own, as Sec. 4.1 reads,
// is the same away from gimbal lock, but the PLT 300's tools sit at
// b = 1.5646, where a and g are nearly the same rotation and rounding them
// separately can turn the tool by a tenth of a radian.
PoseBlock SnapPose(const PoseBlock& pose, const std::string& name,
                   std::vector<std::string>* notes) {
  const Eigen::Matrix3d r = pose.ToRigid().rotation;
  Eigen::Matrix3d snapped = Eigen::Matrix3d::Zero();
  std::array<bool, 3> used_row{false, false, false};
  for (int c = 0; c < 3; ++c) {
    int best = -1;
    for (int row = 0; row < 3; ++row) {
      if (!used_row[row] && (best < 0 || std::abs(r(row, c)) > std::abs(r(best, c)))) best = row;
    }
    used_row[best] = true;
    snapped(best, c) = r(best, c) < 0 ? -1.0 : 1.0;
  }
  if (snapped.determinant() < 0) snapped.col(2) *= -1.0;  // keep a rotation
  const Eigen::Vector3d e = pose.Euler();
  Eigen::Vector3d s = EulerFromRotation(snapped);
  for (int i = 0; i < 3; ++i) s[i] = SnapToQuarterTurn(s[i]);
  if (notes) {
    const Eigen::Vector3d t(pose.t[0], pose.t[1], pose.t[2]);
    const double turned = Eigen::AngleAxisd(snapped.transpose() * r).angle();
    notes->push_back(name + ": euler [a, b, g] (" + Significant(e[0]) + ", " + Significant(e[1]) +
                     ", " + Significant(e[2]) + ") -> (" + Significant(s[0]) + ", " +
                     Significant(s[1]) + ", " + Significant(s[2]) + ") rad, rotation changed by " +
                     Significant(turned) + " rad; |t| " + Significant(t.norm()) + " m -> 0");
  }
  return PoseBlock::FromRigid(Rigid3::FromEuler(s, Eigen::Vector3d::Zero()));
}

std::string QuarterTurns(int k) {
  switch (((k % 4) + 4) % 4) {
    case 0:
      return "0";
    case 1:
      return "pi/2";
    case 2:
      return "pi";
    default:
      return "-pi/2";
  }
}

std::string AngleTerm(int sign, const char* var, int k) {
  std::string s = std::string(sign < 0 ? "-" : "") + var;
  const int q = ((k % 4) + 4) % 4;
  if (q == 1) s += " + pi/2";
  if (q == 2) s += " + pi";
  if (q == 3) s += " - pi/2";
  return s;
}

}  // namespace

double SnapToQuarterTurn(double angle_rad) {
  return std::round(angle_rad / (M_PI / 2)) * (M_PI / 2);
}

InstrumentModel SnapModel(const InstrumentModel& model, std::vector<std::string>* notes) {
  InstrumentModel out = model;
  out.base = SnapPose(model.base, "base", notes);
  for (int i = 0; i < 2; ++i) {
    auto& p = out.links[i].p;
    const auto& q = model.links[i].p;
    p[kDhD] = 0.0;
    p[kDhA] = 0.0;
    p[kDhAlpha] = SnapToQuarterTurn(q[kDhAlpha]);
    p[kDhGamma] = SnapToQuarterTurn(q[kDhGamma]);
    if (notes) {
      notes->push_back("link " + std::to_string(i + 1) + ": alpha " + Significant(q[kDhAlpha]) +
                       " -> " + Significant(p[kDhAlpha]) + ", gamma_offset " +
                       Significant(q[kDhGamma]) + " -> " + Significant(p[kDhGamma]) + " rad; d " +
                       Significant(q[kDhD]) + ", a " + Significant(q[kDhA]) + " m -> 0");
    }
  }
  out.edm = SnapPose(model.edm, "edm tool", notes);
  for (int z = 0; z < model.NumZooms(); ++z) {
    out.cams[z].flange_from_cam =
        SnapPose(model.cams[z].flange_from_cam, "camera tool zoom " + std::to_string(z), notes);
  }
  EffectSet kept;
  for (Effect e : model.effects.List()) {
    if (IsKinematic(e)) {
      if (notes) notes->push_back(std::string("effect ") + Info(e).name + " removed");
    } else {
      kept.Add(e);
    }
  }
  out.effects = kept;
  for (auto& v : out.effect_values) v.fill(0.0);
  out.sigmas = ModelSigmas();
  return out;
}

const std::array<const char*, kNumTrigTerms>& TrigTermNames() {
  static const std::array<const char*, kNumTrigTerms> names = {"1",
                                                               "cos(phi)",
                                                               "sin(phi)",
                                                               "cos(theta)",
                                                               "sin(theta)",
                                                               "cos(phi)*cos(theta)",
                                                               "cos(phi)*sin(theta)",
                                                               "sin(phi)*cos(theta)",
                                                               "sin(phi)*sin(theta)"};
  return names;
}

Eigen::Matrix3d TrigForm::Evaluate(double phi, double theta) const {
  const auto t = Terms(phi, theta);
  Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < kNumTrigTerms; ++k) r(i, j) += coeff[i][j][k] * t[k];
    }
  }
  return r;
}

std::string TrigForm::ToString() const {
  std::ostringstream s;
  for (int i = 0; i < 3; ++i) {
    s << "[ ";
    for (int j = 0; j < 3; ++j) {
      std::string entry;
      for (int k = 0; k < kNumTrigTerms; ++k) {
        const int c = coeff[i][j][k];
        if (c == 0) continue;
        const std::string mag = std::abs(c) == 1 ? "" : std::to_string(std::abs(c)) + "*";
        const std::string term = k == 0 ? (std::abs(c) == 1 ? "1" : std::to_string(std::abs(c)))
                                        : mag + TrigTermNames()[k];
        if (entry.empty()) {
          entry = (c < 0 ? "-" : "") + term;
        } else {
          entry += (c < 0 ? " - " : " + ") + term;
        }
      }
      s << (entry.empty() ? "0" : entry) << (j < 2 ? ", " : " ");
    }
    s << "]" << (i < 2 ? "\n" : "");
  }
  return s.str();
}

TrigForm FitTrigForm(const std::function<Eigen::Matrix3d(double, double)>& rotation) {
  // 5 x 5 samples at irrational-looking spacings: the nine terms are linearly
  // independent on them (the design matrix has full column rank).
  constexpr int kN = 5;
  std::vector<std::pair<double, double>> samples;
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) samples.emplace_back(0.31 + 1.17 * i, 0.23 + 0.61 * j);
  }
  const int m = static_cast<int>(samples.size());
  Eigen::MatrixXd design(m, kNumTrigTerms);
  std::vector<Eigen::Matrix3d> values(m);
  for (int s = 0; s < m; ++s) {
    const auto t = Terms(samples[s].first, samples[s].second);
    for (int k = 0; k < kNumTrigTerms; ++k) design(s, k) = t[k];
    values[s] = rotation(samples[s].first, samples[s].second);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  TrigForm form;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Eigen::VectorXd rhs(m);
      for (int s = 0; s < m; ++s) rhs[s] = values[s](i, j);
      const Eigen::VectorXd c = qr.solve(rhs);
      for (int k = 0; k < kNumTrigTerms; ++k) {
        const double r = std::round(c[k]);
        form.coeff[i][j][k] = static_cast<int>(r);
        form.max_rounding = std::max(form.max_rounding, std::abs(c[k] - r));
      }
    }
  }
  for (int s = 0; s < m; ++s) {
    form.max_error = std::max(
        form.max_error,
        (form.Evaluate(samples[s].first, samples[s].second) - values[s]).cwiseAbs().maxCoeff());
  }
  form.exact = form.max_error <= kExactForm;
  return form;
}

Eigen::Matrix3d EulerForm::Evaluate(double phi, double theta) const {
  return Rz(phi_sign * phi + phi_quarter_turns * M_PI / 2) * Ry(beta_quarter_turns * M_PI / 2) *
         Rx(theta_sign * theta + theta_quarter_turns * M_PI / 2);
}

std::string EulerForm::ToString() const {
  return "Rz(" + AngleTerm(phi_sign, "phi", phi_quarter_turns) + ") Ry(" +
         QuarterTurns(beta_quarter_turns) + ") Rx(" +
         AngleTerm(theta_sign, "theta", theta_quarter_turns) + ")";
}

std::optional<EulerForm> RecogniseEulerForm(const TrigForm& form) {
  if (!form.exact) return std::nullopt;
  // The 256 candidate forms in preference order, computed once.
  static const std::vector<std::pair<EulerForm, TrigForm>> candidates = [] {
    std::vector<std::pair<EulerForm, TrigForm>> c;
    const int ks[4] = {0, 1, -1, 2};
    for (int k1 : ks) {
      for (int k2 : ks) {
        for (int k3 : ks) {
          for (int s1 : {-1, 1}) {
            for (int s3 : {-1, 1}) {
              const EulerForm e{s1, k1, k2, s3, k3};
              c.emplace_back(e, FitTrigForm([&](double p, double t) { return e.Evaluate(p, t); }));
            }
          }
        }
      }
    }
    return c;
  }();
  for (const auto& [e, f] : candidates) {
    if (f == form) return e;
  }
  return std::nullopt;
}

SimplifiedModel Simplify(const InstrumentModel& model, int camera_zoom) {
  SimplifiedModel out;
  out.model = SnapModel(model, &out.notes);
  const InstrumentModel& m = out.model;
  if (camera_zoom >= m.NumZooms()) {
    throw std::out_of_range("Simplify: zoom " + std::to_string(camera_zoom) +
                            " is not in the model (it has " + std::to_string(m.NumZooms()) +
                            " zoom levels)");
  }
  out.rotation = FitTrigForm([&](double phi, double theta) {
    return camera_zoom < 0 ? RefFromEdm(m, phi, theta).rotation
                           : RefFromCam(m, camera_zoom, phi, theta).rotation;
  });
  out.euler = RecogniseEulerForm(out.rotation);
  out.notes.push_back(std::string("M_B,T rotation (") +
                      (camera_zoom < 0 ? "EDM" : "camera zoom " + std::to_string(camera_zoom)) +
                      "):\n" + out.rotation.ToString());
  out.notes.push_back(out.euler ? "M_B,T = " + out.euler->ToString() + " (Eq. 91 form)"
                                : "M_B,T has no Rz(+-phi) Ry Rx(+-theta) form");
  return out;
}

}  // namespace rtscalib
