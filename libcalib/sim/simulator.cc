#include "libcalib/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "libcalib/camera/opencv_model.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib {
namespace {

// One pointing of the plan in face 1; face-2 readings are derived (SPEC 1).
struct Pose {
  double phi, theta;
  const char* set;
};

std::vector<Pose> PlanPoses(const AcquisitionPlan& plan) {
  std::vector<Pose> poses;
  const int n = plan.sweep_points;
  if (plan.sweeps) {
    for (int k = 0; k < n; ++k) poses.push_back({2.0 * M_PI * k / n, M_PI / 2, "sweep1"});
    for (int k = 0; k < n; ++k) poses.push_back({0.0, M_PI * k / (n - 1), "sweep2"});
  }
  for (int i = 0; i < plan.grid_phi_steps; ++i) {
    for (int j = 0; j < plan.grid_theta_steps; ++j) {
      poses.push_back(
          {2.0 * M_PI * i / plan.grid_phi_steps, M_PI * (j + 0.5) / plan.grid_theta_steps, "grid"});
    }
  }
  return poses;
}

void Reading(int face, const Pose& p, double* phi, double* theta) {
  if (face == 1) {
    *phi = p.phi;
    *theta = p.theta;
  } else {
    OtherFace(p.phi, p.theta, phi, theta);
  }
}

}  // namespace

InstrumentModel PaperTruth(int num_zooms) {
  InstrumentModel m;
  m.kinematics = Kinematics::kDh;
  // Klug Table 7 (optimised base and tools) and Table 6 (optimised DH).
  m.base = PoseBlock::FromRigid(
      Rigid3::FromEuler({3.1416, 0.0, 0.0504}, {5.915e-9, 7.216e-9, 3.312e-9}));
  m.links[0].p = {0.0, -1.5203, 1.570808, 0.0};
  m.links[1].p = {0.0684e-3, -0.4432e-3, 0.2055e-3, -0.1117e-3};
  m.edm = PoseBlock::FromRigid(
      Rigid3::FromEuler({-1.4219, 1.5693, 3.2910}, {0.1421e-3, 1.415e-6, -9.014e-5}));
  for (int z = 0; z < num_zooms; ++z) {
    CameraTool cam;
    // Each zoom level: its own small tool change and a longer focal length
    // (the PLT 300 has 7 calibrated zoom positions; values are illustrative).
    // Camera alpha from Table 2 (-1.5020): Table 7's -1.4632 with b = 1.5646
    // (near gimbal lock, where only g - a matters) would turn the optical axis
    // 2.2 deg off the EDM ray, which no coaxial RTS camera is; Table 2's value
    // keeps it within 1e-3 rad, as Klug's Table 4 (camera, method A) shows.
    cam.flange_from_cam = PoseBlock::FromRigid(
        Rigid3::FromEuler({-1.5020 + 1.5e-4 * z, 1.5646 - 0.8e-4 * z, 3.2103 + 1.2e-4 * z},
                          {-0.1451e-3 + 2e-5 * z, -2.152e-9 + 1e-5 * z, 0.1505e-3 - 1.5e-5 * z}));
    cam.width = 1280;
    cam.height = 960;
    const double f = 1500.0 * std::pow(2.0, z);
    cam.intrinsics = {f, f * (1.0 + 2e-4), 640.0 + 3.0 * z - 2.5, 480.0 - 2.0 * z + 1.5};
    cam.distortion.fill(0.0);
    m.cams.push_back(cam);
  }
  return m;
}

