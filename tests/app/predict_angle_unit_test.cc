// `rtscalib predict --angle-unit deg|gon`: the input's readings are read in
// that unit (as the config's data.angle_unit) and the output keeps it; the
// predictions equal those of the same rows given in radians.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "app/commands.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

// A reading in degrees or gon differs from its radians by ~2 ulp
// (tests/io/records_test.cc), which moves a point at 7 m by ~1e-15 m; 1e-12 m
// is far above that and far below any instrument's noise.
constexpr double kSamePointM = 1e-12;

TEST(PredictAngleUnit, DegreesAndGonPredictWhatRadiansPredict) {
  const fs::path dir = fs::path(RTSCALIB_BINARY_DIR) / "test_tmp" / "predict_angle_unit";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string model = (dir / "model.yaml").string();
  WriteModelYaml(model, PaperTruth(1));
  std::vector<Record> rows;
  for (int i = 0; i < 6; ++i) {
    Record r;
    r.phi = 0.3 + 0.9 * i;
    r.theta = 1.2 + 0.05 * i;
    r.d = 7.0;
    if (i % 2) {
      r.tool = Tool::kCam;
      r.u = 600 + 10 * i;
      r.v = 500 - 7 * i;
    }
    rows.push_back(r);
  }
  auto predict = [&](const std::string& unit) {
    const std::string in = (dir / ("in_" + unit + ".csv")).string();
    WriteRecords(in, rows, *AngleUnitFromName(unit));
    app::PredictArgs args;
    args.model = model;
    args.records = in;
    args.out = (dir / ("out_" + unit + ".csv")).string();
    args.angle_unit = unit;
    EXPECT_EQ(app::RunPredict(args), 0);
    return ReadRecords(args.out, *AngleUnitFromName(unit)).records;
  };
  const std::vector<Record> rad = predict("rad");
  for (const std::string unit : {"deg", "gon"}) {
    SCOPED_TRACE(unit);
    const std::vector<Record> other = predict(unit);
    ASSERT_EQ(other.size(), rad.size());
    for (size_t i = 0; i < rad.size(); ++i) {
      EXPECT_LT((other[i].x - rad[i].x).norm(), kSamePointM) << i;
      // The output's readings are in the input's unit: read back in it, they
      // are the input's readings.
      EXPECT_NEAR(other[i].phi, rows[i].phi, 1e-15 * std::fabs(rows[i].phi));
    }
  }
  // A file in degrees read as radians is something else entirely.
  app::PredictArgs wrong;
  wrong.model = model;
  wrong.records = (dir / "in_deg.csv").string();
  wrong.out = (dir / "out_wrong.csv").string();
  app::RunPredict(wrong);
  const std::vector<Record> as_rad = ReadRecords(wrong.out).records;
  EXPECT_GT((as_rad[0].x - rad[0].x).norm(), 1.0);
  // An unknown unit (main.cc checks the names; callers of RunPredict too).
  wrong.angle_unit = "degrees";
  wrong.force = true;
  EXPECT_THROW(app::RunPredict(wrong), std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib
