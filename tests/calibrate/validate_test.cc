// The checks after every fit stage (libcalib/calibrate/validate.h): one test
// per failure kind on a fit outcome built by hand, then the same failures
// through Calibrate on simulated data with one bad row, and the tools the
// data do not determine.
#include "libcalib/calibrate/validate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "libcalib/calibrate/calibrate.h"
#include "libcalib/text/errors.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

using ::testing::AllOf;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::SizeIs;

// Klug's sweeps plus a small grid; every row gets the line it would have in
// a records.csv with a header, so that failures can name it.
struct Data {
  Observations obs;
  InstrumentModel truth;
  Data() {
    SimulationOptions sim;
    sim.seed = 3;
    sim.truth = PaperTruth(1);
    sim.plan.grid_phi_steps = 10;
    sim.plan.grid_theta_steps = 6;
    obs = Simulate(sim).obs;
    truth = sim.truth;
    for (size_t i = 0; i < obs.records.size(); ++i) obs.records[i].line = int(i) + 2;
    obs.records_source = "records.csv";
  }
};

// A row outside the critical regions, of the tool asked for, in the grid:
// the first one, or with `last` the last one.
int GridRow(const Observations& obs, Tool tool, bool last = false) {
  const FitOptions defaults;
  const int n = static_cast<int>(obs.records.size());
  for (int k = 0; k < n; ++k) {
    const int i = last ? n - 1 - k : k;
    const Record& r = obs.records[i];
    if (r.tool == tool && r.set == "grid" &&
        !defaults.critical_region.Contains(r.theta)) {
      return i;
    }
  }
  ADD_FAILURE() << "no grid row";
  return 0;
}

FitSummary Converged() {
  FitSummary f;
  f.converged = true;
  f.iterations = 3;
  f.final_cost = 1.0;
  f.message = " CONVERGENCE";
  return f;
}

CalibrationFailure::Kind KindOf(const Observations& obs, const InstrumentModel& model,
                                const FitSummary& fit, const FitOptions& fo = FitOptions(),
                                std::string* what = nullptr) {
  try {
    ValidateFit("test stage", obs, model, fit, fo, FitChecks());
  } catch (const CalibrationFailure& e) {
    if (what) *what = e.what();
    return e.kind;
  }
  ADD_FAILURE() << "no CalibrationFailure";
  return CalibrationFailure::Kind::kNonFinite;
}

TEST(ValidateFit, TheTruthOnItsOwnDataPasses) {
  const Data data;
  // Exact data (the simulator adds no noise unless asked): sigma0 is round-off.
  EXPECT_NO_THROW(ValidateFit("s", data.obs, data.truth, Converged(), FitOptions(), FitChecks()));
  const Sigma0 s = ComputeSigma0(data.obs, data.truth, FitOptions());
  EXPECT_GT(s.n_edm, 0);
  EXPECT_GT(s.n_cam, 0);
  EXPECT_LT(s.edm, 100);
  EXPECT_LT(s.cam, 100);
}

TEST(ValidateFit, NonFiniteCostFails) {
  const Data data;
  FitSummary fit = Converged();
  fit.final_cost = std::numeric_limits<double>::infinity();
  std::string what;
  EXPECT_EQ(KindOf(data.obs, data.truth, fit, FitOptions(), &what),
            CalibrationFailure::Kind::kNonFinite);
  EXPECT_THAT(what, AllOf(HasSubstr("test stage: the fit is not finite"), HasSubstr("cost inf")));
}

TEST(ValidateFit, NonFiniteParameterIsNamed) {
  const Data data;
  InstrumentModel model = data.truth;
  model.edm.t[2] = std::numeric_limits<double>::quiet_NaN();
  std::string what;
  EXPECT_EQ(KindOf(data.obs, model, Converged(), FitOptions(), &what),
            CalibrationFailure::Kind::kNonFinite);
  EXPECT_THAT(what, HasSubstr("parameters edm"));
}

