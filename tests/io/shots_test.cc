#include "libcalib/io/shots.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;
using testing_io::TempDir;

constexpr const char* kShotsHeader = "face,zoom,phi,theta,image\n";

// shots.csv in `dir` with `text`, plus the image files it may name.
InputError ShotsError(const TempDir& dir, const std::string& text) {
  dir.Write("photos/a.png", "not read by ReadShots");
  dir.Write("photos/b.png", "not read by ReadShots");
  const std::string path = dir.Write("shots.csv", text);
  return CatchInputError([&] { ReadShots(path); });
}

// A bad cell on data line 3 (line 1 comment, line 2 header).
void ExpectCellError(const std::string& row, const std::string& column, const std::string& got,
                     const std::string& expected) {
  TempDir dir;
  const InputError e = ShotsError(dir, std::string("# test\n") + kShotsHeader + row);
  EXPECT_EQ(e.file, dir.Path("shots.csv"));
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, column);
  EXPECT_EQ(e.got, got);
  EXPECT_EQ(e.expected, expected);
  EXPECT_THAT(e.what(), HasSubstr(dir.Path("shots.csv") + ":3: column '" + column + "'"));
}

TEST(Shots, ReadsAnyColumnOrderWithCommentsAndResolvesImagesAgainstTheCsvFolder) {
  TempDir dir;
  dir.Write("data/photos/p1.png", "x");
  dir.Write("data/photos/p2.tif", "x");
  const std::string path = dir.Write("data/shots.csv",
                                     "# instrument export\n"
                                     "image, theta, phi, zoom, face, shot\n"
                                     "photos/p1.png, 1.5, 0.25, 0, 1, first\n"
                                     "# a comment between rows\n"
                                     "photos/p2.tif, 4.5, 3.5, 2, 2,\n");
  const ShotsFile file = ReadShots(path);
  ASSERT_EQ(file.shots.size(), 2u);
  EXPECT_TRUE(file.notes.empty());
  const PhotoShot& a = file.shots[0];
  EXPECT_EQ(a.line, 3);
  EXPECT_EQ(a.face, 1);
  EXPECT_EQ(a.zoom, 0);
  EXPECT_EQ(a.phi, 0.25);
  EXPECT_EQ(a.theta, 1.5);
  EXPECT_EQ(a.image, "photos/p1.png");
  EXPECT_EQ(a.image_path, dir.Path("data/photos/p1.png"));
  EXPECT_EQ(a.shot, "first");
  const PhotoShot& b = file.shots[1];
  EXPECT_EQ(b.line, 5);
  EXPECT_EQ(b.face, 2);
  EXPECT_EQ(b.zoom, 2);
  // An empty shot cell falls back to the image's stem.
  EXPECT_EQ(b.shot, "p2");
}

TEST(Shots, ShotColumnIsOptionalAndExtraColumnsAreNoted) {
  TempDir dir;
  const std::string path = dir.Write("shots.csv",
                                     "face,zoom,phi,theta,image,exposure\n"
                                     "1,0,0,1.5,img_007.jpg,0.01\n");
  dir.Write("img_007.jpg", "x");
  const ShotsFile file = ReadShots(path);
  ASSERT_EQ(file.shots.size(), 1u);
  EXPECT_EQ(file.shots[0].shot, "img_007");
  ASSERT_EQ(file.notes.size(), 1u);
  EXPECT_THAT(file.notes[0], HasSubstr("exposure"));
}

TEST(Shots, MissingRequiredColumnIsNamed) {
  TempDir dir;
  const InputError e = ShotsError(dir, "face,zoom,phi,image\n1,0,0,photos/a.png\n");
  EXPECT_EQ(e.line, 1);
  EXPECT_EQ(e.column, "theta");
  EXPECT_THAT(e.what(), HasSubstr("a column named 'theta' in the header"));
}

TEST(Shots, MissingHeaderOrRowsIsAnError) {
  TempDir dir;
  EXPECT_EQ(ShotsError(dir, "# nothing\n").subject, "no rows");
  EXPECT_EQ(ShotsError(dir, kShotsHeader).subject, "no rows");
}

TEST(Shots, BadCellsNameLineColumnExpectedAndGot) {
  ExpectCellError("3,0,0,1.5,photos/a.png\n", "face", "3", "1 or 2");
  ExpectCellError("1,-1,0,1.5,photos/a.png\n", "zoom", "-1", "a zoom level (integer >= 0)");
  ExpectCellError("1,0.5,0,1.5,photos/a.png\n", "zoom", "0.5", "a zoom level (integer >= 0)");
  ExpectCellError("1,0,east,1.5,photos/a.png\n", "phi", "east", "a finite number");
  ExpectCellError("1,0,0,nan,photos/a.png\n", "theta", "nan", "a finite number");
  ExpectCellError("1,0,0,1.5,\n", "image", "", "an image file (relative to the CSV's folder)");
}

TEST(Shots, MissingImageNamesLineAndPath) {
  TempDir dir;
  const InputError e =
      ShotsError(dir, std::string(kShotsHeader) + "1,0,0,1.5,photos/a.png\n1,0,0,1.5,photos/c.png\n");
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, "image");
  EXPECT_EQ(e.got, dir.Path("photos/c.png"));
  EXPECT_EQ(e.expected, "an existing image file");
  EXPECT_THAT(e.what(), HasSubstr(":3: column 'image'"));
  EXPECT_THAT(e.what(), HasSubstr(dir.Path("photos/c.png")));
}

