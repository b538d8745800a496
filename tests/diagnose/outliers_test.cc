#include "libcalib/diagnose/outliers.h"

#include <gtest/gtest.h>

#include "tests/diagnose/diagnose_fixture.h"

namespace rtscalib {
namespace {

using testing_diagnose::FitBaseline;
using testing_diagnose::Fitted;
using testing_diagnose::PaperNoise;
using testing_diagnose::SmallPlan;

SimulatedData Data(std::uint64_t seed) {
  SimulationOptions o;
  o.seed = seed;
  o.truth = PaperTruth(1);
  o.plan = SmallPlan();
  o.noise = PaperNoise();
  return Simulate(o);
}

// A record moved by 0.5 mm (the EDM noise is 10 um along the ray, 1 arcsec
// across it) is the worst observation and flagged, with its line.
TEST(Outliers, GrossErrorIsFlaggedWithItsLine) {
  SimulatedData data = Data(41);
  int target = -1;
  for (size_t i = 0; i < data.obs.records.size(); ++i) {
    const Record& r = data.obs.records[i];
    if (r.tool == Tool::kEdm && r.set == "grid" && std::abs(r.theta - M_PI / 2) < 0.4 && r.d < 3) {
      target = static_cast<int>(i);
      break;
    }
  }
  ASSERT_GE(target, 0);
  data.obs.records[target].x.x() += 5e-4;
  data.obs.records[target].line = 123;
  data.obs.records_source = "records.csv";
  const Fitted f = FitBaseline(data, PaperTruth(1), 42);
  const Diagnosis d = testing_diagnose::DiagnoseFitted(f);
  ASSERT_FALSE(d.outliers.worst.empty());
  EXPECT_EQ(d.outliers.worst.front().index, target);
  EXPECT_TRUE(d.outliers.worst.front().flagged);
  EXPECT_EQ(d.outliers.flagged, 1);
  EXPECT_EQ(d.outliers.worst.front().where.rfind("records.csv:123", 0), 0u)
      << d.outliers.worst.front().where;
}

TEST(Outliers, CleanDataFlagNothing) {
  const Fitted f = FitBaseline(Data(43), PaperTruth(1), 44);
  const Diagnosis d = testing_diagnose::DiagnoseFitted(f);
  EXPECT_EQ(d.outliers.flagged, 0)
      << d.outliers.worst.front().where << " w " << d.outliers.worst.front().w;
  EXPECT_GT(d.outliers.tested, 100);
}

}  // namespace
}  // namespace rtscalib
