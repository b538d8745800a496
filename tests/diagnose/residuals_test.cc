#include "libcalib/diagnose/residuals.h"

#include <gtest/gtest.h>

#include <cmath>

#include "libcalib/fit/refine.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// Small angular offsets a, b (rad) turn into the components to first order;
// the neglected terms are ~a^2 relative. With a, b = 1e-5 rad: 1e-5 relative,
// so 1e-3 of the offset is a safe tolerance that still fails for a wrong
// sign, a wrong component or a wrong scale (sin z, d).
constexpr double kOffset = 1e-5;
constexpr double kFirstOrder = 1e-3 * kOffset;

Record EdmRecord(const InstrumentModel& m, int face, double phi, double theta, double d) {
  Record r;
  r.face = face;
  r.phi = phi;
  r.theta = theta;
  r.d = d;
  r.x = PredictEdm(m, phi, theta, d);
  return r;
}

TEST(ObservationResiduals, EdmRowSplitsIntoAlongHzAndZenith) {
  // Ideal instrument (SPEC 1): a point measured at the direction (Hz + a,
  // z + b) and distance d + c gives along = c, dHz = a, dz = b, whatever d and
  // whichever face the reading is in (Hz and z are the ray's, not the reading's).
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  const double a = kOffset, b = -0.7 * kOffset, c = 3e-4;
  Observations obs;
  for (double theta : {0.6, M_PI / 2, 2.0}) {
    for (double d : {1.0, 25.0}) {
      const double phi = 1.1;
      Record r1 = EdmRecord(m, 1, phi, theta, d);
      r1.x = PredictEdm(m, phi + a, theta + b, d + c);
      obs.records.push_back(r1);
      // The same measured point read in face 2 (SPEC 1).
      Record r2 = r1;
      r2.face = 2;
      OtherFace(phi, theta, &r2.phi, &r2.theta);
      obs.records.push_back(r2);
    }
  }
  const std::vector<ObservationResidual> res = ObservationResiduals(obs, m, FitOptions());
  ASSERT_EQ(res.size(), obs.records.size());
  for (size_t i = 0; i < res.size(); ++i) {
    const ObservationResidual& o = res[i];
    const Record& r = obs.records[i];
    ASSERT_TRUE(o.valid) << i;
    EXPECT_EQ(o.group, ObsGroup::kEdm);
    EXPECT_EQ(o.index, static_cast<int>(i));
    EXPECT_EQ(o.face, r.face);
    EXPECT_EQ(o.phi, r.phi);
    EXPECT_EQ(o.theta, r.theta);
    EXPECT_EQ(o.d, r.d);
    // delta = observed - model.
    EXPECT_LT((o.delta - (r.x - PredictEdm(m, r.phi, r.theta, r.d))).norm(), 1e-15 * r.d + 1e-15);
    EXPECT_NEAR(o.size, o.delta.norm(), 1e-18);
    // along: c, up to the chord's second-order part d (a^2 + b^2) / 2.
    EXPECT_NEAR(o.along, c, 1e-9 * r.d + 1e-12) << i;
    EXPECT_NEAR(o.hz, a, kFirstOrder) << "face " << r.face << " theta " << r.theta;
    EXPECT_NEAR(o.zenith, b, kFirstOrder) << "face " << r.face << " theta " << r.theta;
  }
}

