// The run configuration reader (libcalib/config/config.h). LoadConfig takes a
// path, so each input goes through a temporary file. An accepted config must
// hold finite numbers, pass the option structs' own Check() (the values are
// promised to be checked where they are read), and DumpConfig's text must load
// again to the same dump (--write-config's promise).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <string>

#include "fuzz/fuzz_util.h"
#include "libcalib/config/config.h"
#include "libcalib/text/errors.h"
#include "libcalib/sim/simulator.h"

namespace {

using rtscalib::RunConfig;
using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

template <typename Values>
void RequireAllFinite(const Values& values, const std::string& what) {
  for (double x : values) RequireFinite(x, what);
}

void RequireFinitePose(const rtscalib::PoseBlock& pose, const std::string& what) {
  RequireAllFinite(pose.q, what + ".q");
  RequireAllFinite(pose.t, what + ".t");
}

void RequireFiniteCamera(const rtscalib::CameraTool& cam, const std::string& what) {
  RequireFinitePose(cam.flange_from_cam, what + ".flange_from_cam");
  RequireAllFinite(cam.intrinsics, what + ".intrinsics");
  RequireAllFinite(cam.distortion, what + ".distortion");
  Require(cam.width > 0 && cam.height > 0, what + ": image size > 0");
}

void RequireValid(const RunConfig& c) {
  RequireFinite(c.calibration.model.edm_cyclic_unit_length, "model.edm_cyclic.unit_length");
  for (const rtscalib::CameraTool& cam : c.calibration.model.cameras)
    RequireFiniteCamera(cam, "model.cameras");
  const rtscalib::FitOptions& f = c.calibration.fit;
  for (double x : {f.sigma_edm_m, f.sigma_cam_m, f.sigma_pixel_px, f.loss_scale,
                   f.translation_bound_m, f.critical_region.min_zenith_rad,
                   f.critical_region.max_zenith_rad}) {
    RequireFinite(x, "a fit option");
  }
  // FitOptions::Check() lives in the fit library (Ceres); its rules, repeated:
  Require(f.sigma_edm_m > 0 && f.sigma_cam_m > 0 && f.sigma_pixel_px > 0, "fit.sigmas > 0");
  Require(f.loss_scale > 0, "fit.robust_loss.scale > 0");
  Require(f.max_iterations >= 1, "fit.max_iterations >= 1");
  Require(f.translation_bound_m >= 0, "fit.translation_bound_m >= 0");
  Require(f.critical_region.Check().empty(), "fit.critical_region 0 <= min < max <= pi");
  Require(f.num_threads >= 1, "fit.threads >= 1");
  RequireFinite(c.calibration.diagnose.significance, "diagnose.significance");

  if (c.simulate) {
    rtscalib::SimulationOptions sim = *c.simulate;
    if (c.truth_from_paper) sim.truth = rtscalib::PaperTruth(rtscalib::PlanNumZooms(sim.plan));
    const rtscalib::InstrumentModel& t = sim.truth;
    RequireFinitePose(t.base, "truth.base");
    RequireFinitePose(t.edm, "truth.edm");
    for (const rtscalib::DhLink& link : t.links) RequireAllFinite(link.p, "truth.links");
    for (const auto& values : t.effect_values) RequireAllFinite(values, "truth effect");
    for (const rtscalib::CameraTool& cam : t.cams) RequireFiniteCamera(cam, "truth.cameras");
    RequireFinite(t.edm_cyclic_unit_length, "truth.edm_cyclic_unit_length");
    const rtscalib::NoiseOptions& n = sim.noise;
    for (double x : {n.angle_rad, n.distance_m, n.point_m, n.pixel_px}) {
      RequireFinite(x, "simulate.noise");
    }
    const rtscalib::AcquisitionPlan& p = sim.plan;
    RequireAllFinite(p.edm_distances, "plan.edm_distances");
    RequireAllFinite(p.grid_edm_distances, "plan.grid.edm_distances");
    RequireAllFinite(p.grid_cam_ray_lengths, "plan.grid.cam_ray_lengths");
    RequireFinite(p.cam_ray_length, "plan.cam_ray_length");
    RequireFinite(p.pixel_offset, "plan.pixel_offset");
    for (const rtscalib::TagBoard& b : sim.targets.boards) {
      RequireFinite(b.tag_size, "targets.tag_size");
      RequireFinite(b.spacing, "targets.spacing");
      for (int i = 0; i < 3; ++i) RequireFinite(b.ref_from_board.translation[i], "targets pose t");
    }
    RequireFinite(sim.shots.fill, "shots.fill");
    RequireFinite(sim.shots.pointing_jitter, "shots.pointing_jitter");
    const std::string message = sim.Check();
    Require(message.empty(), "SimulationOptions::Check() passes, but: " + message);
  }
}

bool StartsNumber(const std::string& s, size_t i) {
  const auto digit = [&](size_t k) {
    return k < s.size() && std::isdigit(static_cast<unsigned char>(s[k]));
  };
  return digit(i) || ((s[i] == '-' || s[i] == '.') && digit(i + 1)) ||
         (s[i] == '-' && i + 1 < s.size() && s[i + 1] == '.' && digit(i + 2));
}

// The texts agree, numbers to within a few units in the last place.
// DumpConfig promises bit-for-bit, but target boards are kept as rotation
// matrices (TagBoard::ref_from_board), so their quaternions may move by an
// ulp per load; docs/fuzzing.md lists this as a known gap.
bool SameUpToRounding(const std::string& a, const std::string& b) {
  constexpr double kUlps = 8 * std::numeric_limits<double>::epsilon();
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (StartsNumber(a, i) && StartsNumber(b, j)) {
      char* end_a = nullptr;
      char* end_b = nullptr;
      const double x = std::strtod(a.c_str() + i, &end_a);
      const double y = std::strtod(b.c_str() + j, &end_b);
      // Something that looked like a number but is none (strtod took
      // nothing): compare it as text, else the loop would not advance (a
      // 10-minute libFuzzer run hung here on "..015").
      if (end_a == a.c_str() + i || end_b == b.c_str() + j) {
        if (a[i++] != b[j++]) return false;
        continue;
      }
      if (!(std::abs(x - y) <= kUlps * std::max({1.0, std::abs(x), std::abs(y)})) && x != y)
        return false;
      i = static_cast<size_t>(end_a - a.c_str());
      j = static_cast<size_t>(end_b - b.c_str());
      continue;
    }
    if (a[i++] != b[j++]) return false;
  }
  return i == a.size() && j == b.size();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunFileReader(data, size, ".yaml", [](const std::string& path) {
    const RunConfig config = rtscalib::LoadConfig(path);
    RequireValid(config);

    const std::string dump = rtscalib::DumpConfig(config);
    const std::string copy = rtscalib::fuzz::WriteInputFile(
        reinterpret_cast<const uint8_t*>(dump.data()), dump.size(), ".dump.yaml");
    try {
      const RunConfig again = rtscalib::LoadConfig(copy);
      const std::string dump_again = rtscalib::DumpConfig(again);
      Require(SameUpToRounding(dump, dump_again),
              "the dumped config loads to the same dump\n--- first:\n" + dump + "--- second:\n" +
                  dump_again);
    } catch (const rtscalib::InputError& e) {
      Require(false, std::string("the dumped config loads: ") + e.what() + "\n--- dump:\n" + dump);
    }
  });
}
