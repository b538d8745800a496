// The screening of observations (libcalib/screen/screen.h): good simulated
// data (libcalib/sim) pass without a finding; each mistake, put into a few
// rows of otherwise good data, gives its exact message.
#include "libcalib/screen/screen.h"

#include "libcalib/screen/gross.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <climits>
#include <string>
#include <vector>

#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;

// Records as a file holds them: line 1 is the header.
void NumberLines(std::vector<Record>* records) {
  for (size_t i = 0; i < records->size(); ++i) (*records)[i].line = static_cast<int>(i) + 2;
}

// Klug's sweeps in face 1 and 2 at zoom 0 of the paper's instrument (no noise).
Observations SweepObservations(const InstrumentModel& truth) {
  AcquisitionPlan plan;
  plan.faces = {1, 2};
  Observations obs;
  obs.records = PlanRecords(plan, truth);
  NumberLines(&obs.records);
  obs.records_source = "records.csv";
  obs.pixels_source = "pixels.csv";
  return obs;
}

std::vector<std::string> Messages(const ScreenFindings& f) {
  std::vector<std::string> out;
  for (const InputError& e : f.errors) out.push_back(e.what());
  return out;
}

// The first row of `obs` with this face and tool.
Record& FirstRow(Observations* obs, int face, Tool tool) {
  for (Record& r : obs->records) {
    if (r.face == face && r.tool == tool) return r;
  }
  throw std::logic_error("no such row");
}

class ScreenTest : public ::testing::Test {
 protected:
  InstrumentModel truth = PaperTruth(1);
  Observations obs = SweepObservations(truth);
  ScreenOptions options;
};

TEST_F(ScreenTest, PaperLikeSimulationHasNoFinding) {
  // configs/paper.yaml: sweeps, a 24 x 12 grid, face 1, zoom 0, with noise.
  SimulationOptions sim;
  sim.truth = truth;
  sim.plan.grid_phi_steps = 24;
  sim.plan.grid_theta_steps = 12;
  sim.noise.angle_rad = 1.0 * M_PI / (180 * 3600);
  sim.noise.distance_m = 1e-5;
  sim.noise.point_m = 5e-6;
  const SimulatedData data = Simulate(sim);
  const ScreenFindings f = FindDataMistakes(data.obs, truth.cams, options);
  EXPECT_THAT(Messages(f), IsEmpty());
  EXPECT_THAT(f.warnings, IsEmpty());
}

TEST_F(ScreenTest, Zoom3LikeSimulationInBothFacesHasNoFinding) {
  // configs/zoom3.yaml: three zooms, both faces, a grid and tag boards.
  SimulationOptions sim;
  sim.seed = 3;
  sim.truth = PaperTruth(3);
  sim.plan.grid_phi_steps = 12;
  sim.plan.grid_theta_steps = 6;
  sim.plan.faces = {1, 2};
  sim.plan.zooms = {0, 1, 2};
  sim.noise.angle_rad = 0.5 * M_PI / (180 * 3600);
  sim.noise.pixel_px = 0.3;
  sim.targets = ZoomScene(sim.truth, 4, 6, 4.0);
  const SimulatedData data = Simulate(sim);
  ASSERT_FALSE(data.obs.pixels.empty());
  int face2_pixels = 0;
  for (const PixelObservation& p : data.obs.pixels) face2_pixels += p.face == 2;
  EXPECT_GT(face2_pixels, 0);
  const ScreenFindings f = FindDataMistakes(data.obs, sim.truth.cams, options);
  EXPECT_THAT(Messages(f), IsEmpty());
  EXPECT_THAT(f.warnings, IsEmpty());
  // Without configured cameras (no image sizes) too.
  const ScreenFindings g = FindDataMistakes(data.obs, {}, options);
  EXPECT_THAT(Messages(g), IsEmpty());
  EXPECT_THAT(g.warnings, IsEmpty());
}