TEST(ObservationResiduals, PixelRowsInImageAndAngularComponentsPerFace) {
  // SPEC 2: camera x = image +u, y = image +v. For the ideal coaxial camera
  // (SPEC 1: line-of-sight frame Rz(-phi) Rx(-theta)), +u in face 1 points
  // towards increasing Hz and +v towards increasing zenith; face 2 sees the
  // same direction with the image turned by 180 degrees, so the signs flip.
  // A pixel offset du gives an angle atan(du / f) ~ du / f, in Hz divided by
  // sin z (angle of arc -> horizontal angle).
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  const auto& k = m.cams[0].intrinsics;            // f = 1000 px
  const double f = k[0], du = 2e-2, dv = -1.5e-2;  // 2e-5 rad, -1.5e-5 rad
  const double phi = 0.4, theta = 1.2;
  Observations obs;
  for (int face : {1, 2}) {
    PixelObservation p;
    p.face = face;
    p.phi = phi;
    p.theta = theta;
    if (face == 2) OtherFace(phi, theta, &p.phi, &p.theta);
    p.X = PredictEdm(m, phi, theta, 5.0);  // on the optical axis: predicted at (cx, cy)
    p.uv = Eigen::Vector2d(k[2] + du, k[3] + dv);
    p.shot = "s" + std::to_string(face);
    obs.pixels.push_back(p);
  }
  const std::vector<ObservationResidual> res = ObservationResiduals(obs, m, FitOptions());
  ASSERT_EQ(res.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const ObservationResidual& o = res[i];
    ASSERT_TRUE(o.valid);
    EXPECT_EQ(o.group, ObsGroup::kPixel);
    EXPECT_EQ(o.index, i);
    EXPECT_EQ(o.d, 0.0);
    // delta = (du, dv, 0) px: observed minus predicted; the prediction of a
    // point on the axis is the principal point to round-off (f * 1e-16).
    EXPECT_NEAR(o.delta.x(), du, 1e-9);
    EXPECT_NEAR(o.delta.y(), dv, 1e-9);
    EXPECT_EQ(o.delta.z(), 0.0);
    EXPECT_NEAR(o.size, std::hypot(du, dv), 1e-9);
    const double sign = i == 0 ? 1.0 : -1.0;
    EXPECT_NEAR(o.hz, sign * du / f / std::sin(theta), 1e-3 * du / f) << "face " << i + 1;
    EXPECT_NEAR(o.zenith, sign * dv / f, 1e-3 * std::abs(dv) / f) << "face " << i + 1;
  }
}

// A camera on its own (Kinematics::kNone): its frame, z along the optical
// axis, is the reference, so it has no horizontal direction or zenith angle.
// Taking the optical axis for the vertical would divide the horizontal
// component by sin(angle off the axis): 0.2 px at 10 px from the principal
// point of a 1000 px lens would read 0.2 / 10 rad, 4,000", in place of 41".
// The residual is the pixel one.
TEST(ObservationResiduals, ACameraOnItsOwnHasPixelResidualsAndNoAngles) {
  CameraTool cam;
  const InstrumentModel m = IdealModel(Kinematics::kNone, 1, cam);
  const auto& k = m.cams[0].intrinsics;
  Observations obs;
  PixelObservation p;
  p.X = Eigen::Vector3d(10.0 / k[0], 0.0, 1.0);  // 10 px right of the principal point at 1 m
  p.uv = Eigen::Vector2d(k[2] + 10.0 + 0.2, k[3] - 0.1);
  obs.pixels.push_back(p);
  const std::vector<ObservationResidual> res = ObservationResiduals(obs, m, FitOptions());
  ASSERT_EQ(res.size(), 1u);
  const ObservationResidual& o = res[0];
  ASSERT_TRUE(o.valid);
  EXPECT_NEAR(o.image_delta.x(), 0.2, 1e-9);
  EXPECT_NEAR(o.image_delta.y(), -0.1, 1e-9);
  EXPECT_NEAR(o.image_radius, std::hypot(10.2, 0.1), 1e-9);
  EXPECT_TRUE(std::isnan(o.hz));
  EXPECT_TRUE(std::isnan(o.zenith));
}

TEST(ObservationResiduals, CameraRecordsAndInvalidRows) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  Observations obs;
  Record cam;
  cam.tool = Tool::kCam;
  cam.phi = 2.0;
  cam.theta = 1.0;
  cam.u = 700;
  cam.v = 400;
  cam.d = 3.0;
  cam.x = PredictCam(m, 0, cam.phi, cam.theta, cam.u, cam.v, cam.d) + Eigen::Vector3d(0, 0, 1e-4);
  obs.records.push_back(cam);
  Record bad = cam;
  bad.zoom = 4;  // no such zoom level
  obs.records.push_back(bad);
  PixelObservation behind;
  behind.phi = 0.0;
  behind.theta = M_PI / 2;
  behind.X = Eigen::Vector3d(0, -5, 0);  // behind the camera looking at +y
  obs.pixels.push_back(behind);
  const auto res = ObservationResiduals(obs, m, FitOptions());
  ASSERT_EQ(res.size(), 3u);
  EXPECT_EQ(res[0].group, ObsGroup::kCam);
  EXPECT_TRUE(res[0].valid);
  EXPECT_EQ(res[0].u, 700);
  EXPECT_EQ(res[0].v, 400);
  EXPECT_LT((res[0].delta - Eigen::Vector3d(0, 0, 1e-4)).norm(), 1e-15 * 3 + 1e-15);
  // The ray through (700, 400): its unit direction's z component is the
  // along part of a vertical 0.1 mm error.
  const Eigen::Vector3d dir =
      (cam.x - Eigen::Vector3d(0, 0, 1e-4) - RefFromCam(m, 0, cam.phi, cam.theta).translation)
          .normalized();
  EXPECT_NEAR(res[0].along, 1e-4 * dir.z(), 1e-15);
  EXPECT_FALSE(res[1].valid);
  EXPECT_EQ(res[2].group, ObsGroup::kPixel);
  EXPECT_FALSE(res[2].valid);
}

