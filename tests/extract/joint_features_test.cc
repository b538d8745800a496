#include "libcalib/extract/joint_features.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/extract/extract_fixture.h"

namespace rtscalib {
namespace {

// A sweep over the given records (all of them, in the given order).
Sweep SweepOf(const std::vector<Record>& records, int joint) {
  Sweep s;
  s.joint = joint;
  for (int i = 0; i < static_cast<int>(records.size()); ++i) s.rows.push_back(i);
  return s;
}

std::vector<Record> EdmSweep(const InstrumentModel& m, const std::vector<double>& phis,
                             double theta, double d = 1.0) {
  std::vector<Record> out;
  for (double phi : phis) {
    Record r;
    r.phi = phi;
    r.theta = theta;
    r.d = d;
    r.x = PredictEdm(m, phi, theta, d);
    out.push_back(r);
  }
  return out;
}

const InstrumentModel kIdealOneZoom = IdealModel(Kinematics::kDh, 1, CameraTool{});

// Exact data, unit radius: the fits are exact to round-off (fits_test.cc).
constexpr double kJointExact = 1e-12;

TEST(AnalyseSweep, RevoluteJointGivesTheSignCorrectedAxis) {
  const auto records = EdmSweep(kIdealOneZoom, {0.0, 0.5, 1.0, 1.5, 2.0, 2.5}, M_PI / 2);
  const JointFeature f = AnalyseSweep(records, SweepOf(records, 1), ExtractOptions());
  EXPECT_EQ(f.trajectory, Trajectory::kCircle);
  EXPECT_EQ(f.num_points, 6);
  EXPECT_LT((f.axis - Eigen::Vector3d(0, 0, -1)).norm(), kJointExact);  // phi is clockwise
  EXPECT_LT(f.center.norm(), kJointExact);
  EXPECT_NEAR(f.radius, 1.0, kJointExact);
  EXPECT_LT(f.circle_rms, kJointExact);
  EXPECT_GT(f.line_rms, 0.1);
  EXPECT_NO_THROW(RequireRevolute(f, SweepOf(records, 1), records, ExtractOptions()));
}

// Footnote 6: only steps below pi decide the sign; a sweep whose one big
// step (3.5 rad) would flip Eq. 31 still gets the right axis.
TEST(AnalyseSweep, SignIgnoresStepsOfPiOrMore) {
  const auto records = EdmSweep(kIdealOneZoom, {0.0, 0.2, 3.7, 3.9, 4.1}, M_PI / 2);
  const JointFeature f = AnalyseSweep(records, SweepOf(records, 1), ExtractOptions());
  ASSERT_EQ(f.trajectory, Trajectory::kCircle);
  EXPECT_LT((f.axis - Eigen::Vector3d(0, 0, -1)).norm(), kJointExact);
  EXPECT_NE(f.sign_rows[0], 1);  // not the 0.2 -> 3.7 pair
}

TEST(AnalyseSweep, ClassifiesLineOnAxisAndNeither) {
  ExtractOptions options;
  // On axis: theta = 0 on the ideal instrument, every point the same.
  auto on_axis = EdmSweep(kIdealOneZoom, {0.0, 1.0, 2.0, 3.0, 4.0}, 0.0);
  EXPECT_EQ(AnalyseSweep(on_axis, SweepOf(on_axis, 1), options).trajectory, Trajectory::kOnAxis);
  // Line.
  auto line = on_axis;
  for (size_t i = 0; i < line.size(); ++i) line[i].x = Eigen::Vector3d(0.1 * i, 0.2 * i, 1.0);
  const JointFeature fl = AnalyseSweep(line, SweepOf(line, 1), options);
  EXPECT_EQ(fl.trajectory, Trajectory::kLine);
  EXPECT_LT((fl.axis - Eigen::Vector3d(1, 2, 0).normalized()).norm(), kJointExact);
  // Neither: a circle with a 5 cm bump.
  auto bumpy = EdmSweep(kIdealOneZoom, {0.0, 0.7, 1.4, 2.1, 2.8, 3.5, 4.2}, M_PI / 2);
  bumpy[3].x.z() += 0.05;
  const JointFeature fn = AnalyseSweep(bumpy, SweepOf(bumpy, 1), options);
  EXPECT_EQ(fn.trajectory, Trajectory::kNeither);
  EXPECT_GT(fn.circle_rms, options.max_fit_rms_m);
  try {
    RequireRevolute(fn, SweepOf(bumpy, 1), bumpy, options);
    FAIL();
  } catch (const ExtractionError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("7 points"));
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("neither on a circle"));
  }
  EXPECT_STREQ(TrajectoryName(Trajectory::kOnAxis), "on axis");
}

}  // namespace
}  // namespace rtscalib