// x = 1e308 m: its (r / sigma)^2 overflows; the row is named first, with
// its file and line.
TEST(ValidateFit, RowWithNonFiniteCostIsNamedFirst) {
  Data data;
  const int row = GridRow(data.obs, Tool::kEdm);
  data.obs.records[row].x.x() = 1e308;
  try {
    ValidateFit("s", data.obs, data.truth, Converged(), FitOptions(), FitChecks());
    FAIL() << "no CalibrationFailure";
  } catch (const CalibrationFailure& e) {
    EXPECT_EQ(e.kind, CalibrationFailure::Kind::kNonFinite);
    ASSERT_FALSE(e.rows.empty());
    EXPECT_THAT(e.rows[0], AllOf(HasSubstr("records.csv:" + std::to_string(row + 2) + ":"),
                                 HasSubstr("cost not finite")));
    EXPECT_THAT(e.rows, SizeIs(20));  // FitChecks::max_rows_named
  }
}

TEST(ValidateFit, NotConvergedFails) {
  const Data data;
  FitSummary fit = Converged();
  fit.converged = false;
  fit.message = " Maximum number of iterations reached.";
  std::string what;
  EXPECT_EQ(KindOf(data.obs, data.truth, fit, FitOptions(), &what),
            CalibrationFailure::Kind::kNotConverged);
  EXPECT_THAT(what, HasSubstr("did not converge (3 iterations; Ceres: Maximum number"));
}

// Ceres can report a solve that stopped before its first evaluation.
TEST(ValidateFit, ZeroIterationsFails) {
  const Data data;
  FitSummary fit = Converged();
  fit.iterations = 0;
  EXPECT_EQ(KindOf(data.obs, data.truth, fit), CalibrationFailure::Kind::kNotConverged);
}

// One row 0.5 m off among n exact EDM rows at sigma 1e-5 m: sigma0 = 0.5 / 1e-5 /
// sqrt(3 n) > 100 for any n < 8e4. The row is named first.
TEST(ValidateFit, ResidualsFarBeyondTheSigmasFailAndNameTheWorstRow) {
  Data data;
  const int row = GridRow(data.obs, Tool::kEdm);
  data.obs.records[row].x.z() += 0.5;
  try {
    ValidateFit("s", data.obs, data.truth, Converged(), FitOptions(), FitChecks());
    FAIL() << "no CalibrationFailure";
  } catch (const CalibrationFailure& e) {
    EXPECT_EQ(e.kind, CalibrationFailure::Kind::kAbsurdResiduals);
    EXPECT_THAT(e.reason, AllOf(HasSubstr("EDM sigma0"), HasSubstr("fit.max_sigma0 = 1.0e+02")));
    ASSERT_FALSE(e.rows.empty());
    EXPECT_THAT(e.rows[0], HasSubstr("records.csv:" + std::to_string(row + 2) + ": EDM residual"));
  }
  // The limit is the option: a limit above the row's sigma0 lets it pass.
  FitChecks lax;
  lax.max_sigma0 = 1e7;
  EXPECT_NO_THROW(ValidateFit("s", data.obs, data.truth, Converged(), FitOptions(), lax));
}

// With a robust loss one gross row is an outlier the loss down-weights, not
// a failed fit: sigma0 is the median-based estimate.
TEST(ValidateFit, RobustLossToleratesOneGrossRow) {
  Data data;
  data.obs.records[GridRow(data.obs, Tool::kEdm)].x.z() += 0.5;
  FitOptions fo;
  fo.loss = RobustLoss::kHuber;
  EXPECT_NO_THROW(ValidateFit("s", data.obs, data.truth, Converged(), fo, FitChecks()));
}

TEST(ValidateFit, ChecksAreValidated) {
  FitChecks c;
  c.max_sigma0 = 0.5;
  EXPECT_THAT(c.Check(), HasSubstr("fit.max_sigma0"));
  CalibrationOptions o;
  o.checks = c;
  EXPECT_THAT(o.Check(), HasSubstr("fit.max_sigma0"));
}

CalibrationOptions Options(const InstrumentModel& truth) {
  CalibrationOptions o;
  o.model.cameras = truth.cams;
  o.diagnose.enabled = false;
  return o;
}

// Gross-error handling off: every protection of a fit against a single huge
// value must hold on its own.
CalibrationOptions WithoutGrossErrorHandling(CalibrationOptions o) {
  o.screen.gross_errors.enabled = false;
  o.fit.gross_errors.enabled = false;
  return o;
}

