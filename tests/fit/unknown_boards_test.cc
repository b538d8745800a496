// SPEC 7: boards of unknown pose and points of unknown position estimated in
// the joint refinement. Simulated truth (tests/fit/joint_scene.h) whose
// boards lose their poses (pixels with X_known == false) plus prism points
// measured in both faces (records with `point`), noise on every observation:
//   - normalised errors (fit - truth) / sigma of the per-zoom intrinsics, the
//     camera tool translations, the board translations and the prism points
//     have a mean square in [0.5, 2] over the seeds (1 if the sigmas are
//     right);
//   - unknown board poses cost little accuracy against surveyed ones;
//   - what such data cannot determine is held and named.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <iostream>
#include <map>
#include <random>

#include "libcalib/fit/parameterization.h"
#include "libcalib/fit/refine.h"
#include "libcalib/fit/robust.h"
#include "libcalib/fit/unknowns.h"
#include "libcalib/model/kinematics.h"
#include "tests/fit/joint_scene.h"

namespace rtscalib {
namespace {

using testing_scene::DhTruth;
using testing_scene::PixelsOnly;

constexpr double kNoisePx = 0.3;
constexpr double kNoisePointM = 2e-4;

// A dh truth whose base frame is the ideal one (SPEC 7: with nothing known,
// the reference frame is the instrument's), so that board poses and points
// compare directly; without EDM effects (no EDM row has a known x, so they
// are held at zero).
InstrumentModel Truth() {
  InstrumentModel t = DhTruth(2);
  const InstrumentModel ideal = IdealModel(Kinematics::kDh, 0, CameraTool());
  t.base = ideal.base;
  t.links[0].p[kDhD] = ideal.links[0].p[kDhD];
  t.links[0].p[kDhGamma] = ideal.links[0].p[kDhGamma];
  for (Effect e : t.effects.List()) {
    if (IsKinematic(e) && Info(e).kind == EffectKind::kEdm) {
      t.effects.Remove(e);
      t.EffectValue(e) = {0, 0};
    }
  }
  return t;
}

// The reading (phi, theta, d) in `face` at which `model` measures x: Newton
// from the ideal instrument's reading (SPEC 1), numeric Jacobian.
Eigen::Vector3d ReadingOf(const InstrumentModel& model, const Eigen::Vector3d& x, int face) {
  const double d0 = x.norm();
  Eigen::Vector3d r(std::atan2(x.x(), x.y()), std::acos(x.z() / d0), d0);
  if (face == 2) OtherFace(r[0], r[1], &r[0], &r[1]);
  for (int it = 0; it < 20; ++it) {
    const Eigen::Vector3d f = PredictEdm(model, r[0], r[1], r[2]) - x;
    Eigen::Matrix3d j;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d h = r;
      h[k] += 1e-7;
      j.col(k) = (PredictEdm(model, h[0], h[1], h[2]) - x - f) / 1e-7;
    }
    r -= j.colPivHouseholderQr().solve(f);
  }
  return r;
}

// Prism points around the station, each measured twice in each face with
// noisy coordinates (the records' noise model: point_m per coordinate).
std::vector<Eigen::Vector3d> AddPrisms(const InstrumentModel& truth, std::uint64_t seed,
                                       Observations* obs) {
  const std::vector<Eigen::Vector3d> prisms = {
      {3.0, 4.0, 0.5}, {-9.0, 2.0, -1.0}, {1.0, -14.0, 2.0}, {20.0, 7.0, 1.5}};
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoisePointM);
  for (size_t p = 0; p < prisms.size(); ++p) {
    for (int face : {1, 2}) {
      for (int rep = 0; rep < 2; ++rep) {
        const Eigen::Vector3d seen =
            prisms[p] + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
        const Eigen::Vector3d r = ReadingOf(truth, seen, face);
        Record rec;
        rec.face = face;
        rec.tool = Tool::kEdm;
        rec.phi = r[0];
        rec.theta = r[1];
        rec.d = r[2];
        rec.point = "P" + std::to_string(p);
        rec.line = static_cast<int>(obs->records.size()) + 2;
        obs->records.push_back(rec);
      }
    }
  }
  return prisms;
}

// The boards lose their poses: their corners become unknowns (SPEC 7).
void ForgetBoardPoses(Observations* obs) {
  for (TagBoard& b : obs->targets.boards) b.pose_known = false;
  for (PixelObservation& p : obs->pixels) {
    p.X_known = false;
    p.X.setZero();
  }
}

struct Fitted {
  InstrumentModel model;
  FitSummary summary;
};

