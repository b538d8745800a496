// Options of the simulated instrument (libcalib/sim/simulator.h): the truth,
// the acquisition plan of Klug Sec. 4, the noise and the shots of known
// targets. Beside the simulator so that readers of these options (the config
// loader in libcalib/io) need not include the simulator.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "libcalib/model/instrument.h"
#include "libcalib/model/targets.h"

namespace rtscalib {

struct NoiseOptions {
  double angle_rad = 0.0;     // sigma of phi and theta readings
  double distance_m = 0.0;    // sigma of the EDM distance
  double point_m = 0.0;       // sigma of each coordinate of a returned point
  double pixel_px = 0.0;      // sigma of each pixel coordinate (pixels.csv)
  std::string Check() const;  // empty if valid
};

struct AcquisitionPlan {
  int sweep_points = 15;
  std::vector<double> edm_distances{1.0, 2.0};
  double cam_ray_length = 1.0;
  double pixel_offset = 1.0;
  bool sweeps = true;      // the paper's two joint sweeps ("sweep1", "sweep2")
  int grid_phi_steps = 0;  // 0 = no grid
  int grid_theta_steps = 0;
  // Grid rows also use these distances and image points (fractions of the
  // image size, e.g. 0.1 .. 0.9), so that held-out points differ in angle,
  // distance and pixel.
  std::vector<double> grid_edm_distances{1.0, 2.0, 5.0, 20.0};
  std::vector<double> grid_cam_ray_lengths{1.0, 3.0};
  int grid_pixels_per_axis = 3;  // n x n pixels over [0.1, 0.9] of the image
  std::vector<int> faces{1};
  std::vector<int> zooms{0};
  // Bounds that keep a simulation's memory in reach (a 1e5 x 1e5 grid would
  // need about 13 GB): at most kMaxRecords records (EstimatedRecords) and
  // zoom levels below kMaxZoomLevels (the truth has a camera per level).
  static constexpr double kMaxRecords = 2e6;
  static constexpr int kMaxZoomLevels = 100;
  // The number of records the plan gives (PlanRecords), computed without
  // building them (in double: the product of counts may exceed any int).
  double EstimatedRecords() const;
  // Empty if the plan is within the bounds above, else what is wrong, naming
  // the simulate.plan keys to change.
  std::string CheckSize() const;
  std::string Check() const;  // includes CheckSize()
};

// Shots of known targets (simulator.cc, SimulatePixels): for every zoom and
// face the instrument aims at the boards that suit that zoom (whole tags fit
// the view >= 2.5 times across and the board spans >= 1/4 of it; the best
// board when none does) from a stratified pattern of directions, so that the
// images are full of tags and together cover the whole image. Shots showing
// fewer than 8 corners are not taken.
// One photo at a given pointing (a planned session, libcalib/plan): the
// simulator takes it as it stands instead of choosing its own.
struct PlannedShot {
  int face = 1;
  int zoom = 0;
  double phi = 0, theta = 0;  // readings of `face` [rad]
  std::string placement;      // SPEC 7.1; "" without placements
  std::string name;           // shot id; "" = the simulator's own numbering
};

struct ShotPlan {
  int shots_per_board = 4;       // per usable board, zoom and face
  double fill = 0.7;             // fraction of the view (half extent) the pattern is sized by
  double pointing_jitter = 0.3;  // jitter of each aim within its pattern cell (fraction of a cell)
  // SPEC 4.1, a truth with the focus effect: each photo is taken focused at
  // its D, the distance from the camera to the centroid of the corners it
  // shows; true: the photo reports D (PixelObservation::focus_distance, as
  // an instrument reports its focus or EDM distance), false: it does not
  // (the calibration then computes D from the model).
  bool report_focus_distance = true;
  // Non-empty: exactly these photos are taken (each showing at least 8
  // corners; the others are left out), not the stratified pattern above.
  std::vector<PlannedShot> given;
};

struct SimulationOptions {
  std::uint64_t seed = 1;
  InstrumentModel truth;
  NoiseOptions noise;
  AcquisitionPlan plan;
  // empty = no pixel observations. A board's TagBoard::warp hides the effect
  // board_warp in the data: its corners are warped, the observations do not
  // say so.
  TargetScene targets;
  // SPEC 7.1: boards moved between sets of shots (a surveyor's one board):
  // the scene of each placement by name (letters, digits, '_', '-', '.').
  // Non-empty replaces `targets` (which must then be empty); the shots are
  // planned over every placement and carry its name.
  PlacedScenes placements;
  ShotPlan shots;
  std::string Check() const;
  // The scenes the shots see: `placements`, or `targets` as the one placement "".
  PlacedScenes Scenes() const;
};

// Number of zoom levels a plan uses: the largest zoom + 1.
int PlanNumZooms(const AcquisitionPlan& plan);

}  // namespace rtscalib
