// model.yaml reader (libcalib/io/model_io.h). An accepted model must have
// finite parameter blocks, unit quaternions and positive image sizes, must
// write back and read again to the same blocks bit for bit (the file format's
// promise), and must predict without crashing.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz/fuzz_util.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"
#include "libcalib/model/kinematics.h"

namespace {

using rtscalib::InstrumentModel;
using rtscalib::PoseBlock;
using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

template <typename Array>
void RequireAllFinite(const Array& values, const std::string& what) {
  for (double x : values) RequireFinite(x, what);
}

void RequirePose(const PoseBlock& pose, const std::string& what) {
  RequireAllFinite(pose.q, what + ".q");
  RequireAllFinite(pose.t, what + ".t");
  const double norm2 =
      pose.q[0] * pose.q[0] + pose.q[1] * pose.q[1] + pose.q[2] * pose.q[2] + pose.q[3] * pose.q[3];
  // model_io accepts |norm - 1| <= 1e-9; the square doubles that.
  Require(std::abs(norm2 - 1.0) <= 3e-9, what + ".q is a unit quaternion");
}

void RequireValid(const InstrumentModel& m) {
  RequirePose(m.base, "base");
  RequirePose(m.edm, "edm");
  for (const rtscalib::DhLink& link : m.links) RequireAllFinite(link.p, "links");
  for (const auto& values : m.effect_values) RequireAllFinite(values, "effect si");
  RequireFinite(m.edm_cyclic_unit_length, "edm_cyclic_unit_length");
  Require(m.edm_cyclic_unit_length > 0, "edm_cyclic_unit_length > 0");
  for (const rtscalib::CameraTool& cam : m.cams) {
    RequirePose(cam.flange_from_cam, "flange_from_cam");
    RequireAllFinite(cam.intrinsics, "intrinsics");
    RequireAllFinite(cam.distortion, "distortion");
    Require(cam.width > 0 && cam.height > 0, "image size > 0");
  }
  if (m.sigmas.valid) {
    Require(m.sigmas.cam_tools.size() == m.cams.size() &&
                m.sigmas.intrinsics.size() == m.cams.size() &&
                m.sigmas.distortion.size() == m.cams.size(),
            "one sigma set per camera");
  }
}

// Bitwise, so that -0 vs 0 and NaN payloads count too.
template <typename T>
bool SameBits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

void RequireSameBlocks(const InstrumentModel& a, const InstrumentModel& b) {
  Require(a.kinematics == b.kinematics && a.effects == b.effects, "round trip: same structure");
  Require(SameBits(a.base.q, b.base.q) && SameBits(a.base.t, b.base.t) &&
              SameBits(a.edm.q, b.edm.q) && SameBits(a.edm.t, b.edm.t),
          "round trip: same base and edm blocks");
  if (a.kinematics == rtscalib::Kinematics::kDh) {
    Require(SameBits(a.links, b.links), "round trip: same links");
  }
  for (rtscalib::Effect e : a.effects.List()) {
    if (rtscalib::IsKinematic(e)) {
      Require(SameBits(a.EffectValue(e), b.EffectValue(e)), "round trip: same effect si");
    }
  }
  Require(SameBits(a.edm_cyclic_unit_length, b.edm_cyclic_unit_length),
          "round trip: same edm_cyclic_unit_length");
  Require(a.cams.size() == b.cams.size(), "round trip: same number of cameras");
  for (size_t z = 0; z < a.cams.size(); ++z) {
    const rtscalib::CameraTool &ca = a.cams[z], &cb = b.cams[z];
    Require(SameBits(ca.flange_from_cam.q, cb.flange_from_cam.q) &&
                SameBits(ca.flange_from_cam.t, cb.flange_from_cam.t) &&
                SameBits(ca.intrinsics, cb.intrinsics) && SameBits(ca.distortion, cb.distortion) &&
                ca.width == cb.width && ca.height == cb.height,
            "round trip: same camera " + std::to_string(z));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunFileReader(data, size, ".yaml", [](const std::string& path) {
    rtscalib::ModelMetadata metadata;
    const InstrumentModel model = rtscalib::ReadModelYaml(path, &metadata);
    RequireValid(model);

    // What the writer makes of an accepted model must read back unchanged;
    // an InputError here is the writer's or reader's bug, not the input's.
    const std::string copy = path + ".copy.yaml";
    rtscalib::WriteModelYaml(copy, model, metadata);
    InstrumentModel again;
    rtscalib::ModelMetadata metadata_again;
    try {
      again = rtscalib::ReadModelYaml(copy, &metadata_again);
    } catch (const rtscalib::InputError& e) {
      Require(false, std::string("the written model reads back: ") + e.what());
    }
    RequireSameBlocks(model, again);
    Require(metadata == metadata_again, "round trip: same metadata");

    // Predictions are what a model is for; they may be meaningless for a
    // fuzzed model, but must not crash or trip a CHECK.
    (void)rtscalib::PredictEdm(model, 0.3, 1.2, 2.0);
    Eigen::Vector2d pixel;
    for (int zoom = 0; zoom < model.NumZooms(); ++zoom) {
      (void)rtscalib::PredictPixel(model, zoom, 0.3, 1.2, Eigen::Vector3d(0.1, 2.0, 0.3), &pixel);
    }
  });
}
