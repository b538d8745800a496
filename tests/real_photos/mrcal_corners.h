// The mrcal tour's chessboard corners (../shared/real-photos/mrcal_tour_corners:
// 186 views of a 10 x 10-corner board with 0.077 m spacing, seen by a wide
// lens at 6016 x 4016 px, found by mrgingham) as a camera-only session
// rtscalib reads (SPEC 7.1): pixels.csv with one placement per view, X Y Z
// empty, target = row * 10 + col of the chessboard's inner corners, and a
// targets.yaml with that chessboard (11 x 11 squares). No photos: the image
// size comes from pixels.csv's width/height columns. mrcal's pixel
// convention is OpenCV's (SPEC 2: (0, 0) is the top-left pixel's centre),
// so the corners are written as they are. Corners mrcal marks as outliers or
// missing (weight <= 0) are left out, as in the set's ref.json; mrgingham's
// weights (1, 0.5, 0.25, 0.125: its decimation level) are kept in an extra
// `weight` column, which rtscalib's reader ignores with a note.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rtscalib::testing_real_photos {

struct MrcalSession {
  std::string pixels;   // pixels.csv
  std::string targets;  // targets.yaml
  int views = 0;
  int corners = 0;
};

// Writes pixels.csv and targets.yaml into `out_dir` (which must exist).
inline MrcalSession WriteMrcalSession(const std::string& set_dir, const std::string& out_dir) {
  std::ifstream in(set_dir + "/corners.csv");
  if (!in) throw std::runtime_error("cannot read " + set_dir + "/corners.csv");
  MrcalSession s;
  s.pixels = out_dir + "/pixels.csv";
  s.targets = out_dir + "/targets.yaml";
  std::ofstream px(s.pixels);
  px << "face,zoom,phi,theta,shot,placement,target,corner,X,Y,Z,u,v,width,height,weight\n";
  std::string line;
  int last_frame = -1;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("frame", 0) == 0) continue;
    std::stringstream ss(line);
    std::string f[8];
    for (std::string& field : f) std::getline(ss, field, ',');
    const int frame = std::stoi(f[0]), row = std::stoi(f[1]), col = std::stoi(f[2]);
    if (!(std::stod(f[5]) > 0)) continue;
    if (frame != last_frame) ++s.views;
    last_frame = frame;
    const std::string view = "v" + std::to_string(frame);
    px << "1,0,,," << view << "," << view << "," << row * 10 + col << ",0,,,," << f[3] << ","
       << f[4] << ",6016,4016," << f[5] << "\n";
    ++s.corners;
  }
  std::ofstream t(s.targets);
  t << "# mrcal's tour board: 10 x 10 inner corners, 0.077 m apart\n"
       "boards:\n"
       "  - {type: chessboard, first_id: 0, rows: 11, cols: 11, square_size: 0.077}\n";
  if (!px || !t) throw std::runtime_error("cannot write the mrcal session into " + out_dir);
  return s;
}

}  // namespace rtscalib::testing_real_photos