std::vector<Record> PlanRecords(const AcquisitionPlan& plan, const InstrumentModel& model) {
  std::vector<Record> out;
  for (int face : plan.faces) {
    for (const Pose& pose : PlanPoses(plan)) {
      double phi, theta;
      Reading(face, pose, &phi, &theta);
      const bool grid = std::string(pose.set) == "grid";
      for (double d : grid ? plan.grid_edm_distances : plan.edm_distances) {
        Record r;
        r.face = face;
        r.zoom = 0;
        r.phi = phi;
        r.theta = theta;
        r.tool = Tool::kEdm;
        r.d = d;
        r.set = pose.set;
        out.push_back(r);
      }
      for (int zoom : plan.zooms) {
        const CameraTool& cam = model.cams.at(zoom);
        const double cx = cam.intrinsics[2], cy = cam.intrinsics[3];
        std::vector<std::pair<double, double>> pixels;
        std::vector<double> lengths;
        if (grid) {
          const int n = plan.grid_pixels_per_axis;
          for (int i = 0; i < n; ++i) {
            for (int j = 0; j < n; ++j) {
              const double fu = n == 1 ? 0.5 : 0.1 + 0.8 * i / (n - 1);
              const double fv = n == 1 ? 0.5 : 0.1 + 0.8 * j / (n - 1);
              pixels.emplace_back(fu * (cam.width - 1), fv * (cam.height - 1));
            }
          }
          lengths = plan.grid_cam_ray_lengths;
        } else {
          pixels = {{cx, cy}, {cx + plan.pixel_offset, cy}, {cx, cy + plan.pixel_offset}};
          lengths = {plan.cam_ray_length};
        }
        for (double len : lengths) {
          for (const auto& [u, v] : pixels) {
            Record r;
            r.face = face;
            r.zoom = zoom;
            r.phi = phi;
            r.theta = theta;
            r.tool = Tool::kCam;
            r.u = u;
            r.v = v;
            r.d = len;
            r.set = pose.set;
            out.push_back(r);
          }
        }
      }
    }
  }
  for (Record& r : out) {
    r.x = r.tool == Tool::kEdm ? PredictEdm(model, r.phi, r.theta, r.d)
                               : PredictCam(model, r.zoom, r.phi, r.theta, r.u, r.v, r.d);
  }
  return out;
}

