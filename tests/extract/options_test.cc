#include "libcalib/extract/options.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace rtscalib {
namespace {

TEST(ExtractOptions, DefaultsAreValid) {
  const ExtractOptions o;
  EXPECT_EQ(o.Check(), "");
  // SPEC 1 critical regions by default: zenith near 0 and beyond 3/4 pi.
  EXPECT_GT(o.critical_region.min_zenith_rad, 0.0);
  EXPECT_NEAR(o.critical_region.max_zenith_rad, 0.75 * M_PI, 1e-15);
  EXPECT_EQ(o.joint1_set_hint, "sweep1");
  EXPECT_EQ(o.joint2_set_hint, "sweep2");
}

// Every invalid setting gives a message that names the option and the value
// it got (an options struct's Check() returns a message, as Ceres's
// Solver::Options::IsValid does).
struct BadCase {
  const char* what;
  std::function<void(ExtractOptions*)> spoil;
  std::vector<std::string> must_contain;
};

TEST(ExtractOptions, CheckNamesTheOptionAndTheValue) {
  const std::vector<BadCase> cases = {
      {"min above max",
       [](ExtractOptions* o) {
         o->critical_region.min_zenith_rad = 2.0, o->critical_region.max_zenith_rad = 1.0;
       },
       {"zenith limits", "min 2", "max 1"}},
      {"negative min",
       [](ExtractOptions* o) { o->critical_region.min_zenith_rad = -0.1; },
       {"zenith limits", "-0.1"}},
      {"max beyond pi",
       [](ExtractOptions* o) { o->critical_region.max_zenith_rad = 4.0; },
       {"zenith limits", "max 4"}},
      {"NaN min",
       [](ExtractOptions* o) { o->critical_region.min_zenith_rad = std::nan(""); },
       {"zenith limits"}},
      {"angle tolerance 0",
       [](ExtractOptions* o) { o->angle_tolerance_rad = 0.0; },
       {"angle_tolerance_rad", "got 0"}},
      {"angle tolerance large",
       [](ExtractOptions* o) { o->angle_tolerance_rad = 0.2; },
       {"angle_tolerance_rad", "got 0.2"}},
      {"distance tolerance",
       [](ExtractOptions* o) { o->distance_tolerance_m = -1e-6; },
       {"distance_tolerance_m", "got -1e-06"}},
      {"pixel tolerance",
       [](ExtractOptions* o) { o->pixel_tolerance_px = 0.5; },
       {"pixel_tolerance_px", "got 0.5"}},
      {"sweep points",
       [](ExtractOptions* o) { o->min_sweep_points = 2; },
       {"min_sweep_points", "got 2"}},
      {"fit rms", [](ExtractOptions* o) { o->max_fit_rms_m = 0.0; }, {"max_fit_rms_m", "got 0"}},
      {"radius", [](ExtractOptions* o) { o->min_radius_m = -1.0; }, {"min_radius_m", "got -1"}},
      {"axis parallel",
       [](ExtractOptions* o) { o->axis_tolerances.parallel_sin = 1.5; },
       {"axis_tolerances", "parallel_sin"}},
      {"axis distance",
       [](ExtractOptions* o) { o->axis_tolerances.distance_m = -1.0; },
       {"axis_tolerances", "distance_m"}},
  };
  for (const BadCase& c : cases) {
    ExtractOptions o;
    c.spoil(&o);
    const std::string msg = o.Check();
    EXPECT_FALSE(msg.empty()) << c.what;
    for (const std::string& s : c.must_contain) {
      EXPECT_NE(msg.find(s), std::string::npos)
          << c.what << ": '" << msg << "' lacks '" << s << "'";
    }
  }
}

TEST(ExtractOptions, BoundaryValuesAreValid) {
  ExtractOptions o;
  o.critical_region.min_zenith_rad = 0.0;
  o.critical_region.max_zenith_rad = M_PI;
  o.min_sweep_points = 3;
  EXPECT_EQ(o.Check(), "");
}

TEST(ExtractionError, IsARuntimeErrorCarryingItsMessage) {
  try {
    throw ExtractionError("sweep1: 4 points, need 5");
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "sweep1: 4 points, need 5");
    return;
  }
  FAIL() << "ExtractionError must be a std::runtime_error";
}

}  // namespace
}  // namespace rtscalib