TEST(Shots, DuplicateShotIdsNameBothLines) {
  TempDir dir;
  // Two folders, one stem: the default ids collide.
  dir.Write("x/a.png", "x");
  InputError e = ShotsError(dir, std::string(kShotsHeader) +
                                     "1,0,0,1.5,photos/a.png\n"
                                     "# comment\n"
                                     "2,0,0,1.5,x/a.png\n");
  EXPECT_EQ(e.line, 4);
  EXPECT_EQ(e.column, "image");
  EXPECT_EQ(e.got, "a");
  EXPECT_THAT(e.expected, HasSubstr("line 2"));
  e = ShotsError(dir,
                 "face,zoom,phi,theta,image,shot\n"
                 "1,0,0,1.5,photos/a.png,s1\n"
                 "1,0,0,1.5,photos/b.png,s1\n");
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, "shot");
  EXPECT_EQ(e.got, "s1");
  EXPECT_THAT(e.expected, HasSubstr("line 2"));
}

TEST(Shots, UnreadableFileIsAnError) {
  const InputError e = CatchInputError([] { ReadShots("/nonexistent/shots.csv"); });
  EXPECT_EQ(e.file, "/nonexistent/shots.csv");
  EXPECT_EQ(e.subject, "cannot open file");
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// data.angle_unit for shots.csv: degrees and gon give the photos' readings in
// radians to 1e-15 relative (17-digit text, a division by 180 or 200 and a
// multiplication by pi: ~3 ulp, tests/io/records_test.cc), and the file
// keeps its unit.
TEST(ShotsAngleUnit, DegreesAndGonGiveTheRadianReadings) {
  TempDir dir;
  dir.Write("a.png", "x");
  dir.Write("b.png", "x");
  const double phi[2] = {0.123456789012345, 5.4321098765432};
  const double theta[2] = {1.5707963267948966, 4.6};  // face 1, face 2
  auto file = [&](const char* name, double scale) {
    std::string text = kShotsHeader;
    for (int i = 0; i < 2; ++i) {
      char row[160];
      std::snprintf(row, sizeof row, "%d,1,%.17g,%.17g,%s\n", i + 1, phi[i] * scale,
                    theta[i] * scale, i == 0 ? "a.png" : "b.png");
      text += row;
    }
    return dir.Write(name, text);
  };
  const ShotsFile rad = ReadShots(file("rad.csv", 1.0));
  const ShotsFile deg = ReadShots(file("deg.csv", 180.0 / M_PI), AngleUnit::kDeg);
  const ShotsFile gon = ReadShots(file("gon.csv", 200.0 / M_PI), AngleUnit::kGon);
  EXPECT_EQ(rad.angle_unit, AngleUnit::kRad);
  EXPECT_EQ(deg.angle_unit, AngleUnit::kDeg);
  EXPECT_EQ(gon.angle_unit, AngleUnit::kGon);
  constexpr double kRel = 1e-15;
  for (int i = 0; i < 2; ++i) {
    for (const ShotsFile* f : {&deg, &gon}) {
      EXPECT_NEAR(f->shots[i].phi, rad.shots[i].phi, kRel * rad.shots[i].phi);
      EXPECT_NEAR(f->shots[i].theta, rad.shots[i].theta, kRel * rad.shots[i].theta);
      EXPECT_EQ(f->shots[i].shot, rad.shots[i].shot);
      EXPECT_EQ(f->shots[i].face, rad.shots[i].face);
    }
  }
}

// SPEC 7.1: the optional `placement` column, readings left empty for a
// camera-only session, and SPEC 4.1's optional focus distance.
TEST(Shots, PlacementsEmptyReadingsAndFocusDistance) {
  TempDir dir;
  dir.Write("a.png", "x");
  dir.Write("b.png", "x");
  const std::string path = dir.Write("shots.csv",
                                     "face,zoom,phi,theta,image,placement,focus_distance\n"
                                     "1,0,,,a.png,wall-1,12.5\n"
                                     "2,1,3.3,4.8,b.png,,\n");
  const ShotsFile file = ReadShots(path);
  EXPECT_TRUE(file.has_placements);
  ASSERT_EQ(file.shots.size(), 2u);
  EXPECT_FALSE(file.shots[0].has_reading);
  EXPECT_EQ(file.shots[0].placement, "wall-1");
  EXPECT_EQ(file.shots[0].focus_distance, 12.5);
  EXPECT_TRUE(file.shots[1].has_reading);
  EXPECT_EQ(file.shots[1].phi, 3.3);
  EXPECT_EQ(file.shots[1].placement, "");
  EXPECT_EQ(file.shots[1].focus_distance, 0.0);
  // Without the column: one placement.
  EXPECT_FALSE(ReadShots(dir.Write("one.csv", std::string(kShotsHeader) + "1,0,0.1,1.5,a.png\n"))
                   .has_placements);
}

TEST(Shots, OneReadingWithoutTheOtherIsAnError) {
  ExpectCellError("1,0,,1.5,photos/a.png\n", "phi", "",
                  "a reading beside theta (both phi and theta, or neither for a camera-only "
                  "calibration)");
  TempDir dir;
  dir.Write("a.png", "x");
  const InputError e = CatchInputError([&] {
    ReadShots(dir.Write("f.csv", "face,zoom,phi,theta,image,focus_distance\n1,0,0,1.5,a.png,-2\n"));
  });
  EXPECT_EQ(e.line, 2);
  EXPECT_EQ(e.column, "focus_distance");
}

}  // namespace
}  // namespace rtscalib
