// Photos as the detector sees them (photo_image.h): depths, the 16-bit
// range, and files that are damaged or claim more than OpenCV reads, each
// refused with a message that names the file.
#include "detect/photo_image.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/detect/synthetic_photo.h"

namespace rtscalib::detect {
namespace {

using ::testing::HasSubstr;

// A folder of its own for one test's files, removed at its end.
class PhotoFiles {
 public:
  PhotoFiles() {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::path(::testing::TempDir()) /
            ("rtscalib_photo_image_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~PhotoFiles() { std::filesystem::remove_all(path_); }
  std::string Path(const std::string& name) const { return (path_ / name).string(); }
  std::string Write(const std::string& name, const std::vector<uint8_t>& bytes) const {
    std::ofstream out(Path(name), std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    return Path(name);
  }

 private:
  std::filesystem::path path_;
};

// The message of LoadPhoto's PhotoError for `path`, or "" when it loads.
std::string LoadError(const std::string& path) {
  try {
    LoadPhoto(path);
  } catch (const PhotoError& e) {
    return e.what();
  }
  return "";
}

// A picture with structure (a bright square on a ramp) as a file's bytes.
std::vector<uint8_t> Encoded(const std::string& ext) {
  cv::Mat img(120, 160, CV_8UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) img.at<uint8_t>(y, x) = static_cast<uint8_t>(x + y / 2);
  }
  img(cv::Rect(40, 30, 50, 40)).setTo(240);
  std::vector<uint8_t> bytes;
  cv::imencode(ext, img, bytes);
  return bytes;
}

TEST(PhotoImageTest, SixteenBitIsStretchedByItsOwnRangeWithoutClipping) {
  // Regions of 2 x 2 pixels or more set the range (the median filter keeps
  // them): 1000 -> 0, 1510 -> 255.
  cv::Mat img(8, 9, CV_16UC1, cv::Scalar(1000));
  img(cv::Rect(3, 0, 3, 8)).setTo(1255);
  img(cv::Rect(6, 0, 3, 8)).setTo(1510);
  const cv::Mat g = ToGray8(img);
  ASSERT_EQ(g.type(), CV_8UC1);
  EXPECT_EQ(g.at<uint8_t>(4, 0), 0);
  EXPECT_EQ(g.at<uint8_t>(4, 4), 128);  // (1255 - 1000) * 255 / 510 = 127.5 -> 128
  EXPECT_EQ(g.at<uint8_t>(4, 8), 255);
  EXPECT_THROW(ToGray8(cv::Mat(2, 2, CV_8UC2)), std::invalid_argument);
  EXPECT_THROW(ToGray8(cv::Mat(2, 2, CV_16SC1)), std::invalid_argument);
}

// A 12-bit sensor's picture in a 16-bit file (values 0 .. 4095) with one hot
// pixel at 65535: a plain min..max stretch would put the whole picture into
// 16 grey levels. The hot pixel alone is clipped; the picture keeps its 256.
TEST(PhotoImageTest, AHotPixelDoesNotCrushTheRange) {
  cv::Mat img(64, 64, CV_16UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) img.at<uint16_t>(y, x) = static_cast<uint16_t>(x * 65);
  }
  img.at<uint16_t>(20, 10) = 65535;  // hot
  img.at<uint16_t>(40, 50) = 0;      // dead
  const cv::Mat g = ToGray8(img);
  EXPECT_EQ(g.at<uint8_t>(5, 0), 0);
  EXPECT_EQ(g.at<uint8_t>(5, 63), 255);
  EXPECT_EQ(g.at<uint8_t>(5, 32), static_cast<uint8_t>(std::lround(32 * 255.0 / 63)));
  EXPECT_EQ(g.at<uint8_t>(20, 10), 255);  // clipped
  // Float images alike.
  cv::Mat f;
  img.convertTo(f, CV_32F, 1.0 / 4095);
  const cv::Mat gf = ToGray8(f);
  EXPECT_EQ(gf.at<uint8_t>(5, 32), g.at<uint8_t>(5, 32));
}

TEST(PhotoImageTest, WholeFilesLoad) {
  const PhotoFiles files;
  for (const std::string ext : {".png", ".jpg", ".tif"}) {
    const Photo p = LoadPhoto(files.Write("whole" + ext, Encoded(ext)));
    EXPECT_EQ(p.width, 160) << ext;
    EXPECT_EQ(p.height, 120) << ext;
    EXPECT_EQ(p.bit_depth, 8) << ext;
  }
}

// A JPEG cut short decodes in OpenCV (libjpeg fills the missing rows with
// grey and warns on stderr only): LoadPhoto finds it by its missing end
// marker. A PNG cut short is likewise named as damaged.
TEST(PhotoImageTest, FilesCutShortAreDamaged) {
  const PhotoFiles files;
  for (const std::string ext : {".jpg", ".png"}) {
    std::vector<uint8_t> bytes = Encoded(ext);
    bytes.resize(bytes.size() / 2);
    const std::string path = files.Write("half" + ext, bytes);
    const std::string error = LoadError(path);
    EXPECT_THAT(error, HasSubstr(path)) << ext;
    EXPECT_THAT(error, HasSubstr("is damaged")) << ext;
  }
  // An EXIF-like segment holding a complete embedded JPEG (its own end
  // marker) does not make a cut file whole.
  std::vector<uint8_t> bytes = Encoded(".jpg");
  const std::vector<uint8_t> thumbnail = Encoded(".jpg");
  std::vector<uint8_t> app1 = {0xFF, 0xE1, 0, 0};
  app1.insert(app1.end(), thumbnail.begin(), thumbnail.end());
  const size_t length = app1.size() - 2;
  app1[2] = static_cast<uint8_t>(length >> 8);
  app1[3] = static_cast<uint8_t>(length & 0xFF);
  bytes.insert(bytes.begin() + 2, app1.begin(), app1.end());
  EXPECT_EQ(LoadError(files.Write("with_thumbnail.jpg", bytes)), "");
  bytes.resize(bytes.size() - 100);
  EXPECT_THAT(LoadError(files.Write("with_thumbnail_cut.jpg", bytes)), HasSubstr("is damaged"));
}

// A PNG header claiming 100000 x 100000 pixels: OpenCV refuses it
// (CV_IO_MAX_IMAGE_PIXELS); the message names the file and the size claimed.
TEST(PhotoImageTest, AHeaderClaimingTooManyPixelsNamesTheFile) {
  const PhotoFiles files;
  const std::vector<uint8_t> bytes = testing::PngClaimingSize(Encoded(".png"), 100000, 100000);
  const std::string path = files.Write("huge.png", bytes);
  const std::string error = LoadError(path);
  EXPECT_THAT(error, HasSubstr(path));
  EXPECT_THAT(error, HasSubstr("100000 x 100000"));
  EXPECT_THAT(LoadError(files.Path("missing.png")), HasSubstr("missing.png"));
  EXPECT_THAT(LoadError(files.Write("text.png", {'n', 'o', 't'})), HasSubstr("text.png"));
}

}  // namespace
}  // namespace rtscalib::detect
