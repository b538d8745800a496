// Values no instrument has are a fit gone wild (wild_fit.h): each bound on
// its own, on an otherwise sensible model (the sigmas are not needed for
// these checks: an empty linearisation gives none).
#include "libcalib/diagnose/wild_fit.h"

#include <gtest/gtest.h>

#include "libcalib/sim/simulator.h"

namespace rtscalib {
namespace {

std::vector<std::string> Names(const std::vector<WildParameter>& w) {
  std::vector<std::string> out;
  for (const WildParameter& p : w) out.push_back(p.name);
  return out;
}

TEST(WildFit, ASensibleModelIsNotWild) {
  const InstrumentModel m = PaperTruth(2);
  EXPECT_TRUE(FindWildParameters(Linearization(), m, DistortionTerms(), {}).empty());
}

TEST(WildFit, ValuesBeyondPhysicalBoundsAreNamed) {
  InstrumentModel m = PaperTruth(2);
  m.cams[0].intrinsics[1] = 1.2 * m.cams[0].intrinsics[0];  // pixels 20 % from square
  m.cams[1].intrinsics[2] = -40.0;                            // principal point left of the image
  m.effects.Add(Effect::kFocus);
  m.cams[1].focus[kFocusKf] = 3.0;  // 3 m: no telescope camera's focal length
  m.cams[0].focus[kFocusAu] = 5e4;  // 5e4 px m: 1.7e4 px at 3 m
  m.effects.Add(Effect::kHzScale);
  m.EffectValue(Effect::kHzScale) = {5e-3, 0};  // 5000 ppm
  const std::vector<WildParameter> w =
      FindWildParameters(Linearization(), m, DistortionTerms(), {{0, 3.0}, {1, 3.0}});
  const std::vector<std::string> names = Names(w);
  for (const char* expected :
       {"fy of zoom 0", "cx of zoom 1", "focus kf of zoom 1", "focus au of zoom 0", "hz_scale"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
  EXPECT_EQ(w.size(), 5u);
  for (const WildParameter& p : w) {
    EXPECT_FALSE(p.undetermined) << p.name;  // their values, not their sigmas
    EXPECT_FALSE(p.why.empty());
  }
}

}  // namespace
}  // namespace rtscalib
