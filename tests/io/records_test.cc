#include "libcalib/io/records.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "libcalib/io/csv.h"
#include "libcalib/text/number_text.h"
#include "tests/io/io_test_util.h"

namespace rtscalib {
namespace {

using ::testing::HasSubstr;
using testing_io::CatchInputError;
using testing_io::TempDir;

constexpr const char* kHeader = "face,zoom,phi,theta,tool,u,v,d,x,y,z,set\n";
constexpr const char* kEdmRow = "1,0,0.5,1.5,edm,,,2,0.1,0.2,0.3,sweep1\n";

// Writes header + rows, reads it, and returns the error (which must come).
InputError RecordsError(const TempDir& dir, const std::string& text) {
  const std::string path = dir.Write("records.csv", text);
  return CatchInputError([&] { ReadRecords(path); });
}

// Checks that a bad cell on data line 3 (line 1 comment, line 2 header) is
// reported with file, line and column in the message.
void ExpectCellError(const TempDir& dir, const std::string& row, const std::string& column,
                     const std::string& got) {
  const InputError e = RecordsError(dir, std::string("# test\n") + kHeader + row);
  EXPECT_EQ(e.file, dir.Path("records.csv"));
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, column);
  EXPECT_EQ(e.got, got);
  EXPECT_THAT(e.what(), HasSubstr(dir.Path("records.csv") + ":3: column '" + column + "'"));
}

TEST(Records, ReadsEdmAndCamRowsWithCommentsInAnyColumnOrder) {
  TempDir dir;
  const std::string path = dir.Write("records.csv",
                                     "# device export\n"
                                     "set , tool, d, z, y, x, theta, phi, zoom, face, v, u\n"
                                     "\n"
                                     "grid, edm, 2.5, 3, 2, 1, 1.5, 0.25, , 2, ,\n"
                                     "# a comment between rows\n"
                                     "train, cam, 1, -3, -2, -1, 1.25, 0.5, 1, 1, 240.5, 320.25\n");
  const RecordsFile file = ReadRecords(path);
  ASSERT_EQ(file.records.size(), 2u);
  EXPECT_TRUE(file.notes.empty());
  const Record& edm = file.records[0];
  EXPECT_EQ(edm.line, 4);
  EXPECT_EQ(edm.face, 2);
  EXPECT_EQ(edm.zoom, 0);
  EXPECT_EQ(edm.tool, Tool::kEdm);
  EXPECT_EQ(edm.phi, 0.25);
  EXPECT_EQ(edm.theta, 1.5);
  EXPECT_EQ(edm.d, 2.5);
  EXPECT_EQ(edm.x, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(edm.set, "grid");
  const Record& cam = file.records[1];
  EXPECT_EQ(cam.line, 6);
  EXPECT_EQ(cam.tool, Tool::kCam);
  EXPECT_EQ(cam.zoom, 1);
  EXPECT_EQ(cam.u, 320.25);
  EXPECT_EQ(cam.v, 240.5);
  EXPECT_EQ(cam.set, "train");
}

TEST(Records, SetColumnMayBeAbsentAndEdmRowsNeedNoUV) {
  TempDir dir;
  const std::string path =
      dir.Write("records.csv", "face,zoom,phi,theta,tool,d,x,y,z\n1,0,0,1.5,edm,1,0,1,0\n");
  const RecordsFile file = ReadRecords(path);
  ASSERT_EQ(file.records.size(), 1u);
  EXPECT_EQ(file.records[0].set, "");
}

TEST(Records, MissingColumnNamesFileAndColumn) {
  TempDir dir;
  const InputError e =
      RecordsError(dir, "face,zoom,phi,theta,tool,u,v,x,y,z\n1,0,0,1.5,edm,,,0,1,0\n");
  EXPECT_EQ(e.column, "d");
  EXPECT_EQ(e.line, 1);
  EXPECT_THAT(e.what(), HasSubstr(dir.Path("records.csv") + ":1: column 'd'"));
  EXPECT_THAT(e.what(), HasSubstr("face, zoom, phi, theta, tool, u, v, x, y, z"));
}

TEST(Records, AllMissingColumnsAreListed) {
  TempDir dir;
  const InputError e = RecordsError(dir, "face,zoom,phi,theta,tool,u,v,y\n1,0,0,1.5,edm,,,1\n");
  EXPECT_EQ(e.column, "d");
  EXPECT_THAT(e.expected, HasSubstr("also missing: x, z"));
}

TEST(Records, UnknownTool) {
  TempDir dir;
  ExpectCellError(dir, "1,0,0.5,1.5,gps,,,2,0.1,0.2,0.3,\n", "tool", "gps");
}

TEST(Records, FaceMustBeOneOrTwo) {
  TempDir dir;
  ExpectCellError(dir, "3,0,0.5,1.5,edm,,,2,0.1,0.2,0.3,\n", "face", "3");
  ExpectCellError(dir, "0,0,0.5,1.5,edm,,,2,0.1,0.2,0.3,\n", "face", "0");
  ExpectCellError(dir, "1.5,0,0.5,1.5,edm,,,2,0.1,0.2,0.3,\n", "face", "1.5");
}

TEST(Records, NegativeZoom) {
  TempDir dir;
  ExpectCellError(dir, "1,-1,0.5,1.5,cam,1,2,2,0.1,0.2,0.3,\n", "zoom", "-1");
  ExpectCellError(dir, "1,-1,0.5,1.5,edm,,,2,0.1,0.2,0.3,\n", "zoom", "-1");
  ExpectCellError(dir, "1,0.5,0.5,1.5,cam,1,2,2,0.1,0.2,0.3,\n", "zoom", "0.5");
  ExpectCellError(dir, "1,,0.5,1.5,cam,1,2,2,0.1,0.2,0.3,\n", "zoom", "");
}

TEST(Records, DistanceMustBePositive) {
  TempDir dir;
  ExpectCellError(dir, "1,0,0.5,1.5,edm,,,0,0.1,0.2,0.3,\n", "d", "0");
  ExpectCellError(dir, "1,0,0.5,1.5,cam,1,2,-1,0.1,0.2,0.3,\n", "d", "-1");
}

TEST(Records, NanInfAndTextAreRejected) {
  TempDir dir;
  ExpectCellError(dir, "1,0,0.5,1.5,edm,,,2,nan,0.2,0.3,\n", "x", "nan");
  ExpectCellError(dir, "1,0,0.5,1.5,edm,,,2,0.1,NaN,0.3,\n", "y", "NaN");
  ExpectCellError(dir, "1,0,inf,1.5,edm,,,2,0.1,0.2,0.3,\n", "phi", "inf");
  ExpectCellError(dir, "1,0,0.5,-Infinity,edm,,,2,0.1,0.2,0.3,\n", "theta", "-Infinity");
  ExpectCellError(dir, "1,0,0.5,abc,edm,,,2,0.1,0.2,0.3,\n", "theta", "abc");
  ExpectCellError(dir, "1,0,0.5,1.5,edm,,,2,0.1,0.2,1.2.3,\n", "z", "1.2.3");
  ExpectCellError(dir, "1,0,0.5,1.5,edm,,,2 m,0.1,0.2,0.3,\n", "d", "2 m");
  ExpectCellError(dir, "1,0,0.5,1.5,edm,,,2,0.1,,0.3,\n", "y", "");
}

TEST(Records, CamRowsNeedPixels) {
  TempDir dir;
  ExpectCellError(dir, "1,0,0.5,1.5,cam,,240,1,0.1,0.2,0.3,\n", "u", "");
  ExpectCellError(dir, "1,0,0.5,1.5,cam,320,,1,0.1,0.2,0.3,\n", "v", "");
  // A file without u/v columns may hold edm rows only.
  const InputError e = RecordsError(
      dir, "face,zoom,phi,theta,tool,d,x,y,z\n1,0,0,1.5,edm,1,0,1,0\n1,0,0,1.5,cam,1,0,1,0\n");
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, "u");
}

// An extra column of numbers (temperature, time) is kept as a covariate
// that the diagnosis tests the residuals against; another extra column is
// ignored with a note. Both are said; the writer gives the covariates back.
TEST(Records, ExtraNumericColumnIsKeptAsACovariate) {
  TempDir dir;
  const std::string path = dir.Write("records.csv",
                                     "face,zoom,phi,theta,tool,u,v,d,x,y,z,set,temperature,who\n"
                                     "1,0,0.5,1.5,edm,,,2,0.1,0.2,0.3,,21.5,ann\n"
                                     "1,0,0.6,1.5,edm,,,2,0.1,0.2,0.3,,,bob\n");
  const RecordsFile file = ReadRecords(path);
  ASSERT_EQ(file.records.size(), 2u);
  EXPECT_EQ(file.covariates, std::vector<std::string>{"temperature"});
  EXPECT_EQ(file.records[0].covariates, std::vector<double>{21.5});
  ASSERT_EQ(file.records[1].covariates.size(), 1u);
  EXPECT_TRUE(std::isnan(file.records[1].covariates[0]));
  ASSERT_EQ(file.notes.size(), 2u);
  EXPECT_THAT(file.notes[0], HasSubstr(path + ":1"));
  EXPECT_THAT(file.notes[0], HasSubstr("temperature kept as covariate"));
  EXPECT_THAT(file.notes[1], HasSubstr("ignored column who"));
  const std::string out = dir.Path("out.csv");
  WriteRecords(out, file.records, AngleUnit::kRad, file.covariates);
  const RecordsFile back = ReadRecords(out);
  EXPECT_EQ(back.covariates, file.covariates);
  EXPECT_EQ(back.records[0].covariates, file.records[0].covariates);
  EXPECT_TRUE(std::isnan(back.records[1].covariates[0]));
}

TEST(Records, WrongFieldCountNamesTheLine) {
  TempDir dir;
  const InputError e = RecordsError(dir, std::string(kHeader) + kEdmRow + "1,0,0.5,1.5,edm\n");
  EXPECT_EQ(e.line, 3);
  EXPECT_THAT(e.what(), HasSubstr(":3: row: expected 12 fields"));
}

TEST(Records, EmptyFileAndHeaderOnlyHaveNoRows) {
  TempDir dir;
  for (const std::string& text : std::vector<std::string>{
           "", "# only a comment\n\n", kHeader, "# c\n" + std::string(kHeader) + "# c\n"}) {
    const InputError e = RecordsError(dir, text);
    EXPECT_THAT(e.what(), HasSubstr("no rows")) << text;
    EXPECT_EQ(e.file, dir.Path("records.csv"));
  }
}

TEST(Records, WriteThenReadIsBitExact) {
  TempDir dir;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unif(-10, 10);
  std::vector<Record> records;
  for (int i = 0; i < 200; ++i) {
    Record r;
    r.face = 1 + i % 2;
    r.zoom = i % 3;
    r.phi = unif(rng);
    r.theta = unif(rng);
    r.tool = i % 4 == 0 ? Tool::kCam : Tool::kEdm;
    if (r.tool == Tool::kCam) {
      r.u = unif(rng) * 100;
      r.v = unif(rng) * 100;
    }
    r.d = std::abs(unif(rng)) + 1e-3;
    r.x = Eigen::Vector3d(unif(rng), unif(rng), unif(rng)) / 3.0;
    r.set = i % 5 == 0 ? "held, out \"A\"" : (i % 5 == 1 ? "" : "sweep1");
    records.push_back(r);
  }
  const std::string path = dir.Path("out.csv");
  WriteRecords(path, records);
  const RecordsFile back = ReadRecords(path);
  ASSERT_EQ(back.records.size(), records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    const Record& a = records[i];
    const Record& b = back.records[i];
    EXPECT_EQ(b.line, static_cast<int>(i) + 2);
    EXPECT_EQ(a.face, b.face);
    EXPECT_EQ(a.zoom, b.zoom);
    EXPECT_EQ(a.phi, b.phi);
    EXPECT_EQ(a.theta, b.theta);
    EXPECT_EQ(a.tool, b.tool);
    EXPECT_EQ(a.u, b.u);
    EXPECT_EQ(a.v, b.v);
    EXPECT_EQ(a.d, b.d);
    EXPECT_EQ(a.x, b.x);
    EXPECT_EQ(a.set, b.set);
  }
}

// --- pixels.csv ---------------------------------------------------------------

constexpr const char* kPixelsHeader = "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n";

InputError PixelsError(const TempDir& dir, const std::string& text) {
  const std::string path = dir.Write("pixels.csv", text);
  return CatchInputError([&] { ReadPixels(path); });
}

TEST(Pixels, ReadsRowsInAnyOrder) {
  TempDir dir;
  const std::string path = dir.Write("pixels.csv",
                                     "u,v,X,Y,Z,corner,target,shot,theta,phi,zoom,face\n"
                                     "# shot s0\n"
                                     "10.5,20.25,1,2,3,3,17,s0,1.5,0.5,2,2\n");
  const PixelsFile file = ReadPixels(path);
  ASSERT_EQ(file.pixels.size(), 1u);
  const PixelObservation& p = file.pixels[0];
  EXPECT_EQ(p.line, 3);
  EXPECT_EQ(p.face, 2);
  EXPECT_EQ(p.zoom, 2);
  EXPECT_EQ(p.shot, "s0");
  EXPECT_EQ(p.target, 17);
  EXPECT_EQ(p.corner, 3);
  EXPECT_EQ(p.X, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.uv, Eigen::Vector2d(10.5, 20.25));
}

TEST(Pixels, BadCellsNameLineAndColumn) {
  TempDir dir;
  struct Case {
    std::string row, column, got;
  };
  for (const Case& c : std::vector<Case>{{"1,0,0,1,s,1,4,0,0,0,1,1", "corner", "4"},
                                         {"1,0,0,1,s,-2,0,0,0,0,1,1", "target", "-2"},
                                         {"3,0,0,1,s,1,0,0,0,0,1,1", "face", "3"},
                                         {"1,-1,0,1,s,1,0,0,0,0,1,1", "zoom", "-1"},
                                         {"1,0,0,1,,1,0,0,0,0,1,1", "shot", ""},
                                         {"1,0,0,1,s,1,0,0,0,0,nan,1", "u", "nan"},
                                         {"1,0,0,1,s,1,0,0,inf,0,1,1", "Y", "inf"}}) {
    const InputError e = PixelsError(dir, std::string(kPixelsHeader) + c.row + "\n");
    EXPECT_EQ(e.line, 2) << c.row;
    EXPECT_EQ(e.column, c.column) << c.row;
    EXPECT_EQ(e.got, c.got) << c.row;
    EXPECT_THAT(e.what(), HasSubstr("pixels.csv:2: column '" + c.column + "'"));
  }
}

TEST(Pixels, MissingColumnAndNoRows) {
  TempDir dir;
  const InputError missing =
      PixelsError(dir, "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u\n1,0,0,1,s,1,0,0,0,0,1\n");
  EXPECT_EQ(missing.column, "v");
  EXPECT_THAT(PixelsError(dir, kPixelsHeader).what(), HasSubstr("no rows"));
}

TEST(Pixels, WriteThenReadIsBitExact) {
  TempDir dir;
  std::vector<PixelObservation> pixels;
  for (int i = 0; i < 20; ++i) {
    PixelObservation p;
    p.face = 1 + i % 2;
    p.zoom = i % 3;
    p.phi = 0.1 * i / 3.0;
    p.theta = 1.0 + i / 7.0;
    p.shot = "z" + std::to_string(p.zoom) + "_s" + std::to_string(i / 4);
    p.target = i / 4;
    p.corner = i % 4;
    p.X = Eigen::Vector3d(i / 3.0, -i / 7.0, 2.0 / (i + 1));
    p.uv = Eigen::Vector2d(100.0 / 3.0 + i, 200.0 / 7.0 + i);
    pixels.push_back(p);
  }
  WritePixels(dir.Path("p.csv"), pixels);
  const PixelsFile back = ReadPixels(dir.Path("p.csv"));
  ASSERT_EQ(back.pixels.size(), pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) {
    EXPECT_EQ(back.pixels[i].face, pixels[i].face);
    EXPECT_EQ(back.pixels[i].zoom, pixels[i].zoom);
    EXPECT_EQ(back.pixels[i].phi, pixels[i].phi);
    EXPECT_EQ(back.pixels[i].theta, pixels[i].theta);
    EXPECT_EQ(back.pixels[i].shot, pixels[i].shot);
    EXPECT_EQ(back.pixels[i].target, pixels[i].target);
    EXPECT_EQ(back.pixels[i].corner, pixels[i].corner);
    EXPECT_EQ(back.pixels[i].X, pixels[i].X);
    EXPECT_EQ(back.pixels[i].uv, pixels[i].uv);
  }
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

using testing_io::CatchInputError;
using testing_io::TempDir;

// SPEC 7: a `point` column names a fixed point of unknown position; its rows
// may leave x, y, z empty, other rows still may not.
TEST(RecordsPoints, PointRowsMayLeaveXyzEmpty) {
  TempDir dir;
  const std::string path = dir.Write("records.csv",
                                     "face,zoom,phi,theta,tool,d,x,y,z,point\n"
                                     "1,,0.5,1.5,edm,12.5,,,,P1\n"
                                     "2,,3.6,4.7,edm,12.5,,,,P1\n"
                                     "1,,0.5,1.5,edm,2,0.1,0.2,0.3,\n");
  const RecordsFile file = ReadRecords(path);
  ASSERT_EQ(file.records.size(), 3u);
  EXPECT_EQ(file.records[0].point, "P1");
  EXPECT_EQ(file.records[1].point, "P1");
  EXPECT_EQ(file.records[2].point, "");
  EXPECT_EQ(file.records[2].x, Eigen::Vector3d(0.1, 0.2, 0.3));
  // Written back with the point column and empty x, y, z; read back equal.
  WriteRecords(dir.Path("out.csv"), file.records);
  const RecordsFile back = ReadRecords(dir.Path("out.csv"));
  ASSERT_EQ(back.records.size(), 3u);
  EXPECT_EQ(back.records[1].point, "P1");
  EXPECT_EQ(back.records[2].x, file.records[2].x);
}

TEST(RecordsPoints, EmptyXyzWithoutPointIsAnErrorNamingLineAndColumn) {
  TempDir dir;
  const std::string path = dir.Write("records.csv",
                                     "face,zoom,phi,theta,tool,d,x,y,z,point\n"
                                     "1,,0.5,1.5,edm,12.5,,,,P1\n"
                                     "1,,0.5,1.5,edm,2,,0.2,0.3,\n");
  const InputError e = CatchInputError([&] { ReadRecords(path); });
  EXPECT_EQ(e.line, 3);
  EXPECT_EQ(e.column, "x");
}

// SPEC 7: pixels.csv rows with X, Y, Z all empty are corners of a board
// without a pose (X_known false); partly empty stays an error.
TEST(PixelsBoards, EmptyXyzMeansABoardCorner) {
  TempDir dir;
  const std::string header = "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n";
  const std::string path = dir.Write("pixels.csv", header +
                                                       "1,0,0.5,1.5,s1,48,2,,,,100.5,200.25\n"
                                                       "1,0,0.5,1.5,s1,1,0,1,2,3,10,20\n");
  const PixelsFile file = ReadPixels(path);
  ASSERT_EQ(file.pixels.size(), 2u);
  EXPECT_FALSE(file.pixels[0].X_known);
  EXPECT_EQ(file.pixels[0].target, 48);
  EXPECT_TRUE(file.pixels[1].X_known);
  WritePixels(dir.Path("out.csv"), file.pixels);
  const PixelsFile back = ReadPixels(dir.Path("out.csv"));
  ASSERT_EQ(back.pixels.size(), 2u);
  EXPECT_FALSE(back.pixels[0].X_known);
  EXPECT_EQ(back.pixels[0].uv, file.pixels[0].uv);
  EXPECT_EQ(back.pixels[1].X, Eigen::Vector3d(1, 2, 3));

  const std::string bad = dir.Write("bad.csv", header + "1,0,0.5,1.5,s1,48,2,,1,,100.5,200.25\n");
  const InputError e = CatchInputError([&] { ReadPixels(bad); });
  EXPECT_EQ(e.line, 2);
  EXPECT_EQ(e.column, "X");
}

// The image size columns `rtscalib detect` writes (SPEC 7: sizes come from
// the images): one size per zoom; both columns or neither.
TEST(PixelsBoards, ImageSizesComeWithTheRows) {
  TempDir dir;
  const std::string header = "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v,width,height\n";
  const PixelsFile f = ReadPixels(dir.Write("pixels.csv", header +
                                                              "1,0,0.5,1.5,s1,48,2,,,,100,200,1280,960\n"
                                                              "1,1,0.5,1.5,s2,48,2,,,,100,200,2592,1944\n"
                                                              "1,1,0.5,1.5,s3,48,2,,,,100,200,,\n"));
  ASSERT_EQ(f.image_sizes.size(), 2u);
  EXPECT_EQ(f.image_sizes.at(0).width, 1280);
  EXPECT_EQ(f.image_sizes.at(1).height, 1944);
  EXPECT_TRUE(ReadPixels(dir.Write("plain.csv", std::string(kPixelsHeader) + "1,0,0,1,s,1,0,0,0,0,1,1\n"))
                  .image_sizes.empty());

  const InputError other = CatchInputError([&] {
    ReadPixels(dir.Write("two.csv", header + "1,0,0.5,1.5,s1,48,2,,,,100,200,1280,960\n"
                                             "1,0,0.5,1.5,s2,48,2,,,,100,200,1280,720\n"));
  });
  EXPECT_EQ(other.line, 3);
  EXPECT_EQ(other.column, "height");
  EXPECT_THAT(other.what(), HasSubstr("expected the image size 1280x960 of zoom 0 (line 2; one "
                                      "camera per zoom level, SPEC 2), got '720'"));
  const InputError half = CatchInputError([&] {
    ReadPixels(dir.Write("half.csv", "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v,width\n"
                                     "1,0,0.5,1.5,s1,48,2,,,,100,200,1280\n"));
  });
  EXPECT_EQ(half.column, "width");
  EXPECT_THAT(half.what(), HasSubstr("a 'height' column beside 'width' (the image size: both "
                                     "columns or neither)"));
  const InputError zero = CatchInputError([&] {
    ReadPixels(dir.Write("zero.csv", header + "1,0,0.5,1.5,s1,48,2,,,,100,200,0,960\n"));
  });
  EXPECT_EQ(zero.column, "width");
}

}  // namespace
}  // namespace rtscalib