TEST(ObservationResiduals, CriticalRowsAreMarkedWithTheFitsLimits) {
  // SPEC 1: zenith angles outside [min, max] and their face-2 mirrors.
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  FitOptions fit;
  fit.critical_region.min_zenith_rad = 0.3;
  fit.critical_region.max_zenith_rad = 2.0;
  Observations obs;
  for (double theta : {0.1, 1.0, 2.5}) {
    obs.records.push_back(EdmRecord(m, 1, 0.5, theta, 2.0));
    Record r2 = obs.records.back();
    r2.face = 2;
    OtherFace(0.5, theta, &r2.phi, &r2.theta);
    obs.records.push_back(r2);
  }
  const auto res = ObservationResiduals(obs, m, fit);
  const bool expected[6] = {true, true, false, false, true, true};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(res[i].critical, expected[i]) << i;
    EXPECT_TRUE(res[i].valid) << "critical rows are still evaluated";
  }
}

// The calibration's one residual table: every row as given, what a figure
// or a file needs, and why a row is not fitted.
TEST(ResidualTable, EveryRowAsGivenWithWhatAPictureNeeds) {
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  const auto& k = m.cams[0].intrinsics;  // f = 1000 px, principal point (640, 480)
  FitOptions fit;
  fit.critical_region.min_zenith_rad = 0.3;
  fit.critical_region.max_zenith_rad = 2.0;
  Observations obs;
  obs.records.push_back(EdmRecord(m, 1, 0.5, 1.0, 2.0));
  obs.records.back().x += Eigen::Vector3d(3e-5, 0, 4e-5);  // |r| = 5e-5 m
  obs.records.push_back(EdmRecord(m, 1, 0.5, 0.1, 2.0));   // critical region
  obs.records.push_back(EdmRecord(m, 1, 0.7, 1.2, 3.0));   // taken out as gross
  PixelObservation p;
  p.phi = 0.4;
  p.theta = 1.2;
  p.shot = "s7";
  p.placement = "left";
  p.target = 12;
  p.corner = 3;
  p.line = 9;
  p.X = PredictEdm(m, p.phi, p.theta, 5.0);        // on the optical axis, 5 m from the camera
  p.uv = Eigen::Vector2d(k[2] + 0.3, k[3] - 0.4);  // |r| = 0.5 px
  obs.pixels.push_back(p);
  FitSummary summary;
  summary.sigma_edm_m = 2e-5;
  summary.sigma_pixel_px = 0.25;
  summary.sigma_pixel_px_zoom = {0.5};
  ExcludedRow gross;
  gross.index = 2;
  gross.line = 17;
  gross.reason = "point 1 m from its distance";

  const std::vector<ObservationResidual> t = ResidualTable(obs, m, fit, summary, {gross});
  ASSERT_EQ(t.size(), 4u);
  EXPECT_EQ(t[0].status, ResidualStatus::kFitted);
  EXPECT_TRUE(t[0].reason.empty());
  EXPECT_EQ(t[1].status, ResidualStatus::kCriticalRegion);
  EXPECT_FALSE(t[1].reason.empty());
  EXPECT_EQ(t[2].status, ResidualStatus::kGrossError);
  EXPECT_EQ(t[2].reason, gross.reason);
  // Records: observed and predicted point, the group's sigma, |r| / sigma;
  // round-off of a 2 m point ~1e-15 m.
  EXPECT_LT((t[0].observed - obs.records[0].x).norm(), 1e-15);
  EXPECT_LT((t[0].predicted - PredictEdm(m, 0.5, 1.0, 2.0)).norm(), 1e-15);
  EXPECT_EQ(t[0].sigma, 2e-5);
  EXPECT_NEAR(t[0].normalised, 2.5, 1e-9);
  EXPECT_TRUE(std::isnan(t[0].image_delta.x())) << "no image residual for an EDM row";
  // The pixel row: where it came from, its zoom's sigma, the pixel residual
  // and the variables of the diagnosis. The prediction of a point on the
  // axis is the principal point to round-off (f * 1e-16).
  const ObservationResidual& px = t[3];
  EXPECT_EQ(px.status, ResidualStatus::kFitted);
  EXPECT_EQ(px.shot, "s7");
  EXPECT_EQ(px.placement, "left");
  EXPECT_EQ(px.target, 12);
  EXPECT_EQ(px.corner, 3);
  EXPECT_EQ(px.line, 9);
  EXPECT_EQ(px.sigma, 0.5);
  EXPECT_NEAR(px.normalised, 1.0, 1e-9);
  EXPECT_NEAR(px.predicted.x(), k[2], 1e-9);
  EXPECT_NEAR(px.predicted.y(), k[3], 1e-9);
  EXPECT_NEAR(px.image_delta.x(), 0.3, 1e-9);
  EXPECT_NEAR(px.image_delta.y(), -0.4, 1e-9);
  EXPECT_NEAR(px.image_radius, 0.5, 1e-9);
  EXPECT_NEAR(px.target_distance, 5.0, 1e-9);  // the ideal camera sits at the origin
  EXPECT_STREQ(ResidualStatusName(ResidualStatus::kGrossError), "gross_error");
}