Fitted FitScene(const InstrumentModel& truth, std::uint64_t seed, bool boards_known,
                std::vector<Eigen::Vector3d>* prisms) {
  SimulationOptions o = PixelsOnly(truth, 3, seed, kNoisePx);
  SimulatedData data = Simulate(o);
  data.obs.records.clear();
  data.obs.targets = o.targets;
  if (!boards_known) {
    ForgetBoardPoses(&data.obs);
    *prisms = AddPrisms(truth, seed, &data.obs);
  }
  Fitted f;
  // The start of a good extraction (about 1 mm / 1 mrad off, effects zero),
  // with intrinsics a few pixels off.
  f.model = PerturbedStart(truth, seed, 1e-3);
  for (CameraTool& c : f.model.cams) {
    c.intrinsics[0] *= 1.01;
    c.intrinsics[1] *= 0.99;
    c.intrinsics[2] += 3;
    c.intrinsics[3] -= 2;
  }
  if (!boards_known) {
    // The EDM's translation along its ray is held (no EDM row has a known
    // x): its value is a convention the prisms' positions follow, so it is
    // the truth's here, as a user's would be the instrument's nominal offset.
    const Eigen::Vector3d ray = f.model.edm.ToRigid().rotation.col(2);
    int along = 0;
    ray.cwiseAbs().maxCoeff(&along);
    f.model.edm.t[along] = truth.edm.t[along];
  }
  FitOptions fo;
  fo.fit_intrinsics = true;
  fo.sigma_edm_m = kNoisePointM;
  fo.sigma_pixel_px = kNoisePx;
  f.summary = Refine(data.obs, fo, &f.model);
  return f;
}

TEST(UnknownBoards, NormalisedErrorsHaveUnitMeanSquare) {
  const InstrumentModel truth = Truth();
  constexpr int kSeeds = 5;
  double sum_sq = 0;
  int n = 0;
  std::map<std::string, std::pair<double, int>> by_kind;  // printed, for reading
  auto add = [&](double err, double sigma, const std::string& what) {
    ASSERT_GT(sigma, 0.0) << what;
    sum_sq += (err / sigma) * (err / sigma);
    ++n;
    by_kind[what].first += (err / sigma) * (err / sigma);
    ++by_kind[what].second;
  };
  for (int seed = 0; seed < kSeeds; ++seed) {
    std::vector<Eigen::Vector3d> prisms;
    const Fitted f = FitScene(truth, 300 + seed, false, &prisms);
    const InstrumentModel& m = f.model;
    ASSERT_TRUE(m.sigmas.valid) << f.summary.message;
    ASSERT_EQ(m.boards.size(), 4u);  // 2 zooms x 2 boards (ZoomScene)
    ASSERT_EQ(m.points.size(), prisms.size());
    for (int z = 0; z < m.NumZooms(); ++z) {
      for (int i = 0; i < 4; ++i) {
        add(m.cams[z].intrinsics[i] - truth.cams[z].intrinsics[i], m.sigmas.intrinsics[z][i],
            "intrinsics");
      }
      for (int i = 0; i < 3; ++i) {
        add(m.cams[z].flange_from_cam.t[i] - truth.cams[z].flange_from_cam.t[i],
            m.sigmas.cam_tools[z].t[i], "camera tool t");
      }
    }
    const TargetScene scene = ZoomScene(truth, 6, 8, 3.0);
    for (const EstimatedBoard& b : m.boards) {
      const TagBoard* tb = nullptr;
      for (const TagBoard& s : scene.boards) {
        if (s.first_id == b.board.first_id) tb = &s;
      }
      ASSERT_NE(tb, nullptr);
      for (int i = 0; i < 3; ++i) {
        add(b.pose.t[i] - tb->ref_from_board.translation[i], b.sigma.t[i], "board t");
      }
    }
    for (size_t p = 0; p < prisms.size(); ++p) {
      const EstimatedPoint* q = m.Point("P" + std::to_string(p));
      ASSERT_NE(q, nullptr);
      for (int i = 0; i < 3; ++i) add(q->x[i] - prisms[p][i], q->sigma[i], "prism");
    }
    // Held, named: the base (nothing has a known position) and the EDM
    // translation along its ray (no known distance).
    std::string gauges;
    for (const std::string& g : f.summary.fixed_gauges) gauges += g + "\n";
    EXPECT_NE(gauges.find("base pose held"), std::string::npos) << gauges;
    EXPECT_NE(gauges.find("(along the ray) held"), std::string::npos) << gauges;
  }
  const double mean_square = sum_sq / n;
  // ~190 normalised errors over 5 seeds, strongly correlated within a seed
  // (a board's translation and the camera tools share the pose errors): the
  // issue's bounds [0.5, 2] hold for right sigmas and catch a factor 1.4.
  std::cout << "mean square of normalised errors: " << mean_square << " (" << n << " values)\n";
  for (const auto& [kind, v] : by_kind) {
    std::cout << "  " << kind << ": " << v.first / v.second << " (" << v.second << ")\n";
  }
  EXPECT_GT(mean_square, 0.5);
  EXPECT_LT(mean_square, 2.0);
}

