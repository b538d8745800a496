// Exact copies of earlier rows (libcalib/screen/duplicates.h): a records.csv
// joined to itself and a photo listed twice in shots.csv are found, named
// line by line in one notice per file and taken out before the fit with the
// gross rows; rows that differ in one bit of one value are not copies.
#include "libcalib/screen/duplicates.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "libcalib/screen/gross.h"
#include "libcalib/screen/screen.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

// Klug's sweeps in face 1 and 2 at zoom 0 of the paper's instrument with
// noise (no two rows alike), as records.csv holds them (line 1: header).
Observations Sweeps() {
  SimulationOptions sim;
  sim.truth = PaperTruth(1);
  sim.noise.angle_rad = 1.0 * M_PI / (180 * 3600);
  sim.noise.distance_m = 1e-5;
  Observations obs = Simulate(sim).obs;
  for (size_t i = 0; i < obs.records.size(); ++i) obs.records[i].line = static_cast<int>(i) + 2;
  obs.records_source = "records.csv";
  obs.pixels_source = "shots.csv";
  return obs;
}

TEST(DuplicateRows, NoneInSimulatedData) {
  const Observations obs = Sweeps();
  ASSERT_GT(obs.records.size(), 10u);
  EXPECT_THAT(FindDuplicateRows(obs), IsEmpty());
  EXPECT_THAT(DuplicateRowNotices(obs), IsEmpty());
}

TEST(DuplicateRows, RecordsJoinedToThemselvesAreNamedAndTakenOut) {
  Observations obs = Sweeps();
  const size_t n = obs.records.size();
  const int first_copy_line = static_cast<int>(n) + 2;
  for (size_t i = 0; i < n; ++i) {
    Record copy = obs.records[i];
    copy.line = first_copy_line + static_cast<int>(i);
    obs.records.push_back(copy);
  }
  const std::vector<ExcludedRow> copies = FindDuplicateRows(obs);
  ASSERT_EQ(copies.size(), n);
  for (size_t i = 0; i < n; ++i) {
    EXPECT_FALSE(copies[i].pixel);
    EXPECT_EQ(copies[i].index, static_cast<int>(n + i));
    EXPECT_EQ(copies[i].line, first_copy_line + static_cast<int>(i));
    EXPECT_EQ(copies[i].reason, "an exact copy of line " + std::to_string(i + 2) +
                                    " (every column equal): counted once, not a second "
                                    "measurement");
  }
  const std::string l = std::to_string(first_copy_line);
  const std::string expected =
      "records.csv: " + std::to_string(n) +
      " rows repeat an earlier row exactly (every column equal): line " + l +
      " repeats line 2, line " + std::to_string(first_copy_line + 1) + " repeats line 3, line " +
      std::to_string(first_copy_line + 2) + " repeats line 4, line " +
      std::to_string(first_copy_line + 3) + " repeats line 5, line " +
      std::to_string(first_copy_line + 4) + " repeats line 6 and " + std::to_string(n - 5) +
      " more. Each copy is taken out before the fit and listed with the gross rows: counted "
      "twice, a copy would shrink every sigma by up to 1/sqrt(2). If the file was joined to "
      "itself, remove the copies";
  EXPECT_THAT(DuplicateRowNotices(obs), ElementsAre(expected));
  // The screening's notices carry it; the rows go out with the gross rows,
  // also with the gross-error search off; what is left is the file once.
  ScreenOptions options;
  EXPECT_THAT(ScreenObservations(obs, PaperTruth(1).cams, options),
              ElementsAre("screening: " + expected));
  options.gross_errors.enabled = false;
  const std::vector<ExcludedRow> out = FindGrossRows(obs, options.gross_errors);
  ASSERT_EQ(out.size(), n);
  const Observations kept = WithoutRows(obs, out);
  ASSERT_EQ(kept.records.size(), n);
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(kept.records[i].line, static_cast<int>(i) + 2);
}

TEST(DuplicateRows, OneBitOfOneValueMakesADifferentRow) {
  Observations obs = Sweeps();
  for (int column = 0; column < 3; ++column) {
    Record copy = obs.records[0];
    copy.line = 1000 + column;
    double& value = column == 0 ? copy.phi : column == 1 ? copy.d : copy.x.z();
    value = std::nextafter(value, 10.0);
    obs.records.push_back(copy);
  }
  Record other_set = obs.records[0];
  other_set.line = 1003;
  other_set.set = "repeat";
  obs.records.push_back(other_set);
  EXPECT_THAT(FindDuplicateRows(obs), IsEmpty());
}

TEST(DuplicateRows, APhotoListedTwiceInShotsCsvIsOneLinePair) {
  Observations obs;
  obs.records_source = "records.csv";
  obs.pixels_source = "shots.csv";
  // Two photos (shots.csv lines 2 and 3) of four corners each; line 4 lists
  // the photo of line 2 again, so its corners come again.
  for (int line : {2, 3, 4}) {
    for (int corner = 0; corner < 4; ++corner) {
      PixelObservation p;
      p.line = line;
      p.shot = line == 3 ? "s2" : "s1";
      p.phi = line == 3 ? 0.5 : 0.25;
      p.theta = 1.5;
      p.corner = corner;
      p.X = {1.0 + 0.1 * corner, 2.0, 0.5};
      p.uv = {600.0 + 10 * corner, 480.0 + 0.5 * (line == 3)};
      obs.pixels.push_back(p);
    }
  }
  const std::vector<ExcludedRow> copies = FindDuplicateRows(obs);
  ASSERT_EQ(copies.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(copies[i].pixel);
    EXPECT_EQ(copies[i].index, 8 + i);
    EXPECT_EQ(copies[i].line, 4);
    EXPECT_THAT(copies[i].reason, HasSubstr("an exact copy of line 2 "));
  }
  EXPECT_THAT(DuplicateRowNotices(obs),
              ElementsAre("shots.csv: 4 rows repeat an earlier row exactly (every column equal; "
                          "the corners of 1 line): line 4 repeats line 2. Each copy is taken out "
                          "before the fit and listed with the gross rows: counted twice, a copy "
                          "would shrink every sigma by up to 1/sqrt(2). If the file was joined "
                          "to itself, remove the copies"));
}

TEST(DuplicateRows, AGrossRowTwiceIsStillFound) {
  // Two copies of a row whose point is 50 m off: one goes out as a copy, the
  // other as a gross row (a copy must not make a gross row look confirmed).
  Observations obs = Sweeps();
  Record bad = obs.records[3];
  bad.x.x() += 50.0;
  bad.line = 500;
  obs.records.push_back(bad);
  bad.line = 501;
  obs.records.push_back(bad);
  const std::vector<ExcludedRow> out = FindGrossRows(obs, GrossScreenOptions());
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].line, 500);
  EXPECT_THAT(out[0].reason, HasSubstr("farther from the instrument"));
  EXPECT_EQ(out[1].line, 501);
  EXPECT_THAT(out[1].reason, HasSubstr("an exact copy of line 500"));
}

}  // namespace
}  // namespace rtscalib
