#include "libcalib/export/urdf_export.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include "libcalib/model/kinematics.h"
#include "tests/export/export_fixture.h"

namespace rtscalib {
namespace {

// KDL's forward kinematics of the exported URDF from the root to `tip`.
class UrdfChain {
 public:
  UrdfChain(const KDL::Tree& tree, const std::string& tip) {
    EXPECT_TRUE(tree.getChain(kUrdfReferenceLink, tip, chain_)) << tip;
    EXPECT_EQ(chain_.getNrOfJoints(), 2u) << tip;
  }
  Rigid3 At(const std::array<double, 2>& q) const {
    KDL::ChainFkSolverPos_recursive fk(chain_);
    KDL::JntArray joints(2);
    joints(0) = q[0];
    joints(1) = q[1];
    KDL::Frame f;
    EXPECT_GE(fk.JntToCart(joints, f), 0);
    Rigid3 out;
    for (int i = 0; i < 3; ++i) {
      out.translation[i] = f.p(i);
      for (int j = 0; j < 3; ++j) out.rotation(i, j) = f.M(i, j);
    }
    return out;
  }

 private:
  KDL::Chain chain_;
};

// Angle of the rotation between two frames, and their origins' distance.
double AngleBetween(const Rigid3& a, const Rigid3& b) {
  return Eigen::AngleAxisd(a.rotation.transpose() * b.rotation).angle();
}
double Distance(const Rigid3& a, const Rigid3& b) { return (a.translation - b.translation).norm(); }

// Tolerances 1e-9 m and 1e-9 rad: the URDF holds the model's transforms in
// %.17g text and rpy extracted to rounding (~1e-15); KDL and rtscalib then
// multiply a handful of unit-magnitude matrices (~1e-15 each).
constexpr double kTolM = 1e-9, kTolRad = 1e-9;

void ExpectUrdfMatchesModel(const InstrumentModel& m, std::mt19937& rng, bool from_file) {
  const UrdfExport urdf = ExportUrdf(m);
  KDL::Tree tree;
  if (from_file) {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / "rtscalib_export_test";
    std::filesystem::create_directories(dir);
    const std::string path = (dir / "instrument.urdf").string();
    std::ofstream(path) << urdf.xml;
    ASSERT_TRUE(kdl_parser::treeFromFile(path, tree));
  } else {
    ASSERT_TRUE(kdl_parser::treeFromString(urdf.xml, tree)) << urdf.xml;
  }
  const UrdfChain edm(tree, kUrdfEdmLink);
  std::vector<UrdfChain> cams;
  for (int z = 0; z < m.NumZooms(); ++z) cams.emplace_back(tree, UrdfCameraLink(z));
  std::uniform_real_distribution<double> angle(0, 2 * M_PI);
  for (int i = 0; i < 200; ++i) {
    // Both faces and the critical regions too: the chain is exact everywhere.
    const double phi = angle(rng), theta = angle(rng);
    const std::array<double, 2> q = UrdfJointPositions(m, phi, theta);
    const Rigid3 want_edm = RefFromEdm(m, phi, theta), got_edm = edm.At(q);
    EXPECT_LT(Distance(got_edm, want_edm), kTolM) << phi << " " << theta;
    EXPECT_LT(AngleBetween(got_edm, want_edm), kTolRad) << phi << " " << theta;
    for (int z = 0; z < m.NumZooms(); ++z) {
      const Rigid3 want = RefFromCam(m, z, phi, theta), got = cams[z].At(q);
      EXPECT_LT(Distance(got, want), kTolM) << "zoom " << z;
      EXPECT_LT(AngleBetween(got, want), kTolRad) << "zoom " << z;
    }
  }
}

// Without reading-dependent effects the joint values are the readings
// themselves, and KDL's frames equal rtscalib's.
TEST(UrdfExport, KdlFramesEqualTheModelsAtTheReadings) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 5; ++trial) {
    for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
      std::vector<Effect> effects = {Effect::kVerticalIndex, Effect::kEdmOffset};
      if (k == Kinematics::kSpherical) {
        effects.push_back(Effect::kCollimation);
        effects.push_back(Effect::kTiltingAxis);
      }
      const InstrumentModel m = RandomModel(k, rng, effects);
      const std::array<double, 2> q = UrdfJointPositions(m, 1.25, 2.0);
      EXPECT_EQ(q[0], 1.25);
      EXPECT_NEAR(q[1], 2.0, 1e-15);
      SCOPED_TRACE(KinematicsName(k));
      ExpectUrdfMatchesModel(m, rng, trial == 0);
    }
  }
}

// With eccentricities and scales the URDF's frames equal rtscalib's at the
// corrected joint values.
TEST(UrdfExport, KdlFramesEqualTheModelsAtCorrectedJointValues) {
  std::mt19937 rng(22);
  for (int trial = 0; trial < 3; ++trial) {
    for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
      std::vector<Effect> effects = {Effect::kVerticalIndex, Effect::kHzEccentricity,
                                     Effect::kVEccentricity, Effect::kHzScale, Effect::kVScale};
      if (k == Kinematics::kSpherical) {
        effects.push_back(Effect::kCollimation);
        effects.push_back(Effect::kTiltingAxis);
      }
      const InstrumentModel m = RandomModel(k, rng, effects);
      SCOPED_TRACE(KinematicsName(k));
      ExpectUrdfMatchesModel(m, rng, false);
    }
  }
}