// z = 1e308 m in an EDM grid row overflowed the extraction's EDM tool
// (Kabsch centroids) into NaN, and Ceres aborted on the NaN quaternion
// (glog CHECK, exit 134). Now the gross-error screening takes the row out and
// names it; without it, the screening sees the point 1e308 m from the others
// before the extraction and stops with an InputError.
TEST(Calibrate, HugeCoordinateInAGridRowIsAGrossRowOrAnInputErrorBeforeAnyFit) {
  Data data;
  const int row = GridRow(data.obs, Tool::kEdm, /*last=*/true);
  data.obs.records[row].x.z() = 1e308;
  const CalibrationResult r = Calibrate(data.obs, Options(data.truth));
  ASSERT_EQ(r.gross_rows.size(), 1u);
  EXPECT_EQ(r.gross_rows[0].line, data.obs.records[row].line);
  EXPECT_THAT(r.gross_rows[0].reason, HasSubstr("EDM row: the point is inf m farther"));
  EXPECT_TRUE(r.refined.fit.converged);
  try {
    Calibrate(data.obs, WithoutGrossErrorHandling(Options(data.truth)));
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line, data.obs.records[row].line);
    EXPECT_THAT(e.what(), HasSubstr("expected a point in metres"));
  }
}

// d = 1e300 m on a camera row: the fit cannot reach it; the old run said
// "converged: yes" and reported `camera inf +- nan`. Now the gross-error
// screening names the row; without it the fit fails and names it.
TEST(Calibrate, HugeDistanceIsAGrossRowOrFailsAndNamesTheRow) {
  Data data;
  const int row = GridRow(data.obs, Tool::kCam);
  data.obs.records[row].d = 1e300;
  const CalibrationResult r = Calibrate(data.obs, Options(data.truth));
  ASSERT_EQ(r.gross_rows.size(), 1u);
  EXPECT_EQ(r.gross_rows[0].line, row + 2);
  EXPECT_THAT(r.gross_rows[0].reason, HasSubstr("camera row (zoom 0): the point is 1e+300 m"));
  try {
    Calibrate(data.obs, WithoutGrossErrorHandling(Options(data.truth)));
    FAIL() << "no CalibrationFailure";
  } catch (const CalibrationFailure& e) {
    ASSERT_FALSE(e.rows.empty());
    EXPECT_THAT(e.rows[0], HasSubstr("records.csv:" + std::to_string(row + 2) + ": camera"));
  }
}

TEST(Calibrate, GoodDataMarkEveryToolDetermined) {
  const Data data;
  const CalibrationResult r = Calibrate(data.obs, Options(data.truth));
  EXPECT_TRUE(r.model.edm_determined);
  EXPECT_TRUE(r.model.cams[0].determined);
}

// Camera rows only: the EDM tool is its start, said so and not claimed.
TEST(Calibrate, CameraRowsOnlyLeaveTheEdmNotDetermined) {
  Data data;
  std::vector<Record> cam;
  for (const Record& r : data.obs.records) {
    if (r.tool == Tool::kCam) cam.push_back(r);
  }
  data.obs.records = cam;
  const CalibrationResult r = Calibrate(data.obs, Options(data.truth));
  EXPECT_FALSE(r.model.edm_determined);
  EXPECT_TRUE(r.model.cams[0].determined);
  EXPECT_THAT(r.notes, Contains(HasSubstr("EDM tool: not determined by the data")));
}

// EDM rows only: zoom 0's camera is the configured start.
TEST(Calibrate, EdmRowsOnlyLeaveTheCameraNotDetermined) {
  Data data;
  std::vector<Record> edm;
  for (const Record& r : data.obs.records) {
    if (r.tool == Tool::kEdm) edm.push_back(r);
  }
  data.obs.records = edm;
  const CalibrationResult r = Calibrate(data.obs, Options(data.truth));
  EXPECT_TRUE(r.model.edm_determined);
  ASSERT_EQ(r.model.NumZooms(), 1);
  EXPECT_FALSE(r.model.cams[0].determined);
  EXPECT_THAT(r.notes, Contains(HasSubstr("zoom 0 camera: not determined by the data")));
}

}  // namespace
}  // namespace rtscalib
