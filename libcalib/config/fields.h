// The values the config's sections share (libcalib/config): checked
// numbers, poses, cameras, enum names, and their dump. Each read fails with
// an InputError at the key that holds the value (YamlNode::Fail): key path,
// file, line, what was expected, what came.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "libcalib/io/yaml_reader.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {

constexpr double kRadPerDeg = M_PI / 180.0;
constexpr double kRadPerArcsec = M_PI / (180.0 * 3600.0);

template <typename E>
using Names = std::vector<std::pair<std::string, E>>;

template <typename E>
const std::string& NameOf(const Names<E>& names, E value) {
  for (const auto& [name, v] : names) {
    if (v == value) return name;
  }
  static const std::string kUnknown = "?";
  return kUnknown;
}

// Every effect of the catalogue by name (for "expected one of").
std::vector<std::string> AllEffectNames();

// --- checked reads: each failure points at the key that holds the value ----

using DoubleCheck = bool (*)(double);
bool IsPositive(double x);     // x > 0
bool IsNonNegative(double x);  // x >= 0

// Reads `key` into *value if present (returns whether it was); `expected`
// describes a valid value.
bool ReadNumber(const YamlNode& m, const std::string& key, double* value, DoubleCheck ok,
                const std::string& expected);

// An integer >= min at `key`, if present; `what` names it in the message.
void ReadCount(const YamlNode& m, const std::string& key, int* value, int min,
               const std::string& what);

// A non-empty list of numbers that all pass `ok`.
void ReadNumbers(const YamlNode& m, const std::string& key, std::vector<double>* value,
                 DoubleCheck ok, const std::string& expected);

// The number y, written shortest, for which y * scale == x exactly if one
// exists next to x / scale: so that dumped degrees and arcseconds give back
// the same radians.
std::string ExactScaled(double x, double scale);

// A pose {euler: [a, b, g] (Klug Eq. 83) | q: [x, y, z, w], t: [x, y, z]}.
// Each key is optional: what is absent keeps *pose's value. People write
// Euler angles; DumpConfig writes quaternions, which read back bit for bit
// (Euler angles lose digits near b = +-pi/2, where the ideal tools sit).
void ReadPoseFields(const YamlNode& m, PoseBlock* pose);
void ReadPoseFields(const YamlNode& m, Rigid3* pose);

// Image size, intrinsics and distortion of one zoom level. `required`: all of
// width, height, fx, fy, cx, cy must be given (model.cameras); otherwise
// absent keys keep *cam's values (simulated truth).
void ReadCameraFields(const YamlNode& m, bool required, CameraTool* cam);

// --- dump ---------------------------------------------------------------------

// Numbers go through YamlDouble (shortest) rather than the emitter's own
// double output, which writes 1e-05 as 1.0000000000000001e-05.
std::string Num(double x);

// Flow lists [a, b, c].
void EmitList(YAML::Emitter& e, const std::vector<double>& x);
void EmitInts(YAML::Emitter& e, const std::vector<int>& x);
// The keys q and t of a pose, into the map being written.
void EmitPose(YAML::Emitter& e, const PoseBlock& pose);
// The keys ReadCameraFields reads, into the map being written.
void EmitCameraFields(YAML::Emitter& e, const CameraTool& cam);

}  // namespace rtscalib
