// Planning a session before it is measured (SPEC 8): which photos to take so
// that the calibration reaches the sigmas the user asks for, with as few
// shots as the targets allow.
//
// Prediction. The calibration's covariance is the pseudo-inverse of the
// whitened information J^T J of its free parameters (libcalib/fit/refine.cc,
// TangentCovariance). A photo not yet taken adds the information of its
// rows, J_c^T J_c, evaluated at the a-priori model with the a-priori sigmas
// (fit.sigmas): the same cost functions, observation groups and
// Parameterization as the fit, through the diagnosis's Linearize
// (libcalib/diagnose/linearization.h, its boards kept as columns so that a
// subset of the photos has its own board poses). The predicted covariance of
// a set of shots is
//   P = (I_fixed + sum_{c in set} J_c^T J_c)^+,
// I_fixed = the information of what is measured anyway (records of a tracker
// session, an earlier run's photos). A constant's predicted sigma is
// sqrt(g^T P g), g its gradient with respect to the free parameters (the
// effects' report units through ToReportUnits); the projection sigma of a
// zoom is, as in the report's uncertainty maps (libcalib/api/uncertainty_map.h),
// the largest over a grid of image cells of sqrt(lambda_max(G P G^T)), G =
// d pixel / d parameters of a point at the map's range and pointing.
//
// Candidates. The simulator's shot pattern (libcalib/sim, ShotPlan) at the
// a-priori model, denser and without jitter: for every zoom, face and
// usable board of every placement, `candidates_per_board` pointings that put
// the board over the whole image, each a photo that shows >= 8 corners.
// A camera on its own (model.kinematics: none) does not turn: its
// candidates are poses of the session's first board (board_poses.h), each a
// placement of its own with one photo, the board's pose estimated.
// A zoom's projection sigma is then taken up to the camera's rotation, as
// its uncertainty map is (over every cell of the grid: where the photos
// will fall is what is being planned).
//
// Design (Atkinson, Donev & Tobias, "Optimum Experimental Designs", ch. 10-12):
// greedy sequential A-optimality toward the goal. Each step takes the
// candidate that most reduces
//   Phi = sum over unmet goals k of g_k^T P g_k / goal_k^2
// (a projection goal counts each of its cells' two image directions), the
// exact reduction of the rank-r update
//   Phi - Phi' = trace(S^-1 A^T W A),  A = P L_c, S = I + L_c^T P L_c,
// L_c L_c^T = J_c^T J_c, W = sum g g^T / goal^2, evaluated on a shortlist of
// the candidates with the largest first-order reduction <P W P, J_c^T J_c>.
// It stops when every goal is met or at the budget. Without a goal it is
// greedy D-optimal (the largest log det(S)) up to the budget. Then an
// exchange pass removes every shot whose removal keeps the goal met
// (backward elimination, the cheapest first). Directions of the parameters
// that no candidate determines (the information of every candidate and the
// fixed data together is rank-deficient there) are reported as such, never
// as a sigma.
#pragma once

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "libcalib/api/uncertainty_map.h"
#include "libcalib/calibrate/options.h"
#include "libcalib/model/instrument.h"
#include "libcalib/model/observations.h"
#include "libcalib/model/targets.h"
#include "libcalib/plan/board_poses.h"
#include "libcalib/sim/options.h"

