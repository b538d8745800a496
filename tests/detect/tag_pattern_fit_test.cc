// The whole-pattern fit of small tags on photos synthesized exactly
// (synthetic_photo.h: every pixel the exact area average of the printed
// pattern, so the corners are known exactly from the homography that made
// the photo), blurred and with sensor noise as a camera would add them.
#include "detect/tag_pattern_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include <opencv2/imgproc.hpp>

#include "detect/tag_family.h"
#include "tests/detect/synthetic_photo.h"

namespace rtscalib::detect {
namespace {

using testing::MakeHomography;
using testing::PrintedTag;
using testing::PrintTag;
using testing::Project;
using testing::QuadCorners;
using testing::RenderCoverage;

// Measured RMS over the views below: 0.010-0.016 px from 1.6 to 3 px per bit
// with optics blur (the edge refinement needs 2.5 px per bit and gives 0.03
// px at 3 px per bit on such photos), 0.007-0.016 px without. 0.04 px
// leaves room for other noise seeds and is still 6x below the 0.25 px the
// start corners are off, so a fit that does not move fails.
constexpr double kRmsTolPx = 0.04;
constexpr double kMaxTolPx = 0.1;

struct SmallTagPhoto {
  cv::Mat gray;
  cv::Mat code;
  std::array<Eigen::Vector2d, 4> exact;  // the quad's corners, TargetCorner order
  std::array<Eigen::Vector2d, 4> start;  // exact corners moved by ~0.25 px
};

// One tag36h11 of `bit` px per code bit, turned by `angle` with a slight
// perspective, on 8-bit grey ink 30 / paper 220; optics blur `blur` px
// (Gaussian, on top of the pixel's own area) and Gaussian noise of 1 grey
// level.
SmallTagPhoto MakePhoto(int id, double bit, double angle, double blur, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const PrintedTag tag = PrintTag("tag36h11", id, 0, 0, 8);
  const Eigen::Matrix3d h =
      MakeHomography(8, Eigen::Vector2d(40 + u(*rng), 40 + u(*rng)), bit, angle,
                     0.03 * (u(*rng) - 0.5) / bit, 0.03 * (u(*rng) - 0.5) / bit);
  cv::Mat coverage = RenderCoverage({tag}, h, 80, 80);
  if (blur > 0) cv::GaussianBlur(coverage, coverage, cv::Size(0, 0), blur);
  cv::Mat noise(coverage.size(), CV_64FC1);
  cv::randn(noise, 0, 1.0 / 190);  // 1 grey level after the scaling below
  coverage += noise;
  SmallTagPhoto photo;
  coverage.convertTo(photo.gray, CV_8UC1, 190, 30);
  photo.code = TagCodeImage("tag36h11", id);
  const std::array<Eigen::Vector2d, 4> quad = QuadCorners(tag);
  for (int k = 0; k < 4; ++k) {
    photo.exact[k] = Project(h, quad[k]);
    // A start as libapriltag gives it on such tags (0.1-0.3 px off).
    const double a = 1.7 * k + angle;
    photo.start[k] = photo.exact[k] + 0.25 * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  return photo;
}

TEST(TagPatternFitTest, SmallTagCornersOnExactPhotos) {
  std::mt19937 rng(11);
  cv::setRNGSeed(11);
  for (const double blur : {0.5, 0.0}) {
    for (const double bit : {1.6, 2.0, 2.5, 3.0}) {
      double sum_sq = 0, max = 0;
      int corners = 0;
      for (int view = 0; view < 6; ++view) {
        const SmallTagPhoto p = MakePhoto(3 + 17 * view, bit, 0.4 + 1.1 * view, blur, &rng);
        const PatternFitResult fit = FitTagPattern(p.gray, p.code, 1, 8, p.start);
        ASSERT_TRUE(fit.converged) << "bit " << bit << " view " << view << " blur " << blur;
        // The fitted levels are the photo's ink and paper, up to what they
        // absorb of the difference between one Gaussian and the true edge
        // profile (a pixel box with or without the optics' Gaussian):
        // measured up to 6 grey levels of the 190 of contrast.
        EXPECT_NEAR(fit.ink, 30, 10);
        EXPECT_NEAR(fit.paper, 220, 10);
        EXPECT_GE(fit.blur_px, std::sqrt(1.0 / 12.0));
        for (int k = 0; k < 4; ++k) {
          const double e = (fit.corners[k] - p.exact[k]).norm();
          sum_sq += e * e;
          max = std::max(max, e);
          ++corners;
        }
      }
      const double rms = std::sqrt(sum_sq / corners);
      std::printf("blur %.1f px, %.1f px per bit: RMS %.4f px, max %.4f px\n", blur, bit, rms, max);
      EXPECT_LT(rms, kRmsTolPx) << "bit " << bit << " blur " << blur;
      EXPECT_LT(max, kMaxTolPx) << "bit " << bit << " blur " << blur;
    }
  }
}

TEST(TagPatternFitTest, AnotherTagsPatternIsRejected) {
  std::mt19937 rng(5);
  const SmallTagPhoto p = MakePhoto(21, 2.2, 0.3, 0.5, &rng);
  // The quad and the levels fit, the code bits do not: the residual is a
  // large fraction of the contrast.
  const PatternFitResult wrong = FitTagPattern(p.gray, TagCodeImage("tag36h11", 22), 1, 8, p.start);
  EXPECT_FALSE(wrong.converged);
  EXPECT_GT(wrong.residual_rms, PatternFitOptions().max_residual_fraction * 150);
  EXPECT_EQ(wrong.corners, p.start);
  const PatternFitResult right = FitTagPattern(p.gray, p.code, 1, 8, p.start);
  EXPECT_TRUE(right.converged);
  EXPECT_LT(right.residual_rms, 0.02 * (right.paper - right.ink));
}

TEST(TagPatternFitTest, CornersBeyondTheImageAreRejected) {
  std::mt19937 rng(7);
  const SmallTagPhoto p = MakePhoto(9, 2.5, 0.2, 0.5, &rng);
  // The same photo cropped so that the quad's left side lies beyond it.
  const double left = std::min({p.exact[0].x(), p.exact[1].x(), p.exact[2].x(), p.exact[3].x()});
  const int crop = static_cast<int>(std::ceil(left)) + 1;
  const cv::Mat cropped = p.gray(cv::Rect(crop, 0, p.gray.cols - crop, p.gray.rows)).clone();
  std::array<Eigen::Vector2d, 4> start = p.start;
  for (Eigen::Vector2d& c : start) c.x() -= crop;
  EXPECT_FALSE(FitTagPattern(cropped, p.code, 1, 8, start).converged);
  // Cropped through the quiet zone only: every corner is still in the image.
  const int margin = static_cast<int>(std::floor(left)) - 2;
  ASSERT_GT(margin, 0);
  const cv::Mat quiet = p.gray(cv::Rect(margin, 0, p.gray.cols - margin, p.gray.rows)).clone();
  start = p.start;
  for (Eigen::Vector2d& c : start) c.x() -= margin;
  const PatternFitResult fit = FitTagPattern(quiet, p.code, 1, 8, start);
  ASSERT_TRUE(fit.converged);
  for (int k = 0; k < 4; ++k) {
    EXPECT_LT((fit.corners[k] + Eigen::Vector2d(margin, 0) - p.exact[k]).norm(), kMaxTolPx);
  }
}

TEST(TagPatternFitTest, OptionsAreChecked) {
  PatternFitOptions o;
  EXPECT_EQ(o.Check(), "");
  o.max_iterations = 0;
  EXPECT_NE(o.Check(), "");
  o = PatternFitOptions();
  o.max_residual_fraction = 0;
  EXPECT_NE(o.Check(), "");
}

}  // namespace
}  // namespace rtscalib::detect