namespace {

// Pointing (face 1) that makes the ideal line of sight pass through `target`
// from the station origin `origin` (SPEC 1: phi clockwise from +y, theta from zenith).
void AimAt(const Eigen::Vector3d& origin, const Eigen::Vector3d& target, double* phi,
           double* theta) {
  const Eigen::Vector3d v = target - origin;
  *phi = std::atan2(v.x(), v.y());
  if (*phi < 0) *phi += 2.0 * M_PI;
  *theta = std::acos(std::clamp(v.z() / v.norm(), -1.0, 1.0));
}

// How a board looks from the station at one zoom: angular half extents of
// the board, of one tag and of the field of view [rad].
struct BoardView {
  int board = 0;
  double board_u = 0, board_v = 0, tag = 0;
  double fov_u = 0, fov_v = 0;
  // Tags across the image width: a board "fills the image" usefully when
  // whole tags fit (>= ~2.5 across, else most shots show < 8 corners) and the
  // board is not a speck (it spans >= 1/4 of the view).
  double TagsAcross() const { return fov_u / tag; }
  double Fill() const { return std::max(board_u / fov_u, board_v / fov_v); }
  bool Usable() const { return TagsAcross() >= 2.5 && Fill() >= 0.25; }
};

BoardView ViewOfBoard(const TagBoard& b, int index, const Eigen::Vector3d& origin,
                      const CameraTool& cam) {
  BoardView v;
  v.board = index;
  const double dist = (b.CentreInRef() - origin).norm();
  v.board_u = std::atan2(0.5 * b.Width(), dist);
  v.board_v = std::atan2(0.5 * b.Height(), dist);
  // A point board's "tag" is its square (an inner corner with its squares).
  v.tag = std::atan2(0.5 * (b.IsPointBoard() ? b.square_size : b.tag_size), dist);
  v.fov_u = std::atan2(0.5 * cam.width, cam.intrinsics[0]);
  v.fov_v = std::atan2(0.5 * cam.height, cam.intrinsics[1]);
  return v;
}

// Shot planning (docs/refinement.md): for every zoom level the boards whose
// tags fit the view several times and that span a good part of it are used
// (the best one alone when none qualifies, so every zoom gets shots). Each
// board gets `shots_per_board` pointings per face on a stratified pattern,
// per image axis:
//   board wider than the view: the aim wanders over the board (half range
//     board - fill x view), so every image is full of tags;
//   board narrower: the board centre is placed at chosen image positions,
//     from the position where the board's edge touches one image edge
//     (kEdgeReach of the half view, so that its tags stay whole) to the one
//     where it touches the opposite edge. The positions of a pattern axis
//     include both ends, so the shots put tags into the image's corners and
//     along its edges, where distortion is largest: without them the
//     distortion polynomial would be extrapolated there.
// Positions are on a k x k grid in [-1, 1] (both ends included), k =
// ceil(sqrt(n)), and k >= 3 on an axis along which the board spans less than
// a third of the view (then a board at both ends would leave the middle
// third empty; the board gets more than n shots), jittered by up to
// `pointing_jitter` cells and kept in [-1, 1].
// Face-2 shots use the face-2 readings of their own face-1 pointings (the
// same pattern, fresh jitter): the image is turned by 180 degrees, so the
// corners stay covered.
// How far a board narrower than the view may reach towards the image edge
// (fraction of the half view): its outer tags stay inside the image.
constexpr double kEdgeReach = 0.96;
// Board half extent over half view below which a board at both ends of an
// axis leaves the middle third of the image without points (with margin).
constexpr double kMiddleThird = 0.36;

// Refocusing rounds of one photo (SimulatePixels): the corners shown settle
// in two or three; a photo whose edge keeps trading a corner is not taken.
constexpr int kMaxFocusIterations = 8;

void SimulatePixels(const SimulationOptions& o, std::mt19937_64& rng, SimulatedData* data) {
  const InstrumentModel& truth = o.truth;
  const bool focus = truth.effects.Has(Effect::kFocus);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const Eigen::Vector3d origin = RefFromFlange(truth, 0.0, M_PI / 2).translation;
  // SPEC 7.1: every placement's boards (the one placement "" without them);
  // the views of one zoom are chosen over all placements.
  const PlacedScenes scenes = o.Scenes();
  std::map<std::string, std::vector<TargetCorner>> corners_of;
  for (const auto& [name, scene] : scenes) corners_of[name] = scene.AllCorners();
  struct PlacedView {
    std::string placement;
    BoardView view;
  };
  // One photo at (face, zoom, phi, theta) of the boards of `placement`;
  // `aimed` is the point it is aimed at (where the focus starts).
  auto take = [&](int face, int zoom, double phi, double theta, const std::string& placement,
                  const std::string& shot, const Eigen::Vector3d& aimed) {
    const CameraTool& cam = truth.cams.at(zoom);
    const std::vector<TargetCorner>& corners = corners_of.at(placement);
    const Rigid3 ref_from_cam = RefFromCam(truth, zoom, phi, theta);
    const double trusted_radius = MaxTrustedRadius(cam.distortion.data());
    // The corners the photo shows, and their exact pixels, with the
    // camera focused at `distance` (SPEC 4.1; without focus it plays
    // no role).
    auto visible = [&](double distance, std::vector<int>* which,
                       std::vector<Eigen::Vector2d>* uvs) {
      which->clear();
      uvs->clear();
      for (size_t k = 0; k < corners.size(); ++k) {
        const TargetCorner& c = corners[k];
        Eigen::Vector2d uv;
        if (!PredictPixel(truth, zoom, phi, theta, c.X, &uv, distance)) continue;
        // A corner beyond the lens's trusted radius folds back into the
        // image under strong barrel distortion; a real lens never shows it.
        const Eigen::Vector3d x_cam = ref_from_cam.Inverse() * c.X;
        if (std::hypot(x_cam.x(), x_cam.y()) > trusted_radius * x_cam.z()) continue;
        const double margin = 2.0;
        if (uv.x() < margin || uv.y() < margin || uv.x() > cam.width - 1 - margin ||
            uv.y() > cam.height - 1 - margin) {
          continue;
        }
        which->push_back(static_cast<int>(k));
        uvs->push_back(uv);
      }
    };
    std::vector<int> shown;
    std::vector<Eigen::Vector2d> exact;
    double distance = 0;
    if (focus) {
      // The camera focuses on what it shows: D is the distance to the
      // centroid of the corners in the photo, which themselves depend
      // on D through the image scale. Start at the aimed board's
      // centre and repeat until the corners shown no longer change, so
      // that D is exactly the centroid of the photo's own points (what
      // a calibration without a reported D computes).
      distance = (aimed - ref_from_cam.translation).norm();
      std::vector<int> before;
      bool stable = false;
      for (int iteration = 0; iteration < kMaxFocusIterations && !stable; ++iteration) {
        visible(distance, &shown, &exact);
        if (shown.empty()) break;
        stable = iteration > 0 && shown == before;
        if (stable) break;
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (int k : shown) sum += corners[k].X;
        distance = (sum / static_cast<double>(shown.size()) - ref_from_cam.translation).norm();
        before = shown;
      }
      if (!stable) return;  // no photo whose focus settles is taken
    } else {
      visible(0.0, &shown, &exact);
    }
    if (shown.size() < 8) return;  // a shot that shows almost nothing is not taken
    std::vector<PixelObservation> rows;
    for (size_t j = 0; j < shown.size(); ++j) {
      const TargetCorner& c = corners[shown[j]];
      PixelObservation p;
      p.face = face;
      p.zoom = zoom;
      p.phi = phi;
      p.theta = theta;
      p.shot = shot;
      p.placement = placement;
      p.focus_distance = focus && o.shots.report_focus_distance ? distance : 0.0;
      p.target = c.target;
      p.corner = c.corner;
      p.X = c.X;
      p.uv = exact[j] + o.noise.pixel_px * Eigen::Vector2d(normal(rng), normal(rng));
      rows.push_back(p);
    }
    data->obs.pixels.insert(data->obs.pixels.end(), rows.begin(), rows.end());
    data->exact_pixels.insert(data->exact_pixels.end(), exact.begin(), exact.end());
  };
  if (!o.shots.given.empty()) {
    int index = 0;
    for (const PlannedShot& g : o.shots.given) {
      if (!corners_of.count(g.placement)) {
        throw std::invalid_argument("simulation: planned shot at unknown placement '" +
                                    g.placement + "'");
      }
      // Focus starts at the board centre nearest the line of sight.
      const Rigid3 ref_from_cam = RefFromCam(truth, g.zoom, g.phi, g.theta);
      const Eigen::Vector3d axis = ref_from_cam.rotation.col(2);
      Eigen::Vector3d aimed = ref_from_cam.translation + 10.0 * axis;
      double best = -2;
      for (const TagBoard& b : scenes.at(g.placement).boards) {
        const Eigen::Vector3d to = b.CentreInRef() - ref_from_cam.translation;
        const double c = axis.dot(to.normalized());
        if (c > best) {
          best = c;
          aimed = b.CentreInRef();
        }
      }
      const std::string name = g.name.empty() ? "planned" + std::to_string(index) : g.name;
      ++index;
      take(g.face, g.zoom, g.phi, g.theta, g.placement, name, aimed);
    }
    return;
  }
  int shot_index = 0;
  for (int zoom : o.plan.zooms) {
    const CameraTool& cam = truth.cams.at(zoom);
    std::vector<PlacedView> views;
    for (const auto& [name, scene] : scenes) {
      for (size_t b = 0; b < scene.boards.size(); ++b) {
        const BoardView v = ViewOfBoard(scene.boards[b], static_cast<int>(b), origin, cam);
        if (v.Usable()) views.push_back({name, v});
      }
    }
    if (views.empty()) {
      // None fits well: the board closest to filling the view with whole tags.
      double best = -1e300;
      for (const auto& [name, scene] : scenes) {
        for (size_t b = 0; b < scene.boards.size(); ++b) {
          const BoardView v = ViewOfBoard(scene.boards[b], static_cast<int>(b), origin, cam);
          const double score = -std::abs(std::log(std::max(v.TagsAcross(), 1e-9) / 4.0)) -
                               std::abs(std::log(std::max(v.Fill(), 1e-9)));
          if (score > best) {
            best = score;
            views.assign(1, PlacedView{name, v});
          }
        }
      }
    }
    const int n = o.shots.shots_per_board;
    const int cells = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    for (int face : o.plan.faces) {
      for (const PlacedView& placed : views) {
        const BoardView& view = placed.view;
        const TargetScene& scene = scenes.at(placed.placement);
        double phi0, theta0;
        AimAt(origin, scene.boards[view.board].CentreInRef(), &phi0, &theta0);
        // Half range of the aim offsets (angles off the board centre).
        auto half_range = [&](double board, double fov) {
          return board >= fov ? board - o.shots.fill * fov
                              : std::max(0.0, kEdgeReach * fov - board);
        };
        const double range_u = half_range(view.board_u, view.fov_u);
        const double range_v = half_range(view.board_v, view.fov_v);
        // A board narrower than a third of the view, placed only at both
        // ends, leaves the image's middle third empty: one position more.
        auto positions = [&](double board, double fov) {
          return cells >= 2 && board < kMiddleThird * fov ? std::max(cells, 3) : cells;
        };
        const int ku = positions(view.board_u, view.fov_u);
        const int kv = positions(view.board_v, view.fov_v);
        for (int s = 0; s < std::max(n, ku * kv); ++s) {
          // Grid position in [-1, 1], both ends included, jittered and kept
          // inside the range.
          const int iu = s % ku, iv = (s / ku) % kv;
          const double cu = ku == 1 ? 0.0 : -1.0 + 2.0 * iu / (ku - 1);
          const double cv = kv == 1 ? 0.0 : -1.0 + 2.0 * iv / (kv - 1);
          const double ju = std::clamp(cu + o.shots.pointing_jitter * uniform(rng) / ku, -1.0, 1.0);
          const double jv = std::clamp(cv + o.shots.pointing_jitter * uniform(rng) / kv, -1.0, 1.0);
          double phi = phi0 + ju * range_u / std::max(std::sin(theta0), 0.2);
          double theta = theta0 + jv * range_v;
          if (face == 2) OtherFace(phi, theta, &phi, &theta);
          const std::string shot = (placed.placement.empty() ? "" : placed.placement + "-") + "z" +
                                   std::to_string(zoom) + "f" + std::to_string(face) + "s" +
                                   std::to_string(shot_index++);
          take(face, zoom, phi, theta, placed.placement, shot,
               scene.boards[view.board].CentreInRef());
        }
      }
    }
  }
}

}  // namespace

