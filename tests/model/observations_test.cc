#include "libcalib/model/observations.h"

#include <gtest/gtest.h>

#include "libcalib/model/instrument.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// The observation structs are plain data; what matters is that a
// default-constructed row is a valid SPEC 3 row (face in {1, 2}, zoom >= 0,
// d > 0) and says it did not come from a file, so that code building rows by
// hand (simulator, tests) never makes rows that the CSV reader would reject.
TEST(Observations, DefaultRecordIsAValidFaceOneEdmRow) {
  const Record r;
  EXPECT_EQ(r.face, 1);
  EXPECT_EQ(r.zoom, 0);
  EXPECT_EQ(r.tool, Tool::kEdm);
  EXPECT_GT(r.d, 0.0) << "SPEC 3: d <= 0 is an error";
  EXPECT_EQ(r.x, Eigen::Vector3d::Zero());
  EXPECT_TRUE(r.set.empty());
  EXPECT_EQ(r.line, 0) << "0 = not from a file";
}

TEST(Observations, DefaultPixelObservationIsAValidFaceOneRow) {
  const PixelObservation p;
  EXPECT_EQ(p.face, 1);
  EXPECT_EQ(p.zoom, 0);
  EXPECT_GE(p.corner, 0);
  EXPECT_LE(p.corner, 3) << "SPEC 3: corner index 0..3 for a tag";
  EXPECT_EQ(p.X, Eigen::Vector3d::Zero());
  EXPECT_EQ(p.uv, Eigen::Vector2d::Zero());
  EXPECT_EQ(p.line, 0);
}

TEST(Observations, DefaultSourcesNameTheFilesForMessages) {
  const Observations obs;
  EXPECT_TRUE(obs.records.empty());
  EXPECT_TRUE(obs.pixels.empty());
  EXPECT_EQ(obs.records_source, "records");
  EXPECT_EQ(obs.pixels_source, "pixels");
}

TEST(Observations, RecordsOfBothFacesOfOnePointingAgree) {
  // A face-1 record and its face-2 twin (SPEC 1: every record carries its
  // face explicitly) observe the same point under the ideal instrument: the
  // fields carry all the model needs. Tolerance: round-off of a few
  // rotations of a 3 m vector, 1e-12 m.
  const InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, CameraTool{});
  Record r1;
  r1.phi = 0.7;
  r1.theta = 1.2;
  r1.d = 3.0;
  r1.x = PredictEdm(m, r1.phi, r1.theta, r1.d);
  Record r2 = r1;
  r2.face = 2;
  OtherFace(r1.phi, r1.theta, &r2.phi, &r2.theta);
  EXPECT_EQ(FaceOf(r2.theta), r2.face);
  EXPECT_LT((PredictEdm(m, r2.phi, r2.theta, r2.d) - r1.x).norm(), 1e-12);
}

}  // namespace
}  // namespace rtscalib
