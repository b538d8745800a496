#include "libcalib/calibrate/intrinsics.h"

#include <gtest/gtest.h>

namespace rtscalib {
namespace {

// One 1000 x 800 camera per zoom.
InstrumentModel Start(int zooms) {
  CameraTool camera;
  camera.width = 1000;
  camera.height = 800;
  return IdealModel(Kinematics::kDh, zooms, camera);
}

// Pixels of `zoom` at the corners of a box of `du` x `dv` px around the
// image centre.
void AddPixels(int zoom, double du, double dv, Observations* obs) {
  for (double su : {-0.5, 0.5}) {
    for (double sv : {-0.5, 0.5}) {
      PixelObservation p;
      p.zoom = zoom;
      p.uv = {500 + su * du, 400 + sv * dv};
      obs->pixels.push_back(p);
    }
  }
}

TEST(FitIntrinsics, FitAndFixedDoNotLookAtTheData) {
  const Observations none;
  EXPECT_TRUE(FitIntrinsics(IntrinsicsMode::kFit, none, Start(1)));
  Observations wide;
  AddPixels(0, 900, 700, &wide);
  EXPECT_FALSE(FitIntrinsics(IntrinsicsMode::kFixed, wide, Start(1)));
}

TEST(FitIntrinsics, AutoWhenEveryZoomSpansMoreThanAQuarterOfItsImage) {
  const InstrumentModel start = Start(2);
  EXPECT_FALSE(FitIntrinsics(IntrinsicsMode::kAuto, Observations{}, start)) << "no camera data";
  Observations obs;
  AddPixels(0, 900, 700, &obs);
  EXPECT_TRUE(FitIntrinsics(IntrinsicsMode::kAuto, obs, start));
  // A quarter of the width (250 px) is not more than a quarter.
  AddPixels(1, 250, 700, &obs);
  EXPECT_FALSE(FitIntrinsics(IntrinsicsMode::kAuto, obs, start)) << "zoom 1 is too narrow";
  AddPixels(1, 251, 201, &obs);
  EXPECT_TRUE(FitIntrinsics(IntrinsicsMode::kAuto, obs, start));
  // Camera data of a zoom the start model has no camera for are never enough.
  AddPixels(2, 900, 700, &obs);
  EXPECT_FALSE(FitIntrinsics(IntrinsicsMode::kAuto, obs, start));
}

TEST(FitIntrinsics, ReducedSetOnlyWhenTheWholeDoesAndItsZeroZoomSpans) {
  const InstrumentModel start = Start(1);
  Observations wide, narrow;
  AddPixels(0, 900, 700, &wide);
  AddPixels(0, 10, 10, &narrow);
  EXPECT_TRUE(FitIntrinsicsOnReducedSet(true, wide, start));
  EXPECT_FALSE(FitIntrinsicsOnReducedSet(false, wide, start));
  EXPECT_FALSE(FitIntrinsicsOnReducedSet(true, narrow, start));
}

}  // namespace
}  // namespace rtscalib