TEST_F(ScreenTest, DegreesAreNamed) {
  for (Record& r : obs.records) {
    r.phi *= 180 / M_PI;
    r.theta *= 180 / M_PI;
  }
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  ASSERT_EQ(f.errors.size(), 2u);
  EXPECT_EQ(f.errors[0].line, 7);  // phi = 0 on lines 2-6 is right in any unit
  EXPECT_EQ(f.errors[0].column, "phi");
  EXPECT_EQ(std::string(f.errors[0].what()),
            "records.csv:7: column 'phi': expected a horizontal angle in radians within "
            "[-2 pi, 4 pi); the file's angles look like degrees: give `data.angle_unit: deg` in "
            "the config (--angle-unit deg for predict and detect) and they are read as degrees; "
            "also lines 8, 9, 10, 11, 12 and 209 more rows, got '24'");
  EXPECT_EQ(std::string(f.errors[1].what()),
            "records.csv:2: column 'theta': expected a zenith angle in radians within "
            "[-2 pi, 4 pi); the file's angles look like degrees: give `data.angle_unit: deg` in "
            "the config (--angle-unit deg for predict and detect) and they are read as degrees; "
            "also lines 3, 4, 5, 6, 7 and 289 more rows, got '90'");
}

TEST_F(ScreenTest, GonAreNamed) {
  for (Record& r : obs.records) {
    r.phi *= 200 / M_PI;
    r.theta *= 200 / M_PI;
  }
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  ASSERT_EQ(f.errors.size(), 2u);
  EXPECT_EQ(std::string(f.errors[1].what()),
            "records.csv:2: column 'theta': expected a zenith angle in radians within "
            "[-2 pi, 4 pi); the file's angles look like gon: give `data.angle_unit: gon` in the "
            "config (--angle-unit gon for predict and detect) and they are read as gon; also "
            "lines 3, 4, 5, 6, 7 and 289 more rows, got '100'");
}

// The screening checks the readings as converted from data.angle_unit: the
// same degrees read with `angle_unit: deg` are radians and pass.
TEST_F(ScreenTest, ConvertedReadingsPass) {
  for (AngleUnit unit : {AngleUnit::kDeg, AngleUnit::kGon}) {
    Observations converted = obs;
    converted.angle_unit = unit;  // as the reader leaves them: radians, unit noted
    const ScreenFindings f = FindDataMistakes(converted, truth.cams, options);
    EXPECT_THAT(Messages(f), IsEmpty()) << AngleUnitName(unit);
  }
}

// A file still out of range once read in degrees (here: degrees of degrees)
// names the key it was read with, and shows the values as the file has them.
TEST_F(ScreenTest, OutOfRangeEvenInTheGivenUnitNamesTheKey) {
  for (Record& r : obs.records) {
    r.phi *= 180 / M_PI;
    r.theta *= 180 / M_PI;
  }
  obs.angle_unit = AngleUnit::kDeg;
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  ASSERT_EQ(f.errors.size(), 2u);
  EXPECT_EQ(std::string(f.errors[1].what()),
            "records.csv:2: column 'theta': expected a zenith angle (read in deg) within "
            "[-2 pi, 4 pi) rad; the file's angles leave that range even read in deg "
            "(data.angle_unit: deg): check the key and the file; also lines 3, 4, 5, 6, 7 and "
            "289 more rows, got '5156.620156177409'");
}

TEST_F(ScreenTest, FaceTwoWrittenTheFaceOneWay) {
  int face2 = 0;
  for (Record& r : obs.records) {
    if (r.face != 2) continue;
    r.theta = 2 * M_PI - r.theta;                   // e.g. 1.5708 instead of 4.7124
    if (FaceContradictsTheta(2, r.theta)) ++face2;  // theta = pi is either face's
  }
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(
      Messages(f),
      ElementsAre("records.csv:152: column 'theta': expected a face-2 zenith angle in [pi, 2 "
                  "pi] (SPEC 1: face 2 of the face-1 pointing (phi, theta) is (phi - pi mod 2 "
                  "pi, 2 pi - theta)); this face-2 row is written the face-1 way; also lines "
                  "153, 154, 155, 156, 157 and " +
                  std::to_string(face2 - 6) + " more rows, got '1.5707963267948966'"));
  EXPECT_EQ(f.errors[0].line, 152);
}

