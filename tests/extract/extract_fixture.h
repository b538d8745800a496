// Test fixture of the extraction tests: truth models and noise-free records of
// Klug's acquisition plan, made directly with PredictEdm/PredictCam
// (libcalib/model/kinematics.h) so that these tests do not depend on the
// simulator (libcalib/sim), which has its own tests.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "libcalib/geometry/rotation.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/model/observations.h"

namespace rtscalib::fixture {

// Klug Sec. 4 plan: sweep1 theta = pi/2, phi = 2 pi k / n (k < n); sweep2
// phi = phi2, theta = pi k / (n - 1) (k <= n - 1); at each pose EDM at every
// distance, camera rays of length cam_d at c, c + [1, 0], c + [0, 1].
struct PaperPlan {
  int sweep_points = 15;
  std::vector<double> edm_distances{1.0, 2.0};
  double cam_d = 1.0;
  std::vector<int> zooms{0};
  double sweep1_theta = M_PI / 2;
  double sweep2_phi = 0.0;
  bool edm = true;
  bool cam = true;
  bool labels = true;
};

inline void AddPose(const InstrumentModel& m, const PaperPlan& plan, double phi, double theta,
                    const std::string& set, std::vector<Record>* out) {
  if (plan.edm) {
    for (double d : plan.edm_distances) {
      Record r;
      r.face = 1;
      r.phi = phi;
      r.theta = theta;
      r.tool = Tool::kEdm;
      r.d = d;
      r.x = PredictEdm(m, phi, theta, d);
      r.set = plan.labels ? set : "";
      out->push_back(r);
    }
  }
  if (plan.cam) {
    for (int z : plan.zooms) {
      const auto& k = m.cams[z].intrinsics;
      for (const auto& off : {std::pair<double, double>{0, 0}, {1, 0}, {0, 1}}) {
        Record r;
        r.face = 1;
        r.zoom = z;
        r.phi = phi;
        r.theta = theta;
        r.tool = Tool::kCam;
        r.u = k[2] + off.first;
        r.v = k[3] + off.second;
        r.d = plan.cam_d;
        r.x = PredictCam(m, z, phi, theta, r.u, r.v, r.d);
        r.set = plan.labels ? set : "";
        out->push_back(r);
      }
    }
  }
}

inline std::vector<Record> PaperPlanRecords(const InstrumentModel& m,
                                            const PaperPlan& plan = PaperPlan()) {
  std::vector<Record> out;
  const int n = plan.sweep_points;
  for (int k = 0; k < n; ++k) AddPose(m, plan, 2 * M_PI * k / n, plan.sweep1_theta, "sweep1", &out);
  for (int k = 0; k < n; ++k) AddPose(m, plan, plan.sweep2_phi, M_PI * k / (n - 1), "sweep2", &out);
  for (size_t i = 0; i < out.size(); ++i) out[i].line = static_cast<int>(i) + 2;  // after a header
  return out;
}

// A truth near the ideal instrument (IdealModel, Klug Eq. 85-88): every DH
// offset and tool translation uniform in +-offset_m, every angle perturbed
// uniformly in +-angle_rad, the base anywhere within +-2 m and turned by any
// angle about the vertical. Cameras: 1280 x 960 px, f = 1000 px.
inline InstrumentModel RandomTruth(std::mt19937& rng, double offset_m, double angle_rad,
                                   int num_zooms = 1) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto off = [&] { return offset_m * u(rng); };
  auto ang = [&] { return angle_rad * u(rng); };
  InstrumentModel m = IdealModel(Kinematics::kDh, num_zooms, CameraTool{});
  const Eigen::Vector3d small_base(ang(), ang(), M_PI * u(rng));
  const Eigen::Vector3d base_t = 2.0 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  m.base = PoseBlock::FromRigid({Rx(M_PI) * RotationFromEuler<double>(small_base), base_t});
  m.links[0].p = {off(), -M_PI / 2 + ang(), M_PI / 2 + ang(), off()};
  m.links[1].p = {off(), ang(), ang(), off()};
  auto tool = [&] {
    const Eigen::Matrix3d ideal = Rz(M_PI) * Ry(M_PI / 2) * Rx(-M_PI / 2);
    return PoseBlock::FromRigid(
        {ideal * RotationFromEuler<double>(Eigen::Vector3d(ang(), ang(), ang())),
         Eigen::Vector3d(off(), off(), off())});
  };
  m.edm = tool();
  for (auto& c : m.cams) c.flange_from_cam = tool();
  return m;
}

// Klug Tables 6/7 (the optimised PLT 300), one camera.
inline InstrumentModel Plt300Truth() {
  InstrumentModel m = IdealModel(Kinematics::kDh, 1, CameraTool{});
  m.base = PoseBlock::FromRigid(
      Rigid3::FromEuler({3.1416, 0.0, 0.0504}, {5.915e-9, 7.216e-9, 3.312e-9}));
  // DhLink order {d, gamma_offset, alpha, a}.
  m.links[0].p = {0.0, -1.5203, 1.570808, 0.0};
  m.links[1].p = {0.0684e-3, -0.4432e-3, 0.2055e-3, -0.1117e-3};
  m.cams[0].flange_from_cam = PoseBlock::FromRigid(
      Rigid3::FromEuler({-1.4632, 1.5646, 3.2103}, {-0.1451e-3, -2.152e-9, 0.1505e-3}));
  m.edm = PoseBlock::FromRigid(
      Rigid3::FromEuler({-1.4219, 1.5693, 3.2910}, {0.1421e-3, 1.415e-6, -9.014e-5}));
  return m;
}

// Largest distance between truth and model predictions at held-out readings:
// other angles (uniform phi, theta in [0.05, pi - 0.05]), the given distance,
// and pixels spread over the image.
struct HeldOutError {
  double edm = 0.0;
  double cam = 0.0;
};
inline HeldOutError MaxHeldOutError(const InstrumentModel& truth, const InstrumentModel& model,
                                    double d, int samples = 200, unsigned seed = 99) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phi(0, 2 * M_PI), theta(0.05, M_PI - 0.05), f(0.05, 0.95);
  HeldOutError e;
  for (int i = 0; i < samples; ++i) {
    const double p = phi(rng), t = theta(rng);
    e.edm = std::max(e.edm, (PredictEdm(truth, p, t, d) - PredictEdm(model, p, t, d)).norm());
    for (int z = 0; z < truth.NumZooms(); ++z) {
      const double u = f(rng) * truth.cams[z].width, v = f(rng) * truth.cams[z].height;
      e.cam = std::max(
          e.cam,
          (PredictCam(truth, z, p, t, u, v, d) - PredictCam(model, z, p, t, u, v, d)).norm());
    }
  }
  return e;
}

}  // namespace rtscalib::fixture
