// targets.yaml (SPEC 7): the AprilTag boards seen in a real instrument's photos.
//
//   boards:
//     - {family: tag36h11, first_id: 0, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015}
//     - {family: tag36h11, first_id: 48, rows: 6, cols: 8, tag_size: 0.06, spacing: 0.015,
//        pose: {euler: [a, b, g], t: [x, y, z]}}   # surveyed ref_from_board
//     - {type: charuco, dictionary: DICT_4X4_50, first_id: 100, rows: 5, cols: 7,
//        square_size: 0.04, marker_size: 0.03}
//     - {type: chessboard, first_id: 200, rows: 6, cols: 9, square_size: 0.025}
//
// `type` is apriltag (the default), charuco or chessboard. ChArUco and
// chessboards are boards of points (libcalib/model/targets.h): rows x cols
// squares (>= 2 each) of square_size [m]; their targets are the inner corners,
// first_id + k, corner 0. ChArUco: dictionary is OpenCV's predefined
// dictionary name, marker_size < square_size [m]; the markers' ids are
// OpenCV's (0, 1, ... in the board's white squares) and are not targets.
//
// Per board: family (a tag family name), first_id (integer >= 0), rows and
// cols (integers >= 1), tag_size (> 0 [m], the detection quad's edge, for
// tag36h11 the outer edge of the black border), spacing (>= 0 [m], the gap
// between neighbouring quads), optionally border_bits (1, the default, or 2:
// the black border's width in code bits, Kalibr's AprilGrid has 2; only for
// families whose quad is the outer edge of their black border) and ids_from
// (top_left, the default, or bottom_left: Kalibr's AprilGrid numbers its rows
// upwards), and an optional pose: ref_from_board with
// R = Rz(g) Ry(b) Rx(a) [rad] (SPEC 1, paper Eq. 83) and t [m]. A board
// without a pose gets TagBoard::pose_known = false. Board layout and corner
// order: libcalib/model/targets.h. A chessboard needs at least 4 x 4 squares
// (3 x 3 inner corners, what OpenCV's detector takes).
//
// Kalibr's own target file is read too (SPEC 7.2), wherever a targets.yaml
// is: `target_type: aprilgrid` (tagCols, tagRows, tagSize [m], tagSpacing =
// gap / tagSize) is one tag36h11 board with border_bits 2, first_id 0,
// ids_from bottom_left and spacing = tagSpacing tagSize; `target_type:
// checkerboard` (targetCols, targetRows = inner corners, rowSpacingMeters,
// colSpacingMeters, which must be equal) is one chessboard of (targetRows +
// 1) x (targetCols + 1) squares. Neither has a pose. Other keys are errors
// naming the key, as in a targets.yaml.
//
// Tag ids are the `target` column of pixels.csv, so the id ranges
// [first_id, first_id + rows cols) of all boards must not overlap (whatever
// their families). Unknown keys, missing keys and bad values are InputErrors
// naming the file, the key path (`boards[1].tag_size`) and its line.
#pragma once

#include <map>
#include <string>

#include "libcalib/model/targets.h"

namespace rtscalib {

// `family_codes`, when given, maps the tag families the caller can detect to
// their number of codes: other families are errors, and so are ids beyond a
// family's last code. ArUco dictionaries (ChArUco) are in it as
// "aruco:<name>" with their number of markers. (libcalib knows no tag family;
// detect/ does: detect::DetectableCodeCounts().)
class YamlNode;

// The key of an ArUco dictionary in `family_codes` ("aruco:<name>").
std::string ArucoCodesKey(const std::string& dictionary);
// The key in `family_codes` of a tag family that may be printed with a wider
// black border (`border_bits` > 1): present when the caller can detect it.
std::string WideBorderKey(const std::string& family);

// One board's layout (everything but its pose) from a targets.yaml or
// model.yaml board mapping, with the rules above; errors name the key.
TagBoard ReadBoardLayout(const YamlNode& item,
                         const std::map<std::string, int>* family_codes = nullptr);

TargetScene ReadTargets(const std::string& path,
                        const std::map<std::string, int>* family_codes = nullptr);
// The same for YAML text; messages name it `name`.
TargetScene ParseTargets(const std::string& text, const std::string& name,
                         const std::map<std::string, int>* family_codes = nullptr);

// Writes `scene` as targets.yaml (the format above, numbers with 17
// significant digits so that they read back exactly); boards with
// pose_known get their pose, the others none. `with_poses == false` leaves
// every pose out (a photo session whose boards are all to be estimated).
// Written whole or not at all (safe_write.h); throws WriteError naming the
// file when it cannot be written.
void WriteTargets(const std::string& path, const TargetScene& scene, bool with_poses = true,
                  const std::string& comment = "");

}  // namespace rtscalib