TagBoard FacingBoard(const Eigen::Vector3d& station, int first_id, int rows, int cols, double tag,
                     double distance, double phi, double height, double tilt) {
  TagBoard b;
  b.first_id = first_id;
  b.rows = rows;
  b.cols = cols;
  b.tag_size = tag;
  b.spacing = 0.25 * tag;
  // Board frame (targets.h): x right, y down, z away from the viewer.
  const Eigen::Matrix3d r = Rz(-phi) * Rx(-M_PI / 2) * Ry(tilt);
  const Eigen::Vector3d centre =
      station + Eigen::Vector3d(distance * std::sin(phi), distance * std::cos(phi), height);
  const double w = cols * tag + (cols - 1) * b.spacing, h = rows * tag + (rows - 1) * b.spacing;
  b.ref_from_board = Rigid3{r, centre - r * Eigen::Vector3d(w / 2, h / 2, 0)};
  return b;
}

TargetScene ZoomScene(const InstrumentModel& truth, int rows, int cols, double distance) {
  TargetScene scene;
  const Eigen::Vector3d station = RefFromFlange(truth, 0.0, M_PI / 2).translation;
  for (int z = 0; z < truth.NumZooms(); ++z) {
    const CameraTool& cam = truth.cams[z];
    // Half the view's half width at the board, shared by `cols` tags and
    // their gaps (1.25 tag each).
    const double half_view = distance * 0.5 * cam.width / cam.intrinsics[0];
    const double tag = half_view / (cols * 1.25);
    const double phi = 0.3 + 0.8 * z;
    scene.boards.push_back(
        FacingBoard(station, 1000 * z, rows, cols, tag, distance, phi, -0.2, 0.5));
    scene.boards.push_back(FacingBoard(station, 1000 * z + 500, rows, cols, 1.3 * tag,
                                       1.3 * distance, phi - 0.8, 0.3, -0.6));
  }
  return scene;
}

