#include "libcalib/extract/simplify.h"

#include <gtest/gtest.h>

#include <random>

#include "libcalib/extract/extract.h"
#include "libcalib/model/kinematics.h"
#include "tests/extract/extract_fixture.h"

namespace rtscalib {
namespace {

// Klug Tables 1 and 2: the extracted PLT 300 (values as printed).
InstrumentModel Tables1And2() {
  InstrumentModel m = IdealModel(Kinematics::kDh, 1, CameraTool{});
  m.links[0].p = {0.0, -1.5708, 1.5708, 0.0};  // {d, gamma_offset, alpha, a}
  m.links[1].p = {0.0, 0.0, 0.0, 0.0};
  m.base = PoseBlock::FromRigid(Rigid3::FromEuler({3.1416, 0.0, 0.0}, {0.0, 0.0, 0.0}));
  const Rigid3 tool = Rigid3::FromEuler({-1.5020, 1.5646, 3.2103}, {-0.0003, 0.0, 0.0003});
  m.edm = PoseBlock::FromRigid(tool);
  m.cams[0].flange_from_cam = PoseBlock::FromRigid(tool);
  return m;
}

// Klug Eq. 90.
Eigen::Matrix3d Eq90(double phi, double theta) {
  const double cp = std::cos(phi), sp = std::sin(phi), ct = std::cos(theta), st = std::sin(theta);
  Eigen::Matrix3d r;
  r << cp, ct * sp, sp * st, -sp, cp * ct, cp * st, 0, -st, ct;
  return r;
}

const char* const kEq90 =
    "[ cos(phi), sin(phi)*cos(theta), sin(phi)*sin(theta) ]\n"
    "[ -sin(phi), cos(phi)*cos(theta), cos(phi)*sin(theta) ]\n"
    "[ 0, -sin(theta), cos(theta) ]";

// Snapped transforms are products of exact quarter turns and of the joint
// rotations: entries are sums of a few unit-magnitude products, exact to a
// few 1e-16; 1e-12 is generous.
constexpr double kSimplifyExact = 1e-12;

TEST(Simplify, Tables1And2SnapToEq90) {
  for (int zoom : {-1, 0}) {  // EDM and camera tool (identical in Table 2)
    const SimplifiedModel s = Simplify(Tables1And2(), zoom);
    EXPECT_TRUE(s.rotation.exact);
    // Least squares on exact quarter-turn data: coefficients off by round-off.
    EXPECT_LT(s.rotation.max_rounding, 1e-9);
    EXPECT_EQ(s.rotation.ToString(), kEq90);
    ASSERT_TRUE(s.euler.has_value());
    EXPECT_EQ(s.euler->ToString(), "Rz(-phi) Ry(0) Rx(-theta)");  // Eq. 91
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> phi(0, 2 * M_PI), theta(0, M_PI);
    for (int i = 0; i < 100; ++i) {
      const double p = phi(rng), t = theta(rng);
      const Rigid3 tool = zoom < 0 ? RefFromEdm(s.model, p, t) : RefFromCam(s.model, 0, p, t);
      EXPECT_LT((tool.rotation - Eq90(p, t)).norm(), kSimplifyExact);
      EXPECT_LT(tool.translation.norm(), kSimplifyExact);
      EXPECT_LT((s.rotation.Evaluate(p, t) - Eq90(p, t)).norm(), kSimplifyExact);
      EXPECT_LT((s.euler->Evaluate(p, t) - Eq90(p, t)).norm(), kSimplifyExact);
    }
  }
}

// Snapping reproduces Eq. 85-88 parameter by parameter.
TEST(Simplify, SnappedParametersAreEq85To88) {
  const InstrumentModel m = SnapModel(Tables1And2());
  EXPECT_DOUBLE_EQ(m.links[0].p[kDhGamma], -M_PI / 2);  // Eq. 85
  EXPECT_DOUBLE_EQ(m.links[0].p[kDhAlpha], M_PI / 2);
  for (double v : m.links[1].p) EXPECT_EQ(v, 0.0);                   // Eq. 86
  EXPECT_LT((m.base.ToRigid().rotation - Rx(M_PI)).norm(), kSimplifyExact);  // Eq. 87
  EXPECT_LT((m.edm.ToRigid().rotation - Rz(M_PI) * Ry(M_PI / 2) * Rx(-M_PI / 2)).norm(),
            kSimplifyExact);  // Eq. 88
  EXPECT_EQ(m.edm.ToRigid().translation.norm(), 0.0);
}

// End to end: extract the PLT 300 of Tables 6/7, simplify, get Eq. 90.
TEST(Simplify, ExtractedPlt300SimplifiesToEq90) {
  const InstrumentModel truth = fixture::Plt300Truth();
  const ExtractionResult r = ExtractDhModel(fixture::PaperPlanRecords(truth), truth.cams);
  for (int zoom : {-1, 0}) {
    const SimplifiedModel s = Simplify(r.model, zoom);
    EXPECT_EQ(s.rotation.ToString(), kEq90) << zoom;
    ASSERT_TRUE(s.euler.has_value());
    EXPECT_EQ(s.euler->ToString(), "Rz(-phi) Ry(0) Rx(-theta)");
  }
}

TEST(Simplify, SnapRemovesKinematicEffectsAndKeepsDistortion) {
  InstrumentModel m = Tables1And2();
  m.effects.Add(Effect::kHzEccentricity);
  m.EffectValue(Effect::kHzEccentricity) = {1e-5, 2e-5};
  m.effects.Add(Effect::kRadialDistortion);
  std::vector<std::string> notes;
  const InstrumentModel s = SnapModel(m, &notes);
  EXPECT_FALSE(s.effects.Has(Effect::kHzEccentricity));
  EXPECT_TRUE(s.effects.Has(Effect::kRadialDistortion));
  EXPECT_EQ(s.EffectValue(Effect::kHzEccentricity)[0], 0.0);
  EXPECT_GE(notes.size(), 5u);  // base, 2 links, edm, camera, effect
}

TEST(SnapToQuarterTurn, NearestMultipleOfHalfPi) {
  EXPECT_DOUBLE_EQ(SnapToQuarterTurn(1.5646), M_PI / 2);
  EXPECT_DOUBLE_EQ(SnapToQuarterTurn(3.2103), M_PI);
  EXPECT_DOUBLE_EQ(SnapToQuarterTurn(-1.5020), -M_PI / 2);
  EXPECT_DOUBLE_EQ(SnapToQuarterTurn(0.7), 0.0);
  EXPECT_DOUBLE_EQ(SnapToQuarterTurn(0.8), M_PI / 2);
  EXPECT_DOUBLE_EQ(SnapToQuarterTurn(-4.0), -M_PI * 1.5);
}

// An unsnapped rotation is not an integer trig form.
TEST(FitTrigForm, InexactForUnsnappedRotations) {
  const TrigForm f =
      FitTrigForm([](double p, double t) -> Eigen::Matrix3d { return Rz(-p + 0.05) * Rx(-t); });
  EXPECT_FALSE(f.exact);
  EXPECT_FALSE(RecogniseEulerForm(f).has_value());
}

// Integer trig forms that are not of the Eq. 91 shape are reported as such:
// Rz(phi) Rx(pi/2) Rz(theta) = Rz(phi) Ry(-theta) Rx(pi/2) turns theta about y.
TEST(FitTrigForm, RecognisesOnlyTheEq91Shape) {
  const TrigForm f = FitTrigForm(
      [](double p, double t) -> Eigen::Matrix3d { return Rz(p) * Rx(M_PI / 2) * Rz(t); });
  EXPECT_TRUE(f.exact);
  EXPECT_FALSE(RecogniseEulerForm(f).has_value());

  auto rotation = [](double p, double t) -> Eigen::Matrix3d {
    return Rz(p + M_PI / 2) * Ry(M_PI) * Rx(-t - M_PI / 2);
  };
  const TrigForm g = FitTrigForm(rotation);
  ASSERT_TRUE(g.exact);
  const auto e = RecogniseEulerForm(g);
  ASSERT_TRUE(e.has_value());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> a(-3, 3);
  for (int i = 0; i < 20; ++i) {
    const double p = a(rng), t = a(rng);
    EXPECT_LT((e->Evaluate(p, t) - rotation(p, t)).norm(), kSimplifyExact);
  }
  EXPECT_EQ(EulerForm({1, 1, 2, -1, -1}).ToString(), "Rz(phi + pi/2) Ry(pi) Rx(-theta - pi/2)");
}

TEST(TrigForm, ToStringWritesEveryTerm) {
  TrigForm f;
  f.coeff[0][0][0] = 1;
  f.coeff[0][0][8] = -1;
  f.coeff[1][1][3] = -2;
  EXPECT_EQ(f.ToString(),
            "[ 1 - sin(phi)*sin(theta), 0, 0 ]\n[ 0, -2*cos(theta), 0 ]\n[ 0, 0, 0 ]");
}

}  // namespace
}  // namespace rtscalib