namespace rtscalib {
namespace {

// data.angle_unit (libcalib/model/angle_unit.h): readings written in degrees
// or gon give the observations of the same readings written in radians.
// Tolerance 1e-15 relative (the issue's): each file holds the reading with
// 17 significant digits (exact to 0.5 ulp; the test's own scaling of the
// radians adds 0.5-1 ulp) and the reader divides by 180 or 200 and
// multiplies by pi (0.5 ulp each), so deg and gon differ from the radians by
// at most ~3 ulp = 6.7e-16 relative.
constexpr double kUnitRelTolerance = 1e-15;

std::string AngleRows(double scale, const std::vector<std::pair<double, double>>& angles) {
  std::string text = kHeader;
  for (size_t i = 0; i < angles.size(); ++i) {
    const bool edm = i % 2 == 0;
    text += std::string(i % 3 == 0 ? "2" : "1") + ",1," + FormatDouble(angles[i].first * scale) +
            "," + FormatDouble(angles[i].second * scale) +
            (edm ? ",edm,,," : ",cam,320.5,240.25,") + "2.5,0.1,0.2,0.3,grid\n";
  }
  return text;
}

std::vector<std::pair<double, double>> RandomReadings(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phi(0, 2 * M_PI), theta(0.2, 2 * M_PI - 0.2);
  std::vector<std::pair<double, double>> out;
  for (int i = 0; i < n; ++i) out.emplace_back(phi(rng), theta(rng));
  // Exact corners of the circle as well.
  out.emplace_back(0.0, M_PI / 2);
  out.emplace_back(M_PI, 3 * M_PI / 2);
  return out;
}

void ExpectSameReading(double rad, double other, const std::string& what) {
  EXPECT_LE(std::fabs(other - rad), kUnitRelTolerance * std::fabs(rad)) << what;
}

TEST(RecordsAngleUnit, DegreesAndGonGiveTheRadianObservations) {
  TempDir dir;
  const auto angles = RandomReadings(200, 7);
  const RecordsFile rad = ReadRecords(dir.Write("rad.csv", AngleRows(1.0, angles)));
  const RecordsFile deg =
      ReadRecords(dir.Write("deg.csv", AngleRows(180.0 / M_PI, angles)), AngleUnit::kDeg);
  const RecordsFile gon =
      ReadRecords(dir.Write("gon.csv", AngleRows(200.0 / M_PI, angles)), AngleUnit::kGon);
  ASSERT_EQ(rad.records.size(), angles.size());
  ASSERT_EQ(deg.records.size(), angles.size());
  ASSERT_EQ(gon.records.size(), angles.size());
  for (size_t i = 0; i < angles.size(); ++i) {
    const Record &r = rad.records[i], &d = deg.records[i], &g = gon.records[i];
    const std::string row = "row " + std::to_string(i);
    ExpectSameReading(r.phi, d.phi, row + " phi deg");
    ExpectSameReading(r.theta, d.theta, row + " theta deg");
    ExpectSameReading(r.phi, g.phi, row + " phi gon");
    ExpectSameReading(r.theta, g.theta, row + " theta gon");
    // Everything that is not an angle is read as it is.
    for (const Record* o : {&d, &g}) {
      EXPECT_EQ(o->face, r.face);
      EXPECT_EQ(o->tool, r.tool);
      EXPECT_EQ(o->u, r.u);
      EXPECT_EQ(o->d, r.d);
      EXPECT_EQ(o->x, r.x);
      EXPECT_EQ(o->line, r.line);
    }
  }
}

// Quarter and half turns are exact: 180 deg and 200 gon are M_PI itself, so
// a face-1 zenith angle of a half turn stays within SPEC 1's [0, pi].
TEST(RecordsAngleUnit, HalfAndQuarterTurnsAreExact) {
  for (AngleUnit unit : {AngleUnit::kDeg, AngleUnit::kGon}) {
    const double half = unit == AngleUnit::kDeg ? 180.0 : 200.0;
    EXPECT_EQ(ReadingToRadians(half, unit), M_PI);
    EXPECT_EQ(ReadingToRadians(half / 2, unit), M_PI / 2);
    EXPECT_EQ(ReadingToRadians(1.5 * half, unit), 1.5 * M_PI);
    EXPECT_EQ(ReadingToRadians(2 * half, unit), 2 * M_PI);
    EXPECT_EQ(FormatReading(M_PI, unit), unit == AngleUnit::kDeg ? "180" : "200");
  }
}

TEST(RecordsAngleUnit, ExactAnglesOfDegreesAndGon) {
  TempDir dir;
  const RecordsFile deg = ReadRecords(
      dir.Write("deg.csv", std::string(kHeader) + "1,0,90,45,edm,,,2,0,0,1,\n"), AngleUnit::kDeg);
  EXPECT_EQ(deg.records[0].phi, M_PI / 2);
  EXPECT_EQ(deg.records[0].theta, M_PI / 4);
  const RecordsFile gon = ReadRecords(
      dir.Write("gon.csv", std::string(kHeader) + "1,0,100,300,edm,,,2,0,0,1,\n"), AngleUnit::kGon);
  EXPECT_EQ(gon.records[0].phi, M_PI / 2);
  EXPECT_EQ(gon.records[0].theta, 3 * M_PI / 2);
}

// predict and detect echo a user's rows in the user's unit: written back in
// degrees or gon, the readings read back bit for bit.
TEST(RecordsAngleUnit, WrittenBackInTheFileUnitReadsBackExactly) {
  TempDir dir;
  const auto angles = RandomReadings(100, 8);
  for (AngleUnit unit : {AngleUnit::kDeg, AngleUnit::kGon}) {
    const double scale = unit == AngleUnit::kDeg ? 180.0 / M_PI : 200.0 / M_PI;
    const RecordsFile in = ReadRecords(dir.Write("in.csv", AngleRows(scale, angles)), unit);
    const std::string out = dir.Path(std::string("out_") + AngleUnitName(unit) + ".csv");
    WriteRecords(out, in.records, unit);
    const RecordsFile back = ReadRecords(out, unit);
    ASSERT_EQ(back.records.size(), in.records.size());
    for (size_t i = 0; i < in.records.size(); ++i) {
      EXPECT_EQ(back.records[i].phi, in.records[i].phi) << i;
      EXPECT_EQ(back.records[i].theta, in.records[i].theta) << i;
    }
  }
}

TEST(PixelsAngleUnit, DegreesGiveTheRadianObservations) {
  TempDir dir;
  const std::string header = "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v\n";
  const double phi = 1.2345678901234567, theta = 1.4142135623730951;
  const PixelsFile rad =
      ReadPixels(dir.Write("rad.csv", header + "1,0," + FormatDouble(phi) + "," +
                                          FormatDouble(theta) + ",s1,3,0,1,2,3,10.5,20.5\n"));
  const PixelsFile deg = ReadPixels(
      dir.Write("deg.csv", header + "1,0," + FormatDouble(phi * 180 / M_PI) + "," +
                               FormatDouble(theta * 180 / M_PI) + ",s1,3,0,1,2,3,10.5,20.5\n"),
      AngleUnit::kDeg);
  ExpectSameReading(rad.pixels[0].phi, deg.pixels[0].phi, "phi");
  ExpectSameReading(rad.pixels[0].theta, deg.pixels[0].theta, "theta");
  EXPECT_EQ(rad.pixels[0].uv, deg.pixels[0].uv);
}

// SPEC 7.1 / 4.1: pixels.csv's optional placement and focus_distance
// columns, empty readings (camera-only), and the one writer's image sizes:
// written and read back unchanged.
TEST(PixelsBoards, PlacementsFocusAndEmptyReadingsRoundTrip) {
  TempDir dir;
  const std::string path = dir.Write(
      "pixels.csv",
      "face,zoom,phi,theta,shot,target,corner,X,Y,Z,u,v,placement,focus_distance,width,height\n"
      "1,0,,,s1,48,2,,,,100.5,200.25,p1,7.5,640,480\n"
      "2,0,3.2,4.7,s2,48,3,,,,10,20,p2,,640,480\n");
  const PixelsFile file = ReadPixels(path);
  ASSERT_EQ(file.pixels.size(), 2u);
  EXPECT_FALSE(file.pixels[0].has_reading);
  EXPECT_EQ(file.pixels[0].placement, "p1");
  EXPECT_EQ(file.pixels[0].focus_distance, 7.5);
  EXPECT_TRUE(file.pixels[1].has_reading);
  EXPECT_EQ(file.pixels[1].placement, "p2");
  EXPECT_EQ(file.pixels[1].focus_distance, 0.0);
  WritePixels(dir.Path("out.csv"), file.pixels, AngleUnit::kRad, file.image_sizes);
  const PixelsFile back = ReadPixels(dir.Path("out.csv"));
  ASSERT_EQ(back.pixels.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.pixels[i].has_reading, file.pixels[i].has_reading);
    EXPECT_EQ(back.pixels[i].phi, file.pixels[i].phi);
    EXPECT_EQ(back.pixels[i].placement, file.pixels[i].placement);
    EXPECT_EQ(back.pixels[i].focus_distance, file.pixels[i].focus_distance);
    EXPECT_EQ(back.pixels[i].uv, file.pixels[i].uv);
  }
  EXPECT_EQ(back.image_sizes.at(0).width, 640);
  EXPECT_EQ(back.image_sizes.at(0).height, 480);
  // Files without placements keep SPEC 3's columns.
  std::vector<PixelObservation> plain = file.pixels;
  for (PixelObservation& p : plain) {
    p.placement.clear();
    p.focus_distance = 0;
  }
  WritePixels(dir.Path("plain.csv"), plain);
  const CsvTable t = CsvTable::Read(dir.Path("plain.csv"), {{"shot"}, {}});
  EXPECT_FALSE(t.Has("placement"));
  EXPECT_FALSE(t.Has("focus_distance"));
  EXPECT_FALSE(t.Has("width"));
}

}  // namespace
}  // namespace rtscalib
