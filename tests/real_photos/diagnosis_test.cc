// The diagnosis on real cameras (docs/diagnostics.md): what it says of a
// model that fits must hold up against the scatter that is really there,
// and what it recommends must be what the user then sees.
//
// Camera-only sessions (SPEC 7.1, k1 k2 p1 p2 k3, one placement per photo)
// of boofcv_sony_chess, validationboof_bb2_chess (left and right) and
// configs/bench.yaml (OpenCV's own left*.jpg), run as `rtscalib --config`
// runs them (RunPipeline):
//   - no effect is recommended for a gain under DiagnosisSettings::min_gain
//     (2 % of the rms), whatever its BIC: such an effect is at most
//     "statistically detectable but not worth adding";
//   - no structure outside the catalogue is said larger than 3x the fit's
//     rms at the observed points (its size is stated there, never at image
//     corners no photo reached).
// The wide lens of the mrcal tour, whose diagnosis must name
// rational_distortion with the fall a calibration with it gives, is
// tests/real_photos/mrcal_tour_test.cc.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "app/pipeline.h"
#include "tests/real_photos/photo_sets.h"
#include "tests/real_photos/real_photos.h"

namespace rtscalib::testing_real_photos {
namespace {

namespace fs = std::filesystem;

// A camera-only chessboard session of the photos `names` of `set_dir`
// (one placement per photo, WriteShots) with a board of `cols` x `rows`
// squares of `square` m (targets.yaml counts squares: inner corners + 1),
// k1 k2 p1 p2 k3 as OpenCV's default. Returns the config's path.
std::string WriteSession(const TestFolder& folder, const std::string& set_dir,
                         const std::vector<std::string>& names, int cols, int rows,
                         double square) {
  std::vector<SetPhoto> photos;
  for (const std::string& n : names) photos.push_back({set_dir + "/" + n + ".jpg", n, 0});
  WriteShots(folder, photos);
  folder.Write("targets.yaml", "boards:\n  - {type: chessboard, first_id: 0, rows: " +
                                   std::to_string(rows) + ", cols: " + std::to_string(cols) +
                                   ", square_size: " + std::to_string(square) + "}\n");
  return folder.Write("config.yaml",
                      "data: {shots: shots.csv, targets: targets.yaml}\n"
                      "model:\n"
                      "  kinematics: none\n"
                      "  effects: [radial_distortion, tangential_distortion]\n"
                      "  intrinsics: fit\n"
                      "fit: {sigmas: {pixel_px: 0.1}}\n"
                      "detect: {jobs: 2}\n"
                      "diagnose: {enabled: true}\n"
                      "output: out\n");
}

std::vector<std::string> Numbered(const std::string& stem, int n) {
  std::vector<std::string> out;
  for (int i = 1; i <= n; ++i) out.push_back(stem + (i < 10 ? "0" : "") + std::to_string(i));
  return out;
}

std::string Verdict(const Diagnosis& d) {
  std::string out;
  for (const std::string& v : d.verdict) out += "  " + v + "\n";
  return out;
}

// The checks every camera-only real session must pass; prints the verdict.
void ExpectTruthfulDiagnosis(const std::string& name, const app::PipelineResult& r) {
  ASSERT_TRUE(r.calibration.diagnosis.has_value()) << name;
  const Diagnosis& d = *r.calibration.diagnosis;
  std::printf("%s (diagnosis %.3f s):\n%s", name.c_str(), d.seconds, Verdict(d).c_str());
  const double rms = d.current.pixels_px;
  ASSERT_GT(rms, 0.0);
  for (const RankedEffect& e : d.ranking.entries) {
    if (e.recommended) {
      EXPECT_GE(e.gain, d.min_gain) << name << ": " << e.name << "\n" << Verdict(d);
      EXPECT_TRUE(e.significant) << name << ": " << e.name;
    }
    if (e.significant && e.gain < d.min_gain) {
      EXPECT_FALSE(e.recommended) << name << ": " << e.name << " gains " << e.gain;
      for (const std::string& v : d.verdict) {
        EXPECT_EQ(v.find("Add " + e.name + " next"), std::string::npos) << name << ": " << v;
      }
    }
  }
  // Structure outside the catalogue, at the observed points: within 3x the
  // fit's rms (a real lens and a paper board leave some; a field of ten
  // times the residuals would be the extrapolation this size must never be).
  for (const StructureFinding& f : d.structure.unexplained) {
    EXPECT_TRUE(f.material) << f.description;
    if (f.unit == "px") {
      EXPECT_LE(f.size, 3 * rms) << name << ": " << f.description;
    }
  }
  EXPECT_TRUE(d.harmonics.unexplained.empty()) << name;  // camera-only: no phi, theta
}

app::PipelineResult RunSession(const std::string& config, const std::string& work) {
  app::Progress progress(true);
  return app::RunPipeline(app::LoadRunSettings(config), work, &progress);
}

TEST(RealDiagnosis, BoofcvSonyChessSaysNothingWithinTheScatter) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "boofcv_sony_chess");
  TestFolder folder;
  // 6 x 4 inner corners of 30 mm (PROVENANCE.md): 7 x 5 squares.
  const std::string config = WriteSession(folder, set, Numbered("frame", 13), 7, 5, 0.03);
  ExpectTruthfulDiagnosis("boofcv_sony_chess", RunSession(config, folder.Path("work")));
}

TEST(RealDiagnosis, ValidationBoofLeftSaysNothingWithinTheScatter) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "validationboof_bb2_chess");
  TestFolder folder;
  // 4 x 6 inner corners of 30 mm: 5 x 7 squares.
  const std::string config = WriteSession(folder, set, Numbered("left", 11), 5, 7, 0.03);
  ExpectTruthfulDiagnosis("validationboof_bb2_chess left", RunSession(config, folder.Path("work")));
}

TEST(RealDiagnosis, ValidationBoofRightSaysNothingWithinTheScatter) {
  RTSCALIB_REQUIRE_REAL_PHOTOS(set, "validationboof_bb2_chess");
  TestFolder folder;
  const std::string config = WriteSession(folder, set, Numbered("right", 11), 5, 7, 0.03);
  ExpectTruthfulDiagnosis("validationboof_bb2_chess right",
                          RunSession(config, folder.Path("work")));
}

TEST(RealDiagnosis, BenchSaysNothingWithinTheScatter) {
  // OpenCV's samples come with Debian's opencv-doc, not with the shared sets.
  if (!fs::exists("/usr/share/doc/opencv-doc/examples/data/left01.jpg")) {
    GTEST_SKIP() << "Debian's opencv-doc is not installed (scripts/install-deps.sh)";
  }
  TestFolder folder;
  ExpectTruthfulDiagnosis("configs/bench.yaml",
                          RunSession(std::string(RTSCALIB_SOURCE_DIR) + "/configs/bench.yaml",
                                     folder.Path("work")));
}

}  // namespace
}  // namespace rtscalib::testing_real_photos