// One row against the face convention is a gross row (gross.h), not a
// convention mistake: no error, and the gross-error screening lists it.
TEST_F(ScreenTest, OneFaceOneRowHoldingAFaceTwoReadingIsAGrossRow) {
  Record& r = FirstRow(&obs, 1, Tool::kCam);
  r.theta = 4.0;
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(Messages(f), IsEmpty());
  const std::vector<ExcludedRow> gross = FindGrossRows(obs, GrossScreenOptions());
  ASSERT_EQ(gross.size(), 1u);
  EXPECT_EQ(gross[0].line, 4);
  EXPECT_EQ(gross[0].reason,
            "face 1 with theta = 4: SPEC 1 puts face 1's zenith angles in [0, pi]; the other "
            "149 face-1 rows follow it (a wrong face label or reading)");
}

TEST_F(ScreenTest, PhiBeyondTwoPiIsAWarning) {
  FirstRow(&obs, 1, Tool::kEdm).phi += 2 * M_PI;
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(Messages(f), IsEmpty());
  EXPECT_THAT(f.warnings,
              ElementsAre("records.csv: phi beyond 2 pi on 1 of 300 rows (line 2): readings of one "
                          "turn are in [0, 2 pi) (SPEC 1); check that these angles are radians"));
}

TEST_F(ScreenTest, PixelOutsideTheImage) {
  Record& r = FirstRow(&obs, 1, Tool::kCam);
  r.u = 1280 + 60;  // the image is 1280 px wide; the margin 50 px
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(
      Messages(f),
      ElementsAre("records.csv:4: column 'u': expected a pixel column u within the image of "
                  "zoom 0, -0.5 .. 1279.5 give or take screen.pixel_margin_px = 50 px "
                  "(model.cameras[0]: 1280 x 960 px), got '1340'"));
  // Within the margin: no finding.
  r.u = 1280 + 40;
  EXPECT_THAT(Messages(FindDataMistakes(obs, truth.cams, options)), IsEmpty());
  // Without image sizes nothing is known about the image.
  r.u = 1e6;
  EXPECT_THAT(Messages(FindDataMistakes(obs, {}, options)), IsEmpty());
}

TEST_F(ScreenTest, SwappedUAndV) {
  // Pixels spread over a 1280 x 960 image, written (v, u).
  Observations o = obs;
  int k = 0;
  for (Record& r : o.records) {
    if (r.tool != Tool::kCam) continue;
    const double u = 100.0 + (k * 37) % 1100, v = 50.0 + (k * 53) % 860;
    r.u = v;
    r.v = u;
    ++k;
  }
  const ScreenFindings f = FindDataMistakes(o, truth.cams, options);
  EXPECT_THAT(
      Messages(f),
      ElementsAre("records.csv:45: column 'v': expected a pixel row v within the image height "
                  "960 px of zoom 0 (model.cameras[0]: 1280 x 960 px); u and v look swapped: "
                  "every u fits the height and every v the width (SPEC 2: u = column to the "
                  "right, v = row down); also lines 46, 49, 50, 51, 95 and 24 more rows, got "
                  "'1025'"));
}

TEST_F(ScreenTest, MillimetresInRecords) {
  for (Record& r : obs.records) r.x *= 1000.0;
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(
      Messages(f),
      ElementsAre("records.csv:2: column 'x': expected a point in metres about d = 1 m from "
                  "the instrument, so within 2 (d + sqrt(3) d_max) + 1 m = 9.9282 m of the "
                  "median of the points (SPEC 1; d_max = 2 m); it is 554.809 m from it; the "
                  "coordinates look like millimetres (SPEC 1: metres); also lines 3, 4, 5, 6, "
                  "7 and 294 more rows, got '0.10159591643580074, 999.9985802675793, "
                  "-0.0910441871214191'"));
}

