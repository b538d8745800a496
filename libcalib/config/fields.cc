#include "libcalib/config/fields.h"

#include <algorithm>

#include "libcalib/io/yaml_writer.h"
#include "libcalib/model/effects.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

Eigen::Vector3d ToVector3(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

}  // namespace

std::vector<std::string> AllEffectNames() {
  std::vector<std::string> out;
  for (const EffectInfo& info : EffectCatalogue()) out.emplace_back(info.name);
  return out;
}

using DoubleCheck = bool (*)(double);
bool IsPositive(double x) { return x > 0; }
bool IsNonNegative(double x) { return x >= 0; }

// Reads `key` into *value if present (returns whether it was); `expected`
// describes a valid value.
bool ReadNumber(const YamlNode& m, const std::string& key, double* value, DoubleCheck ok,
                const std::string& expected) {
  const std::optional<YamlNode> n = m.Find(key);
  if (!n) return false;
  const double x = n->AsDouble();
  if (!ok(x)) n->Fail(expected);
  *value = x;
  return true;
}

void ReadCount(const YamlNode& m, const std::string& key, int* value, int min,
               const std::string& what) {
  if (const std::optional<YamlNode> n = m.Find(key)) {
    const int x = n->AsInt();
    if (x < min) n->Fail(what + " (an integer >= " + std::to_string(min) + ")");
    *value = x;
  }
}

// A non-empty list of numbers that all pass `ok`.
void ReadNumbers(const YamlNode& m, const std::string& key, std::vector<double>* value,
                 DoubleCheck ok, const std::string& expected) {
  if (const std::optional<YamlNode> n = m.Find(key)) {
    std::vector<double> out;
    for (const YamlNode& item : n->Items()) {
      const double x = item.AsDouble();
      if (!ok(x)) item.Fail(expected);
      out.push_back(x);
    }
    if (out.empty()) n->Fail("a non-empty list of " + expected);
    *value = out;
  }
}

// The number y, written shortest, for which y * scale == x exactly if one
// exists next to x / scale: so that dumped degrees and arcseconds give back
// the same radians.
std::string ExactScaled(double x, double scale) {
  double best = x / scale, up = best, down = best;
  for (int step = 0; step < 4 && best * scale != x; ++step) {
    up = std::nextafter(up, INFINITY);
    down = std::nextafter(down, -INFINITY);
    if (up * scale == x) best = up;
    if (down * scale == x) best = down;
  }
  return YamlDouble(best, /*shortest=*/true);
}

// A pose {euler: [a, b, g] (Klug Eq. 83) | q: [x, y, z, w], t: [x, y, z]}.
// Each key is optional: what is absent keeps *pose's value. People write
// Euler angles; DumpConfig writes quaternions, which read back bit for bit
// (Euler angles lose digits near b = +-pi/2, where the ideal tools sit).
void ReadPoseFields(const YamlNode& m, PoseBlock* pose) {
  const std::optional<YamlNode> euler = m.Find("euler");
  const std::optional<YamlNode> q = m.Find("q");
  if (euler && q) q->Fail("either euler or q, not both");
  if (q) {
    const std::vector<double> v = q->AsDoubles(4);
    RequireUnitQuaternion(*q, v.data());
    std::copy(v.begin(), v.end(), pose->q.begin());
  } else if (euler) {
    const Rigid3 rotation{RotationFromEuler<double>(ToVector3(euler->AsDoubles(3))),
                          Eigen::Vector3d::Zero()};
    pose->q = PoseBlock::FromRigid(rotation).q;
  }
  if (const std::optional<YamlNode> t = m.Find("t")) {
    const std::vector<double> v = t->AsDoubles(3);
    std::copy(v.begin(), v.end(), pose->t.begin());
  }
}

void ReadPoseFields(const YamlNode& m, Rigid3* pose) {
  PoseBlock block = PoseBlock::FromRigid(*pose);
  ReadPoseFields(m, &block);
  *pose = block.ToRigid();
}