TEST(UnknownBoards, CostLittleAccuracyAgainstSurveyedBoards) {
  const InstrumentModel truth = Truth();
  std::vector<Eigen::Vector3d> prisms;
  const Fitted surveyed = FitScene(truth, 77, true, &prisms);
  const Fitted unknown = FitScene(truth, 77, false, &prisms);
  ASSERT_TRUE(surveyed.model.sigmas.valid && unknown.model.sigmas.valid);
  // The stated uncertainty of fx, fy, cx, cy (RMS over zooms) and the actual
  // RMS error, both ways.
  auto rms = [&](const InstrumentModel& m, bool sigma) {
    double s = 0;
    int n = 0;
    for (int z = 0; z < m.NumZooms(); ++z) {
      for (int i = 0; i < 4; ++i) {
        const double v = sigma ? m.sigmas.intrinsics[z][i]
                               : m.cams[z].intrinsics[i] - truth.cams[z].intrinsics[i];
        s += v * v;
        ++n;
      }
    }
    return std::sqrt(s / n);
  };
  const double sig_s = rms(surveyed.model, true), sig_u = rms(unknown.model, true);
  const double err_s = rms(surveyed.model, false), err_u = rms(unknown.model, false);
  std::cout << "intrinsics RMS sigma / error [px]: surveyed boards " << sig_s << " / " << err_s
            << ", unknown boards " << sig_u << " / " << err_u << "\n";
  // Each board is seen in 6 shots of ~190 corners: its 6 pose parameters
  // take little from ~2,300 pixel residuals, so the intrinsics' uncertainty
  // grows by well under a factor 2 (the planar-target calibration keeps the
  // focal length through the boards' perspective).
  EXPECT_LT(sig_u, 2.0 * sig_s);
  // Both fits agree with the truth within 4 stated sigmas (RMS over 8 values).
  EXPECT_LT(err_s, 4.0 * sig_s);
  EXPECT_LT(err_u, 4.0 * sig_u);
}

// The gross-error search evaluates its start with the boards' starting poses
// (as the refinement starts them): every corner of a board of unknown pose
// can be evaluated there, and a corner moved by 40 px (over 100 sigmas) is
// found and taken out.
TEST(UnknownBoards, GrossErrorSearchEvaluatesCornersOfUnknownBoards) {
  const InstrumentModel truth = Truth();
  SimulationOptions o = PixelsOnly(truth, 1, 9, kNoisePx);
  SimulatedData data = Simulate(o);
  data.obs.records.clear();
  data.obs.targets = o.targets;
  ForgetBoardPoses(&data.obs);
  const int planted = static_cast<int>(data.obs.pixels.size() / 2);
  data.obs.pixels[planted].uv.x() += 40;
  InstrumentModel m = PerturbedStart(truth, 9, 1e-3);
  FitOptions fo;
  fo.sigma_pixel_px = kNoisePx;
  GrossErrorOptions robust;
  const RobustFitResult r = FindGrossErrorsByFit(data.obs, fo, robust, &m, false);
  for (const std::string& note : r.notes) {
    EXPECT_EQ(note.find("cannot be evaluated at the start"), std::string::npos) << note;
  }
  bool found = false;
  for (const ExcludedRow& e : r.gross) found |= e.pixel && e.index == planted;
  EXPECT_TRUE(found) << r.gross.size() << " rows flagged";
}

// Corners of a target on no board are bad input, named by file and line.
TEST(UnknownBoards, PixelOfNoBoardIsAnError) {
  const InstrumentModel truth = Truth();
  SimulationOptions o = PixelsOnly(truth, 1, 5, 0.0);
  SimulatedData data = Simulate(o);
  data.obs.records.clear();
  data.obs.targets = o.targets;
  ForgetBoardPoses(&data.obs);
  data.obs.pixels[3].target = 99999;
  data.obs.pixels[3].line = 42;
  InstrumentModel m = truth;
  FitOptions fo;
  try {
    Refine(data.obs, fo, &m);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pixels:42"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("99999"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rtscalib
