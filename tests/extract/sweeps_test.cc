#include "libcalib/extract/sweeps.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>

#include "tests/extract/extract_fixture.h"

namespace rtscalib {
namespace {

using fixture::PaperPlan;
using fixture::PaperPlanRecords;

const InstrumentModel kIdeal = IdealModel(Kinematics::kDh, 2, CameraTool{});

TEST(FindPrincipalPoints, FromIntrinsicsOrDetected) {
  PaperPlan plan;
  plan.zooms = {0, 1};
  const auto records = PaperPlanRecords(kIdeal, plan);
  CameraTool given;
  given.intrinsics = {900, 900, 600, 400};
  const auto pp = FindPrincipalPoints(records, {given}, ExtractOptions());
  ASSERT_EQ(pp.size(), 2u);
  ASSERT_TRUE(pp[0] && pp[1]);
  EXPECT_FALSE(pp[0]->detected);
  EXPECT_EQ(pp[0]->pixel, Eigen::Vector2d(600, 400));  // the configured one wins
  // Zoom 1: c, c + [1, 0], c + [0, 1] are equally frequent; c is the one
  // whose +1 px neighbours exist.
  EXPECT_TRUE(pp[1]->detected);
  EXPECT_EQ(pp[1]->pixel, Eigen::Vector2d(640, 480));
  EXPECT_TRUE(FindPrincipalPoints({}, {}, ExtractOptions()).empty());
}

// A mistyped zoom must not size the result (2147483647 + 1 overflowed an int
// and a zoom of 1e6 allocated a camera per level): the levels are bounded by
// the data, and the message names the row.
TEST(FindPrincipalPoints, ZoomFarBeyondTheDataIsAnError) {
  auto records = PaperPlanRecords(kIdeal);
  for (size_t i = 0; i < records.size(); ++i) records[i].line = static_cast<int>(i) + 2;
  Record& cam = *std::find_if(records.begin(), records.end(),
                              [](const Record& r) { return r.tool == Tool::kCam; });
  for (int zoom : {1000000, std::numeric_limits<int>::max()}) {
    cam.zoom = zoom;
    try {
      FindPrincipalPoints(records, {}, ExtractOptions());
      FAIL() << "no ExtractionError for zoom " << zoom;
    } catch (const ExtractionError& e) {
      EXPECT_EQ(std::string(e.what()), "zoom " + std::to_string(zoom) + " on line " +
                                           std::to_string(cam.line) +
                                           ", but the data hold 2 zoom level(s); zoom levels "
                                           "are 0..N-1 (SPEC 2)");
    }
  }
}

// Rows elsewhere in the image (a grid pixel at more poses than the triplet)
// do not fool the detection: triplet centres come first.
TEST(FindPrincipalPoints, TripletCentreBeatsMoreFrequentGridPixels) {
  auto records = PaperPlanRecords(kIdeal);
  for (int i = 0; i < 200; ++i) {
    Record r;
    r.tool = Tool::kCam;
    r.phi = 0.01 * i;
    r.theta = 1.0;
    r.u = 128.0;
    r.v = 96.0;
    r.x = PredictCam(kIdeal, 0, r.phi, r.theta, r.u, r.v, 1.0);
    records.push_back(r);
  }
  const auto pp = FindPrincipalPoints(records, {}, ExtractOptions());
  ASSERT_EQ(pp.size(), 1u);
  EXPECT_EQ(pp[0]->pixel, Eigen::Vector2d(640, 480));
}

TEST(FindSweeps, FindsBothJointsAndCountsExclusions) {
  const auto records = PaperPlanRecords(kIdeal);
  const auto pp = FindPrincipalPoints(records, kIdeal.cams, ExtractOptions());
  const SweepSearch s = FindSweeps(records, pp, ExtractOptions());
  ASSERT_TRUE(s.joint1 && s.joint2);
  EXPECT_EQ(s.joint1->tool, Tool::kEdm);
  EXPECT_EQ(s.joint1->d, 1.0);  // the smallest distance
  EXPECT_EQ(s.joint1->NumPoints(), 15);
  EXPECT_EQ(s.joint2->NumPoints(), 10);
  EXPECT_EQ(s.excluded.critical_zenith, 25);
  EXPECT_EQ(s.excluded.face2, 0);
  // Controls in increasing order.
  for (int i = 1; i < s.joint1->NumPoints(); ++i) {
    EXPECT_GT(s.joint1->Control(records, i), s.joint1->Control(records, i - 1));
  }
  // Candidates: per joint, EDM at 1 and 2 m and the three camera pixels.
  int per_joint[3] = {0, 0, 0};
  for (const Sweep& c : s.candidates) ++per_joint[c.joint];
  EXPECT_EQ(per_joint[1], 5);
  EXPECT_EQ(per_joint[2], 5);
  EXPECT_EQ(s.joint1->Describe(records),
            "joint-1 sweep (face 1, edm, d = 1 m, theta = 1.5708 rad constant, 15 points, "
            "lines 2-72, set 'sweep1')");
}

// Readings that wrap around 2 pi and repeated readings are one control value.
TEST(FindSweeps, PhiWrapsAndRepeatsCollapse) {
  std::vector<Record> records;
  for (double phi : {0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 2 * M_PI - 1e-6, 1.0 + 1e-6}) {
    Record r;
    r.phi = phi;
    r.theta = 1.2;
    r.x = PredictEdm(kIdeal, phi, 1.2, 1.0);
    records.push_back(r);
  }
  const SweepSearch s = FindSweeps(records, {}, ExtractOptions());
  ASSERT_TRUE(s.joint1);
  EXPECT_EQ(s.joint1->NumPoints(), 6);
  EXPECT_FALSE(s.joint2);
}

// The hint decides between otherwise equal candidates; the choice order puts
// EDM before camera rows and small distances first.
TEST(FindSweeps, HintAndPreferenceOrder) {
  PaperPlan plan;
  plan.edm = false;
  auto records = PaperPlanRecords(kIdeal, plan);
  // Another joint-1 sweep at theta = 1.2, labelled, with as many points.
  PaperPlan other = plan;
  other.sweep1_theta = 1.2;
  for (Record r : PaperPlanRecords(kIdeal, other)) {
    if (r.set != "sweep1") continue;
    r.set = "extra";
    records.push_back(r);
  }
  const auto pp = FindPrincipalPoints(records, kIdeal.cams, ExtractOptions());
  SweepSearch s = FindSweeps(records, pp, ExtractOptions());
  ASSERT_TRUE(s.joint1);
  EXPECT_EQ(s.joint1->tool, Tool::kCam);
  EXPECT_EQ(s.joint1->pixel_offset, Eigen::Vector2d::Zero());
  EXPECT_EQ(s.joint1->set, "sweep1");
  ExtractOptions hint_extra;
  hint_extra.joint1_set_hint = "extra";
  s = FindSweeps(records, pp, hint_extra);
  EXPECT_NEAR(s.joint1->constant_control, 1.2, 1e-15);
  // Without hints, sin(theta) prefers theta = pi/2 (the larger circle).
  hint_extra.joint1_set_hint = "";
  s = FindSweeps(records, pp, hint_extra);
  EXPECT_NEAR(s.joint1->constant_control, M_PI / 2, 1e-15);
}

TEST(IsUsableForExtraction, FaceAndZenithLimits) {
  ExtractOptions o;
  Record r;
  r.theta = 0.5;
  EXPECT_TRUE(IsUsableForExtraction(r, o));
  r.theta = 0.1;  // < 10 deg
  EXPECT_FALSE(IsUsableForExtraction(r, o));
  r.theta = 2.4;  // > 135 deg
  EXPECT_FALSE(IsUsableForExtraction(r, o));
  r.theta = 2 * M_PI - 0.5;
  r.face = 2;
  EXPECT_FALSE(IsUsableForExtraction(r, o));
}

}  // namespace
}  // namespace rtscalib