// Image size, intrinsics and distortion of one zoom level. `required`: all of
// width, height, fx, fy, cx, cy must be given (model.cameras); otherwise
// absent keys keep *cam's values (simulated truth).
void ReadCameraFields(const YamlNode& m, bool required, CameraTool* cam) {
  auto get = [&](const std::string& key) {
    return required ? std::optional<YamlNode>(m.Require(key)) : m.Find(key);
  };
  for (auto [key, value] : {std::pair<const char*, int*>{"width", &cam->width},
                            std::pair<const char*, int*>{"height", &cam->height}}) {
    if (const std::optional<YamlNode> n = get(key)) {
      *value = n->AsInt();
      if (*value <= 0) n->Fail(std::string("an image ") + key + " > 0 [px]");
    }
  }
  const char* names[kNumIntrinsics] = {"fx", "fy", "cx", "cy"};
  for (int i = 0; i < kNumIntrinsics; ++i) {
    if (const std::optional<YamlNode> n = get(names[i])) {
      const double x = n->AsDouble();
      if (i < 2 && !(x > 0)) n->Fail(std::string("a focal length ") + names[i] + " > 0 [px]");
      cam->intrinsics[i] = x;
    }
  }
  if (const std::optional<YamlNode> n = m.Find("distortion")) {
    const std::vector<double> d = n->AsDoubles();
    if (d.size() > kNumDistortion) {
      n->Fail("at most 14 OpenCV coefficients k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 taux tauy");
    }
    cam->distortion.fill(0.0);
    std::copy(d.begin(), d.end(), cam->distortion.begin());
  }
  // SPEC 4.1, in report units: {kf: mm, au: px m, av: px m}.
  if (const std::optional<YamlNode> n = m.Find("focus")) {
    for (int i = 0; i < kNumFocus; ++i) {
      double x = 0;
      ReadNumber(*n, kFocusParamNames[i], &x, [](double v) { return std::isfinite(v); },
                 std::string("a finite number [") + kFocusReportUnits[i] + "]");
      cam->focus[i] = x / kFocusReportScale[i];
    }
  }
}

// Numbers go through YamlDouble (shortest) rather than the emitter's own
// double output, which writes 1e-05 as 1.0000000000000001e-05.
std::string Num(double x) { return YamlDouble(x, /*shortest=*/true); }

void EmitList(YAML::Emitter& e, const std::vector<double>& x) {
  EmitNumbers(e, x.data(), x.size(), /*shortest=*/true);
}
void EmitInts(YAML::Emitter& e, const std::vector<int>& x) {
  e << YAML::Flow << YAML::BeginSeq;
  for (int v : x) e << v;
  e << YAML::EndSeq;
}

void EmitPose(YAML::Emitter& e, const PoseBlock& pose) {
  e << YAML::Key << "q" << YAML::Value;
  EmitNumbers(e, pose.q.data(), 4, /*shortest=*/true);
  e << YAML::Key << "t" << YAML::Value;
  EmitNumbers(e, pose.t.data(), 3, /*shortest=*/true);
}

void EmitCameraFields(YAML::Emitter& e, const CameraTool& cam) {
  e << YAML::Key << "width" << YAML::Value << cam.width;
  e << YAML::Key << "height" << YAML::Value << cam.height;
  const char* names[kNumIntrinsics] = {"fx", "fy", "cx", "cy"};
  for (int i = 0; i < kNumIntrinsics; ++i) {
    e << YAML::Key << names[i] << YAML::Value << Num(cam.intrinsics[i]);
  }
  e << YAML::Key << "distortion" << YAML::Value;
  EmitNumbers(e, cam.distortion.data(), cam.distortion.size(), /*shortest=*/true);
  if (cam.focus != std::array<double, kNumFocus>{}) {
    e << YAML::Key << "focus" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (int i = 0; i < kNumFocus; ++i) {
      e << YAML::Key << kFocusParamNames[i] << YAML::Value
        << Num(cam.focus[i] * kFocusReportScale[i]);
    }
    e << YAML::EndMap;
  }
}

}  // namespace rtscalib