// One mistyped point is a gross row, not a unit mistake: the screening
// lets it through and the gross-error screening (gross.h) lists it.
TEST_F(ScreenTest, OneMistypedPointInRecordsIsAGrossRow) {
  Record& r = FirstRow(&obs, 1, Tool::kEdm);
  r.x.x() += 50.0;
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(Messages(f), ElementsAre());
  const std::vector<ExcludedRow> gross = FindGrossRows(obs, GrossScreenOptions());
  ASSERT_EQ(gross.size(), 1u);
  EXPECT_EQ(gross[0].line, 2);
  EXPECT_FALSE(gross[0].pixel);
  EXPECT_THAT(gross[0].reason, ::testing::StartsWith("EDM row: the point is 49.0101 m"));
  EXPECT_THAT(gross[0].reason, ::testing::HasSubstr("m farther from the instrument than its "
                                                    "distance d says"));
}

// The corners of one photo share its line of shots.csv: a mistake in the
// photos' readings lists each line once and counts the rows apart (it
// listed "2, 2, 2, 2, 2 and 5198 more rows" before).
TEST_F(ScreenTest, RowsOfOneLineAreListedOnce) {
  obs.records.clear();
  obs.pixels_source = "shots.csv";
  for (int line = 2; line < 12; ++line) {
    for (int corner = 0; corner < 4; ++corner) {
      PixelObservation p;
      p.line = line;
      p.phi = 30.0 + line;  // degrees
      p.theta = 90.0;
      p.corner = corner;
      p.uv = {640, 480};
      obs.pixels.push_back(p);
    }
  }
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  ASSERT_EQ(f.errors.size(), 2u);
  EXPECT_EQ(std::string(f.errors[0].what()),
            "shots.csv:2: column 'phi': expected a horizontal angle in radians within "
            "[-2 pi, 4 pi); the file's angles look like degrees: give `data.angle_unit: deg` in "
            "the config (--angle-unit deg for predict and detect) and they are read as degrees; "
            "also lines 3, 4, 5, 6, 7 and 4 more lines (40 rows in all), got '32'");
}

TEST_F(ScreenTest, KnownPointsBeyondTheExtent) {
  PixelObservation p;
  p.line = 2;
  p.theta = M_PI / 2;
  p.X = {12000.0, 3000.0, 500.0};  // millimetres
  p.uv = {640, 480};
  obs.pixels = {p};
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(
      Messages(f),
      ElementsAre("pixels.csv:2: column 'X': expected a known point in metres within "
                  "screen.max_extent_m = 10000 m of the origin (SPEC 1); it is 12379.4 m away; "
                  "the coordinates look like millimetres, got '12000, 3000, 500'"));
  options.max_extent_m = 20000;
  EXPECT_THAT(Messages(FindDataMistakes(obs, truth.cams, options)), IsEmpty());
}

TEST_F(ScreenTest, ZoomFarBeyondTheData) {
  for (int zoom : {1000000, INT_MAX}) {
    Observations o = obs;
    Record& r = FirstRow(&o, 1, Tool::kCam);
    r.zoom = zoom;
    const ScreenFindings f = FindDataMistakes(o, truth.cams, options);
    EXPECT_THAT(
        Messages(f),
        ElementsAre(
            std::string("records.csv:4: column 'zoom': expected a zoom level below 10 (SPEC 2: "
                        "zoom levels are 0..N-1; the data hold 2 zoom levels (0, ") +
            std::to_string(zoom) +
            "), model.cameras lists 1, and screen.max_missing_zooms = 8 more may lack data), "
            "got '" +
            std::to_string(zoom) + "'"))
        << zoom;
  }
}