namespace rtscalib {

// What the user asks for.
struct PlanGoal {
  // Constant name -> sigma in its report unit (PredictedConstant::name:
  // "hz_eccentricity.e" [arcsec], "cam[0].fx" [px], "cam[1].k1" [1], ...).
  std::vector<std::pair<std::string, double>> sigmas;
  double projection_px = 0;  // worst projection sigma per zoom [px]; 0 = no goal
  bool Empty() const { return sigmas.empty() && projection_px <= 0; }
};

struct PlanOptions {
  PlanGoal goal;
  std::vector<int> faces{1, 2};
  std::vector<int> zooms;  // empty: every zoom of the model
  int max_shots = 400;     // budget (0: the prediction of PlanSession::fixed alone)
  // Candidate pointings per usable board, zoom and face (the simulator's
  // stratified pattern, ShotPlan::shots_per_board) and how much of the view
  // the pattern spans (ShotPlan::fill).
  int candidates_per_board = 16;
  double fill = 0.7;
  bool exchange = true;  // the pass that removes shots the goal does not need
  // Photos per zoom a plan takes at least, whatever the goal: a session
  // without records starts each zoom's camera from its photos alone
  // (libcalib/fit/calibrate_views.h, OpenCV's calibrateCamera of several
  // views of a planar board), which a first-order design does not see; -1
  // (default) = 16 for a session without camera records, else 0 (with 8
  // per zoom the one-board session of configs/one_board.yaml does not
  // converge from its start; with 16 it does).
  int min_shots_per_zoom = -1;
  // Where the projection sigma is evaluated (the report's uncertainty maps'
  // options: pointing, range, grid).
  UncertaintyMapOptions projection;
  // "" when valid, else "plan.<key>: expected ...".
  std::string Check() const;
};

// The session to plan: the a-priori knowledge of SPEC 8.
struct PlanSession {
  // The a-priori instrument: a previous calibration's model.yaml or the
  // simulated truth. Its values are where the information is evaluated.
  InstrumentModel prior;
  // What will be estimated (model.kinematics, effects, intrinsics,
  // distortion choices) and the a-priori observation sigmas (fit.sigmas).
  CalibrationOptions calibration;
  // The boards, per placement (SPEC 7.1; one placement "" when they do not
  // move).
  PlacedScenes scenes;
  // True: the boards' poses are surveyed (pixels with known X). False: each
  // placement's pose of each board is estimated with everything else.
  bool board_poses_known = true;
  // Observations taken in any case (a tracker's records, an earlier run's
  // photos): their information is part of every plan.
  Observations fixed;
};

// One photo of the plan.
struct PlanShot {
  PlannedShot pointing;       // face, zoom, phi, theta, placement, name
  double focus_distance = 0;  // [m] the distance the camera focuses at (SPEC 4.1); 0: not used
  int points = 0;             // corners the photo shows at the a-priori model
  // A camera on its own (board_poses.h): where the board is held for this
  // photo (its own placement), in the camera's frame and in words, and its
  // outline in the image at the a-priori camera.
  bool board_pose = false;
  Rigid3 cam_from_board;
  BoardPoseInWords board;
  std::vector<Eigen::Vector2d> board_outline;
  // What the shot was chosen for: the goal (or, without a goal, the
  // parameter group) whose variance it reduced most, relatively.
  std::string determines;
  // What the shot buys: per goal constant, its predicted sigma without this
  // shot (the other shots of the plan taken), to compare with the plan's.
  std::vector<std::pair<std::string, double>> sigma_without;
};

struct PredictedConstant {
  std::string name;  // "hz_eccentricity.e", "cam[0].fx", "link1.alpha", "base.t[x]"
  std::string unit;  // report unit
  double sigma = std::numeric_limits<double>::quiet_NaN();  // NaN when not determined
  double goal = 0;                                          // 0: no goal for it
  bool determined = true;  // false: these targets cannot determine it (any number of shots)
  // Predicted sigma with every candidate photo taken (what the geometry
  // allows; NaN when not determined).
  double sigma_all_candidates = std::numeric_limits<double>::quiet_NaN();
  // Predicted sigma of what is measured in any case (PlanSession::fixed)
  // alone: NaN when that does not determine it.
  double sigma_fixed = std::numeric_limits<double>::quiet_NaN();
};

struct PredictedProjection {
  int zoom = 0;
  int width = 0, height = 0;  // the zoom's image [px]
  double worst_px = 0;  // over the grid of PlanOptions::projection
  double goal_px = 0;
};

struct PlanResult {
  std::vector<PlanShot> shots;  // in measuring order (OrderShots)
  std::vector<PredictedConstant> constants;
  std::vector<PredictedProjection> projection;
  bool goal_met = false;
  std::vector<std::string> limits;  // why the goal is not met (empty when it is)
  int candidates = 0;               // photos in the candidate pool
  int fixed_observations = 0;       // rows of PlanSession::fixed used
  double motor_travel_rad = 0;      // sum over consecutive shots of the larger axis move
  // Criterion after every greedy step (A: Phi over every goal functional,
  // D: -log det of the information in the determined directions): never
  // increases. Tests check it.
  std::vector<double> criterion;
  std::vector<double> log_det;  // log det of the information after every greedy step
};

// Plans `session`. Throws std::invalid_argument for bad options or a goal
// naming a constant the model does not estimate (the message lists them).
PlanResult PlanShots(const PlanSession& session, const PlanOptions& options);

// The a-priori model as the calibration will estimate it: `session.prior`
// with the kinematics, effects and held distortion of `session.calibration`
// (effects the prior lacks start at zero), and, when the boards' poses are
// not known, one estimated pose per board and placement at its scene pose.
InstrumentModel PlanningModel(const PlanSession& session);

// The observations of photos at `shots` as the simulator takes them at
// `model` (exact pixels, noise `pixel_sigma_px` with `seed`), board corners
// with X empty when the poses are not known: what the tests calibrate. A
// shot with a board pose (a camera on its own) shows the session's first
// board there.
Observations SimulatePlannedShots(const PlanSession& session, const std::vector<PlanShot>& shots,
                                  double pixel_sigma_px, std::uint64_t seed);

}  // namespace rtscalib