SimulatedData Simulate(const SimulationOptions& o) {
  const std::string msg = o.Check();
  if (!msg.empty()) throw std::invalid_argument("simulation options: " + msg);
  SimulatedData data;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Record> records = PlanRecords(o.plan, o.truth);
  data.exact_points.reserve(records.size());
  for (Record& r : records) {
    data.exact_points.push_back(r.x);
    if (o.noise.angle_rad > 0 || o.noise.distance_m > 0) {
      // The instrument reads phi, theta but truly points at phi + n, theta + n.
      const double phi = r.phi + o.noise.angle_rad * normal(rng);
      const double theta = r.theta + o.noise.angle_rad * normal(rng);
      if (r.tool == Tool::kEdm) {
        r.x = PredictEdm(o.truth, phi, theta, r.d + o.noise.distance_m * normal(rng));
      } else {
        r.x = PredictCam(o.truth, r.zoom, phi, theta, r.u, r.v, r.d);
      }
    }
    if (o.noise.point_m > 0) {
      r.x += o.noise.point_m * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    }
  }
  data.obs.records = std::move(records);
  data.obs.records_source = "simulated records";
  data.obs.pixels_source = "simulated pixels";
  if (!o.targets.boards.empty() || !o.placements.empty()) {
    SimulatePixels(o, rng, &data);
    // The simulated photos have the simulated cameras' sizes (SPEC 7: sizes
    // come from the images).
    for (int z = 0; z < o.truth.NumZooms(); ++z) {
      data.obs.image_sizes[z] = ImageSize{o.truth.cams[z].width, o.truth.cams[z].height};
    }
  }
  return data;
}

InstrumentModel PerturbedStart(const InstrumentModel& truth, std::uint64_t seed, double scale) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  InstrumentModel m = truth;
  auto move_pose = [&](PoseBlock* p) {
    Rigid3 r = p->ToRigid();
    r.rotation =
        r.rotation * RotationFromEuler<double>({scale * n(rng), scale * n(rng), scale * n(rng)});
    r.translation += scale * Eigen::Vector3d(n(rng), n(rng), n(rng));
    *p = PoseBlock::FromRigid(r);
  };
  move_pose(&m.base);
  if (m.kinematics == Kinematics::kDh) {
    move_pose(&m.edm);
    m.links[0].p[kDhAlpha] += scale * n(rng);
    m.links[0].p[kDhA] += scale * n(rng);
  } else {
    // Spherical: the EDM rotation and t_z are part of the definition (held).
    m.edm.t[0] += scale * n(rng);
    m.edm.t[1] += scale * n(rng);
  }
  for (CameraTool& c : m.cams) {
    move_pose(&c.flange_from_cam);
    c.focus.fill(0.0);  // an effect's values, zeroed like the others
  }
  for (auto& e : m.effect_values) e = {0.0, 0.0};
  m.sigmas = {};
  return m;
}

}  // namespace rtscalib