TEST_F(ScreenTest, PixelsFileIsScreenedLikeRecords) {
  PixelObservation p;
  p.line = 2;
  p.face = 2;
  p.phi = 1.0;
  p.theta = 1.2;  // face 2 written the face-1 way
  p.X = {1.0, 2.0, 0.5};
  p.uv = {640, 1100};  // below the 960 px image by more than 50 px; one row is not "swapped"
  obs.pixels = {p};
  p.line = 3;
  p.face = 1;
  p.zoom = 40;
  p.uv = {640, 480};
  obs.pixels.push_back(p);
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(
      Messages(f),
      ElementsAre(
          "pixels.csv:3: column 'zoom': expected a zoom level below 10 (SPEC 2: zoom levels are "
          "0..N-1; the data hold 2 zoom levels (0, 40), model.cameras lists 1, and "
          "screen.max_missing_zooms = 8 more may lack data), got '40'",
          "pixels.csv:2: column 'theta': expected a face-2 zenith angle in [pi, 2 pi] (SPEC 1: "
          "face 2 of the face-1 pointing (phi, theta) is (phi - pi mod 2 pi, 2 pi - theta)); this "
          "face-2 row is written the face-1 way, got '1.2'",
          "pixels.csv:2: column 'v': expected a pixel row v within the image of zoom 0, -0.5 .. "
          "959.5 give or take screen.pixel_margin_px = 50 px (model.cameras[0]: 1280 x 960 px), "
          "got '1100'"));
}

TEST_F(ScreenTest, MissingZoomLevelsAreAWarning) {
  FirstRow(&obs, 1, Tool::kCam).zoom = 3;
  const ScreenFindings f = FindDataMistakes(obs, truth.cams, options);
  EXPECT_THAT(Messages(f), IsEmpty());
  EXPECT_THAT(f.warnings,
              ElementsAre("zoom levels 1, 2 have no camera rows and no pixels (the data use 0, 3); "
                          "their cameras are not calibrated"));
}

TEST_F(ScreenTest, OneToolOnlyIsAWarning) {
  Observations cam_only = obs, edm_only = obs;
  cam_only.records.clear();
  edm_only.records.clear();
  for (const Record& r : obs.records) {
    (r.tool == Tool::kCam ? cam_only : edm_only).records.push_back(r);
  }
  EXPECT_THAT(FindDataMistakes(cam_only, truth.cams, options).warnings,
              ElementsAre("records.csv has camera rows only (no edm rows): the EDM tool is not "
                          "determined and keeps its starting pose"));
  EXPECT_THAT(
      FindDataMistakes(edm_only, truth.cams, options).warnings,
      ElementsAre("records.csv has EDM rows only (no cam rows) and there are no pixels: the "
                  "camera tools are not determined"));
}

TEST_F(ScreenTest, ScreenObservationsThrowsAllErrorsAtOnce) {
  for (Record& r : obs.records) {
    if (r.face == 2) r.theta = 1.0;
  }
  FirstRow(&obs, 1, Tool::kCam).v = -500;
  try {
    ScreenObservations(obs, truth.cams, options);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "records.csv:152: column 'theta': expected a face-2 zenith angle in [pi, 2 "
              "pi] (SPEC 1: face 2 of the face-1 pointing (phi, theta) is (phi - pi mod 2 "
              "pi, 2 pi - theta)); this face-2 row is written the face-1 way; also lines 153, "
              "154, 155, 156, 157 and 144 more rows, got '1'\nrecords.csv:4: column 'v': expected "
              "a pixel row v within the image of "
              "zoom 0, -0.5 .. 959.5 give or take screen.pixel_margin_px = 50 px "
              "(model.cameras[0]: 1280 x 960 px), got '-500'");
  }
}

TEST(ScreenOptions, CheckNamesTheKey) {
  ScreenOptions o;
  EXPECT_EQ(o.Check(), "");
  o.max_missing_zooms = 5000;
  EXPECT_EQ(o.Check(), "screen.max_missing_zooms must be in 0..1000 (got 5000)");
  o = ScreenOptions();
  o.pixel_margin_px = -1;
  EXPECT_EQ(o.Check(), "screen.pixel_margin_px must be a finite number >= 0 [px]");
  o = ScreenOptions();
  o.max_extent_m = 0;
  EXPECT_EQ(o.Check(), "screen.max_extent_m must be a finite number > 0 [m]");
  EXPECT_THROW(FindDataMistakes(Observations(), {}, o), std::invalid_argument);
}

}  // namespace
}  // namespace rtscalib