// The joint conventions themselves: at theta = pi/2 in face 1 an ideal
// instrument looks north at phi = 0 and east at phi = pi/2 (clockwise seen
// from above, SPEC 1); the URDF agrees with the joint value +phi.
TEST(UrdfExport, IdealInstrumentTurnsClockwiseWithPositiveJointValue) {
  for (Kinematics k : {Kinematics::kDh, Kinematics::kSpherical}) {
    const InstrumentModel m = IdealModel(k, 1, CameraTool{});
    KDL::Tree tree;
    ASSERT_TRUE(kdl_parser::treeFromString(ExportUrdf(m).xml, tree));
    const UrdfChain edm(tree, kUrdfEdmLink);
    const Eigen::Vector3d north = edm.At({0.0, M_PI / 2}).rotation.col(2);
    const Eigen::Vector3d east = edm.At({M_PI / 2, M_PI / 2}).rotation.col(2);
    const Eigen::Vector3d up = edm.At({0.3, 0.0}).rotation.col(2);
    EXPECT_LT((north - Eigen::Vector3d(0, 1, 0)).norm(), 1e-12) << KinematicsName(k);
    EXPECT_LT((east - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12) << KinematicsName(k);
    EXPECT_LT((up - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12) << KinematicsName(k);
  }
}

// What the URDF cannot hold is listed, with its value, in the XML comment
// and in not_held; the rigid constants are folded, not listed.
TEST(UrdfExport, ListsWhatItCannotHoldAndFoldsRigidConstants) {
  std::mt19937 rng(23);
  const InstrumentModel m =
      RandomModel(Kinematics::kSpherical, rng,
                  {Effect::kCollimation, Effect::kTiltingAxis, Effect::kVerticalIndex,
                   Effect::kAxisWobble, Effect::kHzEccentricity, Effect::kEdmOffset,
                   Effect::kEdmScale, Effect::kEdmCyclic, Effect::kRadialDistortion});
  const UrdfExport u = ExportUrdf(m);
  auto listed = [](const std::vector<std::string>& list, const std::string& name) {
    for (const std::string& s : list) {
      if (s.rfind(name + " ", 0) == 0 || s.rfind(name + ":", 0) == 0) return true;
    }
    return false;
  };
  for (const char* name : {"collimation", "tilting_axis", "vertical_index"}) {
    EXPECT_TRUE(listed(u.folded, name)) << name;
    EXPECT_FALSE(listed(u.not_held, name)) << name;
  }
  for (const char* name : {"axis_wobble", "hz_eccentricity", "edm_offset", "edm_scale",
                           "edm_cyclic", "radial_distortion"}) {
    EXPECT_TRUE(listed(u.not_held, name)) << name;
    EXPECT_NE(u.xml.find(std::string("  ") + name), std::string::npos) << name;
  }
  // The comment is well formed: "--" only in its delimiters.
  const size_t open = u.xml.find("<!--"), close = u.xml.find("-->");
  ASSERT_NE(open, std::string::npos);
  ASSERT_NE(close, std::string::npos);
  EXPECT_EQ(u.xml.substr(open + 4, close - open - 4).find("--"), std::string::npos);
  // The wobble really is outside the URDF: its frames differ from rtscalib's.
  KDL::Tree tree;
  ASSERT_TRUE(kdl_parser::treeFromString(u.xml, tree));
  const UrdfChain edm(tree, kUrdfEdmLink);
  const double phi = 0.7, theta = 1.4;
  EXPECT_GT(AngleBetween(edm.At(UrdfJointPositions(m, phi, theta)), RefFromEdm(m, phi, theta)),
            1e-7);
}

// rpy near and at pitch = +-pi/2 reproduces the rotation to rounding.
// Tolerance 1e-14: a few products of unit-magnitude terms.
TEST(UrdfExport, RpyIsExactNearGimbalLock) {
  std::mt19937 rng(24);
  std::uniform_real_distribution<double> a(-M_PI, M_PI);
  for (double sign : {1.0, -1.0}) {
    for (int k = 0; k <= 16; ++k) {
      const double pitch = sign * (M_PI / 2 - (k == 16 ? 0.0 : std::pow(10.0, -k)));
      const Eigen::Matrix3d r = RotationFromEuler<double>(Eigen::Vector3d(a(rng), pitch, a(rng)));
      const Eigen::Matrix3d back = RotationFromEuler<double>(UrdfRpy(r));
      EXPECT_LT((back - r).cwiseAbs().maxCoeff(), 1e-14) << "pitch " << pitch;
    }
  }
}

}  // namespace
}  // namespace rtscalib
