// `rtscalib predict` on files with rows the model cannot predict: the first
// such row stops it with an error naming the file, the line and the columns,
// and nothing is written; with --skip-bad the other rows are written and the
// skipped ones counted and listed (at most 20) on stderr.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "app/commands.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

struct Files {
  fs::path dir;
  InstrumentModel model = PaperTruth(2);  // 1280 x 960 images, zooms 0 and 1
  std::string Model() const { return (dir / "model.yaml").string(); }
};

Files MakeFiles(const std::string& name) {
  Files f;
  f.dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "predict_bad_rows" / name;
  fs::remove_all(f.dir);
  fs::create_directories(f.dir);
  WriteModelYaml(f.Model(), f.model);
  return f;
}

Record EdmRow(double phi) {
  Record r;
  r.phi = phi;
  r.theta = 1.4;
  r.d = 7.0;
  return r;
}

Record CamRow(int zoom, double u, double v) {
  Record r = EdmRow(0.5);
  r.tool = Tool::kCam;
  r.zoom = zoom;
  r.u = u;
  r.v = v;
  return r;
}

// Line of the i-th data row (0-based) of a file written by WriteRecords /
// WritePixels: the header is line 1.
int LineOf(int row) { return row + 2; }

TEST(PredictBadRows, RecordsStopAtTheFirstBadRowNamingFileLineAndColumn) {
  const Files f = MakeFiles("records_stop");
  const std::string in = (f.dir / "in.csv").string();
  WriteRecords(in, {EdmRow(0.1), CamRow(0, 640, 480), EdmRow(0.2), CamRow(2, 640, 480),
                    CamRow(0, 2000, 480)});
  app::PredictArgs args;
  args.model = f.Model();
  args.records = in;
  args.out = (f.dir / "out.csv").string();
  try {
    app::RunPredict(args);
    ADD_FAILURE() << "a zoom the model does not have was predicted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file, in);
    EXPECT_EQ(e.line, LineOf(3));
    EXPECT_EQ(e.column, "zoom");
    EXPECT_EQ(e.got, "2");
    EXPECT_NE(std::string(e.what()).find(in + ":5: column 'zoom'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(args.out));  // nothing half-written

  // The pixel beyond the 1280-px image (margin 10%: u <= 1407.5) on line 6.
  WriteRecords(in, {EdmRow(0.1), CamRow(0, 640, 480), EdmRow(0.2), CamRow(1, 640, 480),
                    CamRow(0, 2000, 480)});
  try {
    app::RunPredict(args);
    ADD_FAILURE() << "a pixel outside the image was predicted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line, LineOf(4));
    EXPECT_EQ(e.subject, "columns u, v");
    EXPECT_NE(std::string(e.what()).find("1280x960"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(args.out));
}

TEST(PredictBadRows, PixelsBehindTheCameraStopTheCommand) {
  const Files f = MakeFiles("pixels_stop");
  const double phi = 0.3, theta = 1.2;
  std::vector<PixelObservation> rows(3);
  for (size_t i = 0; i < rows.size(); ++i) {
    rows[i].phi = phi;
    rows[i].theta = theta;
    rows[i].shot = "s";
    rows[i].X = PredictCam(f.model, 0, phi, theta, 600 + 10.0 * i, 500, 12.0);
  }
  // Row 1: the mirror image through the camera centre, behind it.
  rows[1].X = 2 * RefFromCam(f.model, 0, phi, theta).translation - rows[1].X;
  const std::string in = (f.dir / "in.csv").string();
  WritePixels(in, rows);
  app::PredictArgs args;
  args.model = f.Model();
  args.pixels = in;
  args.out = (f.dir / "out.csv").string();
  try {
    app::RunPredict(args);
    ADD_FAILURE() << "a point behind the camera was predicted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file, in);
    EXPECT_EQ(e.line, LineOf(1));
    EXPECT_EQ(e.subject, "columns X, Y, Z");
    EXPECT_NE(std::string(e.what()).find("in front of zoom 0's camera"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(args.out));

  // --skip-bad: the two good rows, predicted where they were taken from
  // (Newton undistortion converges to ~1e-9 px).
  args.skip_bad = true;
  testing::internal::CaptureStderr();
  ASSERT_EQ(app::RunPredict(args), 0);
  const std::string err = testing::internal::GetCapturedStderr();
  const PixelsFile out = ReadPixels(args.out);
  ASSERT_EQ(out.pixels.size(), 2u);
  EXPECT_LT((out.pixels[0].uv - Eigen::Vector2d(600, 500)).norm(), 1e-6);
  EXPECT_LT((out.pixels[1].uv - Eigen::Vector2d(620, 500)).norm(), 1e-6);
  EXPECT_NE(err.find("skipped 1 of 3 rows"), std::string::npos) << err;
  EXPECT_NE(err.find(in + ":3: columns X, Y, Z"), std::string::npos) << err;
}

TEST(PredictBadRows, SkipBadWritesTheRestAndListsTheFirstTwentyLines) {
  const Files f = MakeFiles("records_skip");
  std::vector<Record> rows;
  std::vector<int> bad_lines;
  for (int i = 0; i < 60; ++i) {
    if (i % 2 == 1) {
      rows.push_back(CamRow(7, 640, 480));  // 30 rows of a zoom the model lacks
      bad_lines.push_back(LineOf(i));
    } else {
      rows.push_back(EdmRow(0.01 * i));
    }
  }
  const std::string in = (f.dir / "in.csv").string();
  WriteRecords(in, rows);
  app::PredictArgs args;
  args.model = f.Model();
  args.records = in;
  args.out = (f.dir / "out.csv").string();
  args.skip_bad = true;
  testing::internal::CaptureStderr();
  ASSERT_EQ(app::RunPredict(args), 0);
  const std::string err = testing::internal::GetCapturedStderr();
  const RecordsFile out = ReadRecords(args.out);
  ASSERT_EQ(out.records.size(), 30u);
  for (const Record& r : out.records) {
    EXPECT_EQ(r.tool, Tool::kEdm);
    EXPECT_EQ(r.x, PredictEdm(f.model, r.phi, r.theta, r.d));  // 17 digits round-trip
  }
  EXPECT_NE(err.find("skipped 30 of 60 rows"), std::string::npos) << err;
  for (size_t k = 0; k < bad_lines.size(); ++k) {
    const std::string named = in + ":" + std::to_string(bad_lines[k]) + ": column 'zoom'";
    EXPECT_EQ(err.find(named) != std::string::npos, k < 20) << named << "\n" << err;
  }
}

}  // namespace
}  // namespace rtscalib