TEST(ResidualTable, CameraRecordsCarryTheirPixelResidual) {
  // A cam record whose point is seen 0.2 px right of where it was read:
  // observed (u, v) minus the projection of its point is (-0.2, 0).
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  Record cam;
  cam.tool = Tool::kCam;
  cam.phi = 2.0;
  cam.theta = 1.0;
  cam.u = 700;
  cam.v = 400;
  cam.d = 3.0;
  cam.x = PredictCam(m, 0, cam.phi, cam.theta, cam.u + 0.2, cam.v, cam.d);
  Observations obs;
  obs.records.push_back(cam);
  const auto t = ResidualTable(obs, m, FitOptions(), FitSummary(), {});
  ASSERT_EQ(t.size(), 1u);
  // Back-projection and projection agree to ~1e-9 px (the undistortion's
  // iteration is exact without distortion).
  EXPECT_NEAR(t[0].image_delta.x(), -0.2, 1e-6);
  EXPECT_NEAR(t[0].image_delta.y(), 0.0, 1e-6);
  EXPECT_NEAR(t[0].image_radius, std::hypot(700 - 640, 400 - 480), 1e-9);
  EXPECT_NEAR(t[0].target_distance, 3.0, 1e-9);
}

TEST(Where, NamesTheFileLineOrTheRow) {
  Observations obs;
  obs.records_source = "records.csv";
  obs.pixels_source = "simulated pixels";
  Record r;
  r.phi = M_PI / 6;
  r.theta = 80 * M_PI / 180;
  r.d = 2.0;
  r.line = 17;
  obs.records.push_back(r);
  r.line = 0;
  r.tool = Tool::kCam;
  r.face = 2;
  obs.records.push_back(r);
  PixelObservation p;
  p.shot = "img_004";
  p.target = 12;
  p.corner = 3;
  obs.pixels.push_back(p);

  const std::string a = Where(obs, ObsGroup::kEdm, 0);
  EXPECT_EQ(a.rfind("records.csv:17", 0), 0u) << a;
  EXPECT_NE(a.find("edm"), std::string::npos) << a;
  EXPECT_NE(a.find("phi 30.00 deg"), std::string::npos) << a;
  EXPECT_NE(a.find("theta 80.00 deg"), std::string::npos) << a;
  EXPECT_NE(a.find("d 2 m"), std::string::npos) << a;
  // Without a line: the 1-based row of the in-memory records.
  const std::string b = Where(obs, ObsGroup::kCam, 1);
  EXPECT_EQ(b.rfind("records.csv, row 2", 0), 0u) << b;
  EXPECT_NE(b.find("cam"), std::string::npos) << b;
  EXPECT_NE(b.find("face 2"), std::string::npos) << b;
  const std::string c = Where(obs, ObsGroup::kPixel, 0);
  EXPECT_EQ(c.rfind("simulated pixels, row 1", 0), 0u) << c;
  EXPECT_NE(c.find("shot img_004"), std::string::npos) << c;
  EXPECT_NE(c.find("target 12 corner 3"), std::string::npos) << c;
}

}  // namespace
}  // namespace rtscalib
