// targets.yaml reader (libcalib/io/targets_io.h) against its documented rules:
// an accepted scene has boards with finite, positive sizes, proper rotations,
// non-overlapping id ranges that fit in an int, ids within the family's codes
// when the families are given; and it writes and reads back to the same scene.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <string>

#include "fuzz/fuzz_util.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/targets_io.h"

namespace {

using rtscalib::TagBoard;
using rtscalib::TargetScene;
using rtscalib::fuzz::Require;
using rtscalib::fuzz::RequireFinite;

// Codes per family as detect/ reports them (tag36h11 587, tag25h9 35).
const std::map<std::string, int> kFamilies = {{"tag36h11", 587}, {"tag25h9", 35}};

void RequireValid(const TargetScene& scene, const std::map<std::string, int>* families) {
  for (size_t i = 0; i < scene.boards.size(); ++i) {
    const TagBoard& b = scene.boards[i];
    Require(!b.family.empty(), "a family");
    Require(b.first_id >= 0 && b.rows >= 1 && b.cols >= 1, "first_id >= 0, rows, cols >= 1");
    const long long last = static_cast<long long>(b.first_id) +
                           static_cast<long long>(b.rows) * static_cast<long long>(b.cols) - 1;
    Require(last <= std::numeric_limits<int>::max(), "the id range fits in an int");
    RequireFinite(b.tag_size, "tag_size");
    RequireFinite(b.spacing, "spacing");
    Require(b.tag_size > 0 && b.spacing >= 0, "tag_size > 0, spacing >= 0");
    Require(b.border_bits == 1 || b.border_bits == 2, "border_bits 1 or 2");
    const Eigen::Matrix3d& R = b.ref_from_board.rotation;
    for (int k = 0; k < 9; ++k) RequireFinite(R.data()[k], "pose rotation");
    for (int k = 0; k < 3; ++k) RequireFinite(b.ref_from_board.translation[k], "pose t");
    Require((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
                std::abs(R.determinant() - 1) < 1e-9,
            "the pose's rotation is proper");
    if (families && !b.IsPointBoard()) {
      const auto family = families->find(b.family);
      Require(family != families->end(), "a known family");
      Require(last < family->second, "ids within the family's codes");
    }
    for (size_t j = 0; j < i; ++j) {
      const TagBoard& o = scene.boards[j];
      Require(b.LastId() < o.first_id || o.LastId() < b.first_id, "id ranges do not overlap");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return rtscalib::fuzz::RunFileReader(data, size, ".yaml", [](const std::string& path) {
    const TargetScene scene = rtscalib::ReadTargets(path);
    RequireValid(scene, nullptr);
    try {
      RequireValid(rtscalib::ReadTargets(path, &kFamilies), &kFamilies);
    } catch (const rtscalib::InputError&) {
      // The families are a narrower rule; a clean refusal is fine.
    }
    // Written and read again: the same boards (WriteTargets keeps 17 digits).
    const std::string copy = path + ".again.yaml";
    rtscalib::WriteTargets(copy, scene);
    const TargetScene again = rtscalib::ReadTargets(copy);
    Require(again.boards.size() == scene.boards.size(), "the same number of boards");
    for (size_t i = 0; i < scene.boards.size(); ++i) {
      const TagBoard& a = scene.boards[i];
      const TagBoard& b = again.boards[i];
      Require(a.family == b.family && a.first_id == b.first_id && a.rows == b.rows &&
                  a.cols == b.cols && a.tag_size == b.tag_size && a.spacing == b.spacing &&
                  a.border_bits == b.border_bits && a.ids_from == b.ids_from &&
                  a.kind == b.kind && a.square_size == b.square_size &&
                  a.pose_known == b.pose_known,
              "a board reads back the same");
      Require((a.ref_from_board.rotation - b.ref_from_board.rotation).norm() < 1e-12 &&
                  (a.ref_from_board.translation - b.ref_from_board.translation).norm() <=
                      1e-15 * (1 + a.ref_from_board.translation.norm()),
              "a pose reads back the same");
    }
  });
}
