#include "libcalib/config/config.h"
#include "libcalib/io/yaml_writer.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <thread>

#include "libcalib/fit/options.h"
#include "libcalib/io/yaml_reader.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"
#include "libcalib/screen/options.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

constexpr double kRadPerDeg = M_PI / 180.0;
constexpr double kRadPerArcsec = M_PI / (180.0 * 3600.0);

template <typename E>
using Names = std::vector<std::pair<std::string, E>>;

// A simulated instrument has a chain; a calibration may also be camera-only
// (SPEC 7.1: model.kinematics none).
const Names<Kinematics> kKinematicsNames = {{"dh", Kinematics::kDh},
                                            {"spherical", Kinematics::kSpherical}};
const Names<Kinematics> kModelKinematicsNames = {
    {"dh", Kinematics::kDh}, {"spherical", Kinematics::kSpherical}, {"none", Kinematics::kNone}};
const Names<FaceMode> kFaceModeNames = {{"joint", FaceMode::kJoint},
                                        {"separate", FaceMode::kSeparate}};
const Names<IntrinsicsMode> kIntrinsicsNames = {{"auto", IntrinsicsMode::kAuto},
                                                {"fit", IntrinsicsMode::kFit},
                                                {"fixed", IntrinsicsMode::kFixed}};
const Names<AngleUnit> kAngleUnitChoices = {{AngleUnitName(AngleUnit::kRad), AngleUnit::kRad},
                                            {AngleUnitName(AngleUnit::kDeg), AngleUnit::kDeg},
                                            {AngleUnitName(AngleUnit::kGon), AngleUnit::kGon}};
const Names<RobustLoss> kLossNames = {
    {"none", RobustLoss::kNone}, {"huber", RobustLoss::kHuber}, {"cauchy", RobustLoss::kCauchy}};
const Names<CovarianceClusters> kClusterNames = {{"shot", CovarianceClusters::kShot},
                                                 {"tag", CovarianceClusters::kTag},
                                                 {"none", CovarianceClusters::kNone}};

template <typename E>
const std::string& NameOf(const Names<E>& names, E value) {
  for (const auto& [name, v] : names) {
    if (v == value) return name;
  }
  static const std::string kUnknown = "?";
  return kUnknown;
}

std::vector<std::string> AllEffectNames() {
  std::vector<std::string> out;
  for (const EffectInfo& info : EffectCatalogue()) out.emplace_back(info.name);
  return out;
}

std::string Resolve(const std::string& dir, const std::string& path) {
  fs::path p(path);
  if (p.is_relative()) p = fs::path(dir) / p;
  return p.lexically_normal().string();
}

// fit.threads may exceed the hardware threads a little (harmless), but not
// without bound: every thread costs memory, and beyond the cores threads
// only wait (100000 needed 2.2 GB).
constexpr int kThreadsPerCore = 4;
unsigned HardwareThreads() { return std::thread::hardware_concurrency(); }

// --- checked reads: each failure points at the key that holds the value ----

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

Eigen::Vector3d ToVector3(const std::vector<double>& v) { return {v[0], v[1], v[2]}; }

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

// --- sections ---------------------------------------------------------------

void ReadData(const YamlNode& m, const std::string& config_dir, RunConfig* out) {
  for (auto [key, path] : {std::pair<const char*, std::string*>{"records", &out->records_path},
                           std::pair<const char*, std::string*>{"pixels", &out->pixels_path},
                           std::pair<const char*, std::string*>{"shots", &out->shots_path},
                           std::pair<const char*, std::string*>{"targets", &out->targets_path}}) {
    if (const std::optional<YamlNode> n = m.Find(key)) {
      const std::string resolved = Resolve(config_dir, n->AsString());
      std::error_code ec;  // e.g. a name too long for the file system: not a file either
      if (!fs::is_regular_file(resolved, ec)) {
        n->Fail("an existing file (relative paths start at the config's folder " + config_dir +
                ")");
      }
      *path = resolved;
    }
  }
  m.ReadEnum("angle_unit", kAngleUnitChoices, &out->angle_unit);
  // Photos need their boards (SPEC 7); boards need what sees them: the
  // photos, or pixels.csv rows whose empty X, Y, Z name their corners (what
  // `rtscalib detect` writes).
  if (!out->shots_path.empty() && out->targets_path.empty()) {
    m.Find("shots")->Fail("data.targets next to data.shots (the photos and the boards they show "
                          "come together)");
  }
  if (!out->targets_path.empty() && out->shots_path.empty() && out->pixels_path.empty()) {
    m.Find("targets")->Fail(
        "data.shots or data.pixels next to data.targets (the boards are seen in photos, or in "
        "pixels.csv rows with empty X, Y, Z)");
  }
}

// The coefficients of one distortion group, by name, each once (an empty
// list holds every coefficient of the group at that zoom).
std::vector<int> ReadCoefficientList(const YamlNode& n, const EffectInfo& group) {
  std::vector<std::string> names;
  for (int index : group.distortion_indices) names.emplace_back(kDistortionCoefficientNames[index]);
  std::vector<int> out;
  for (const YamlNode& item : n.Items()) {
    const std::string name = item.AsString();
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) item.FailChoice(names);
    const int index = group.distortion_indices[it - names.begin()];
    if (std::find(out.begin(), out.end(), index) != out.end()) item.Fail("each coefficient once");
    out.push_back(index);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// model.<group>: {coefficients: [k1, k2], zooms: {2: [k1]}}: which of an
// enabled distortion group's coefficients are fitted (libcalib/fit/options.h).
DistortionChoice ReadDistortionChoice(const YamlNode& n, const EffectInfo& group,
                                      const EffectSet& effects) {
  if (!effects.Has(group.effect)) {
    n.Fail(std::string(group.name) + " in model.effects (the coefficients to fit of an effect " +
           "that is not in the model)");
  }
  DistortionChoice choice;
  choice.group = group.effect;
  choice.coefficients = group.distortion_indices;
  if (const std::optional<YamlNode> list = n.Find("coefficients")) {
    choice.coefficients = ReadCoefficientList(*list, group);
  }
  if (const std::optional<YamlNode> zooms = n.Find("zooms")) {
    for (const YamlNode::Entry& entry : zooms->Entries()) {
      const int zoom = entry.key.AsInt();
      if (zoom < 0) entry.key.Fail("a zoom level >= 0");
      choice.zooms[zoom] = ReadCoefficientList(entry.value, group);
    }
  }
  return choice;
}

void ReadModel(const YamlNode& m, ModelSettings* out) {
  m.ReadEnum("kinematics", kModelKinematicsNames, &out->kinematics);
  if (const std::optional<YamlNode> effects = m.Find("effects")) {
    for (const YamlNode& item : effects->Items()) {
      const std::optional<Effect> e = EffectFromName(item.AsString());
      if (!e) item.FailChoice(AllEffectNames());
      if (out->effects.Has(*e)) item.Fail("each effect once");
      // SPEC 4: in dh these are already in the links and tools; fitting them
      // again would make the problem singular.
      if (out->kinematics == Kinematics::kDh && Info(*e).redundant_in_dh) {
        item.Fail(
            "an effect that the dh kinematics does not already hold (collimation, "
            "tilting_axis, vertical_index and edm_offset are part of its DH links and tools; "
            "use kinematics: spherical to fit them as effects)");
      }
      if (out->kinematics == Kinematics::kNone && IsKinematic(*e)) {
        item.Fail(
            "a camera effect (radial_distortion, tangential_distortion, ...): kinematics none is "
            "a camera-only calibration without axes or EDM");
      }
      out->effects.Add(*e);
    }
  }
  if (const std::optional<YamlNode> cyclic = m.Find("edm_cyclic")) {
    ReadNumber(*cyclic, "unit_length", &out->edm_cyclic_unit_length, IsPositive,
               "a unit length U > 0 [m]");
  }
  for (const EffectInfo& info : EffectCatalogue()) {
    if (info.kind != EffectKind::kDistortion) continue;
    if (const std::optional<YamlNode> n = m.Find(info.name)) {
      out->distortion_choices.push_back(ReadDistortionChoice(*n, info, out->effects));
    }
  }
  m.ReadEnum("faces", kFaceModeNames, &out->faces);
  m.ReadEnum("intrinsics", kIntrinsicsNames, &out->intrinsics);
  if (const std::optional<YamlNode> cameras = m.Find("cameras")) {
    out->cameras.clear();
    for (const YamlNode& item : cameras->Items()) {
      CameraTool cam;
      ReadCameraFields(item, /*required=*/true, &cam);
      out->cameras.push_back(cam);
    }
  }
}

void ReadFit(const YamlNode& m, FitOptions* out) {
  if (const std::optional<YamlNode> s = m.Find("sigmas")) {
    ReadNumber(*s, "edm_m", &out->sigma_edm_m, IsPositive, "a sigma > 0 [m]");
    ReadNumber(*s, "cam_m", &out->sigma_cam_m, IsPositive, "a sigma > 0 [m]");
    ReadNumber(*s, "pixel_px", &out->sigma_pixel_px, IsPositive, "a sigma > 0 [px]");
  }
  m.Read("reestimate_sigmas", &out->reestimate_sigmas);
  if (const std::optional<YamlNode> loss = m.Find("robust_loss")) {
    loss->ReadEnum("type", kLossNames, &out->loss);
    ReadNumber(*loss, "scale", &out->loss_scale, IsPositive, "a scale > 0 [sigmas]");
  }
  if (const std::optional<YamlNode> g = m.Find("gross_errors")) {
    GrossErrorOptions& o = out->gross_errors;
    g->Read("enabled", &o.enabled);
    ReadNumber(*g, "loss_scale", &o.loss_scale, IsPositive, "a Cauchy scale > 0 [sigmas]");
    ReadNumber(
        *g, "reject", &o.reject, [](double x) { return x > 1; }, "a limit > 1 [robust sigmas]");
    ReadNumber(
        *g, "max_fraction", &o.max_fraction, [](double x) { return x > 0 && x < 1; },
        "a fraction of a group's rows in (0, 1)");
  }
  ReadCount(m, "max_iterations", &out->max_iterations, 1, "an iteration limit");
  ReadNumber(m, "translation_bound_m", &out->translation_bound_m, IsPositive,
             "a translation bound > 0 [m]");
  if (const std::optional<YamlNode> region = m.Find("critical_region")) {
    // Only given limits are converted, so that a default is never rewritten
    // by a degree round trip.
    auto in_range = [](double x) { return x >= 0 && x <= 180; };
    const std::string expected = "a zenith angle in [0, 180] [deg]";
    double deg = 0;
    if (ReadNumber(*region, "min_zenith_deg", &deg, in_range, expected)) {
      out->min_zenith_rad = deg * kRadPerDeg;
    }
    if (ReadNumber(*region, "max_zenith_deg", &deg, in_range, expected)) {
      out->max_zenith_rad = deg * kRadPerDeg;
    }
    if (!(out->min_zenith_rad < out->max_zenith_rad)) {
      const std::optional<YamlNode> at = region->Find("max_zenith_deg");
      (at ? *at : *region->Find("min_zenith_deg"))
          .Fail("max_zenith_deg > min_zenith_deg (" +
                FormatShortestDouble(out->min_zenith_rad / kRadPerDeg) + " deg)");
    }
  }
  if (const std::optional<YamlNode> n = m.Find("threads")) {
    const int max_threads = kThreadsPerCore * static_cast<int>(std::max(1u, HardwareThreads()));
    const int x = n->AsInt();
    if (x < 1 || x > max_threads) {
      n->Fail("a thread count 1.." + std::to_string(max_threads) + " (at most " +
              std::to_string(kThreadsPerCore) + " x this machine's " +
              std::to_string(std::max(1u, HardwareThreads())) + " hardware threads)");
    }
    out->num_threads = x;
  }
  m.Read("covariance", &out->compute_covariance);
  m.ReadEnum("covariance_clusters", kClusterNames, &out->covariance_clusters);
  m.Read("verbose", &out->verbose);
}

void ReadNoise(const YamlNode& m, NoiseOptions* out) {
  double angle_arcsec = 0;
  if (ReadNumber(m, "angle_arcsec", &angle_arcsec, IsNonNegative, "a sigma >= 0 [arcsec]")) {
    out->angle_rad = angle_arcsec * kRadPerArcsec;
  }
  ReadNumber(m, "distance_m", &out->distance_m, IsNonNegative, "a sigma >= 0 [m]");
  ReadNumber(m, "point_m", &out->point_m, IsNonNegative, "a sigma >= 0 [m]");
  ReadNumber(m, "pixel_px", &out->pixel_px, IsNonNegative, "a sigma >= 0 [px]");
}

// A non-empty list of distinct integers, each checked by `ok`.
std::vector<int> ReadIndexList(const YamlNode& n, bool (*ok)(int), const std::string& expected) {
  std::vector<int> out;
  for (const YamlNode& item : n.Items()) {
    const int x = item.AsInt();
    if (!ok(x)) item.Fail(expected);
    if (std::find(out.begin(), out.end(), x) != out.end()) item.Fail(expected + ", each once");
    out.push_back(x);
  }
  if (out.empty()) n.Fail("a non-empty list of " + expected);
  return out;
}

void ReadPlan(const YamlNode& m, AcquisitionPlan* out) {
  ReadCount(m, "sweep_points", &out->sweep_points, 2, "points per sweep");
  m.Read("sweeps", &out->sweeps);
  ReadNumbers(m, "edm_distances", &out->edm_distances, IsPositive, "distances > 0 [m]");
  ReadNumber(m, "cam_ray_length", &out->cam_ray_length, IsPositive, "a ray length > 0 [m]");
  ReadNumber(m, "pixel_offset", &out->pixel_offset, IsPositive, "a pixel offset > 0 [px]");
  if (const std::optional<YamlNode> grid = m.Find("grid")) {
    out->grid_phi_steps = 0;
    out->grid_theta_steps = 0;
    grid->Require("phi_steps");
    grid->Require("theta_steps");
    ReadCount(*grid, "phi_steps", &out->grid_phi_steps, 1, "grid steps in phi");
    ReadCount(*grid, "theta_steps", &out->grid_theta_steps, 1, "grid steps in theta");
    ReadNumbers(*grid, "edm_distances", &out->grid_edm_distances, IsPositive, "distances > 0 [m]");
    ReadNumbers(*grid, "cam_ray_lengths", &out->grid_cam_ray_lengths, IsPositive,
                "ray lengths > 0 [m]");
    ReadCount(*grid, "pixels_per_axis", &out->grid_pixels_per_axis, 1, "pixels per image axis");
  }
  if (const std::optional<YamlNode> faces = m.Find("faces")) {
    out->faces = ReadIndexList(
        *faces, [](int f) { return f == 1 || f == 2; }, "faces 1 or 2");
  }
  if (const std::optional<YamlNode> zooms = m.Find("zooms")) {
    out->zooms = ReadIndexList(
        *zooms, [](int z) { return z >= 0; }, "zoom levels >= 0");
  }
  // The plan's size bounds (records, zoom levels) before anything is
  // allocated for it (the simulated truth has one camera per zoom level).
  const std::string problem = out->CheckSize();
  if (!problem.empty()) m.Fail("a plan within the simulation's bounds: " + problem);
}

TagBoard ReadBoard(const YamlNode& m) {
  TagBoard b;
  if (const std::optional<YamlNode> n = m.Find("family")) {
    b.family = n->AsString();
    if (b.family.empty()) n->Fail("an AprilTag family name such as tag36h11");
  }
  ReadCount(m, "first_id", &b.first_id, 0, "the first tag id");
  ReadCount(m, "rows", &b.rows, 1, "tag rows");
  ReadCount(m, "cols", &b.cols, 1, "tag columns");
  ReadNumber(m, "tag_size", &b.tag_size, IsPositive, "a tag size > 0 [m]");
  ReadNumber(m, "spacing", &b.spacing, IsNonNegative, "a spacing >= 0 [m]");
  // A board at the instrument's origin is never meant: the placement is required.
  m.Require("t");
  ReadPoseFields(m, &b.ref_from_board);
  // The board_warp of the simulated board (TagBoard::warp): [wx, wy] [m].
  if (const std::optional<YamlNode> warp = m.Find("warp")) {
    const std::vector<double> w = warp->AsDoubles(2);
    b.warp = {w[0], w[1]};
  }
  return b;
}

void ReadShots(const YamlNode& m, ShotPlan* out) {
  ReadCount(m, "shots_per_board", &out->shots_per_board, 1, "shots per board");
  ReadNumber(
      m, "fill", &out->fill, [](double x) { return x > 0 && x <= 1; },
      "a fraction of the image in (0, 1]");
  ReadNumber(m, "pointing_jitter", &out->pointing_jitter, IsNonNegative,
             "a fraction of the field of view >= 0");
  m.Read("report_focus_distance", &out->report_focus_distance);
}

// The truth instrument: starts from the ideal model of its kinematics (with
// the configured cameras' intrinsics), then every given key overrides.
InstrumentModel ReadTruth(const YamlNode& m, const ModelSettings& model, int plan_zooms) {
  Kinematics kinematics = model.kinematics;
  m.ReadEnum("kinematics", kKinematicsNames, &kinematics);
  const std::optional<YamlNode> cameras = m.Find("cameras");
  const std::vector<YamlNode> camera_nodes = cameras ? cameras->Items() : std::vector<YamlNode>{};
  if (cameras && camera_nodes.empty()) cameras->Fail("a non-empty list of cameras (one per zoom)");
  const int num_zooms = cameras ? static_cast<int>(camera_nodes.size()) : plan_zooms;

  InstrumentModel truth = IdealModel(kinematics, num_zooms, CameraTool{});
  truth.edm_cyclic_unit_length = model.edm_cyclic_unit_length;
  for (int z = 0; z < num_zooms && z < static_cast<int>(model.cameras.size()); ++z) {
    const PoseBlock ideal_pose = truth.cams[z].flange_from_cam;
    truth.cams[z] = model.cameras[z];
    truth.cams[z].flange_from_cam = ideal_pose;
  }
  for (int z = 0; z < static_cast<int>(camera_nodes.size()); ++z) {
    ReadPoseFields(camera_nodes[z], &truth.cams[z].flange_from_cam);
    ReadCameraFields(camera_nodes[z], /*required=*/false, &truth.cams[z]);
  }
  if (const std::optional<YamlNode> n = m.Find("base")) ReadPoseFields(*n, &truth.base);
  if (const std::optional<YamlNode> n = m.Find("edm")) ReadPoseFields(*n, &truth.edm);
  if (const std::optional<YamlNode> n = m.Find("links")) {
    if (kinematics != Kinematics::kDh) n->Fail("no DH links in the spherical kinematics");
    const std::vector<YamlNode> links = n->Items();
    if (links.size() != 2) n->Fail("2 links [[d, gamma_offset, alpha, a], [...]]");
    for (int i = 0; i < 2; ++i) {
      const std::vector<double> p = links[i].AsDoubles(4);
      std::copy(p.begin(), p.end(), truth.links[i].p.begin());
    }
  }
  ReadNumber(m, "edm_cyclic_unit_length", &truth.edm_cyclic_unit_length, IsPositive,
             "a unit length U > 0 [m]");
  if (const std::optional<YamlNode> effects = m.Find("effects")) {
    for (const YamlNode::Entry& entry : effects->Entries()) {
      const std::optional<Effect> e = EffectFromName(entry.key.AsString());
      if (!e) entry.key.FailChoice(AllEffectNames());
      const EffectInfo& info = Info(*e);
      if (!IsKinematic(*e)) {
        entry.key.Fail(
            "a kinematic or EDM effect (distortion coefficients go in "
            "simulate.truth.cameras[zoom].distortion, focus in simulate.truth.cameras[zoom].focus, "
            "a board's warp in simulate.targets[i].warp)");
      }
      if (kinematics == Kinematics::kDh && info.redundant_in_dh) {
        entry.key.Fail(
            "an effect that the dh kinematics does not already hold (put it into "
            "the links and tools, or use kinematics: spherical)");
      }
      std::string expected = std::to_string(info.num_params) + " value(s) in report units [";
      for (int i = 0; i < info.num_params; ++i) {
        expected +=
            std::string(i ? ", " : "") + info.param_names[i] + " (" + info.report_units[i] + ")";
      }
      expected += "]";
      const std::vector<double> report = entry.value.IsScalar()
                                             ? std::vector<double>{entry.value.AsDouble()}
                                             : entry.value.AsDoubles();
      if (static_cast<int>(report.size()) != info.num_params) entry.value.Fail(expected);
      truth.effects.Add(*e);
      truth.EffectValue(*e) = FromReportUnits(*e, {report[0], info.num_params > 1 ? report[1] : 0});
    }
  }
  // Distortion groups are switched on by their coefficients, so that the
  // truth's effect list says what the simulated data contain.
  for (const EffectInfo& info : EffectCatalogue()) {
    for (const CameraTool& cam : truth.cams) {
      for (int index : info.distortion_indices) {
        if (cam.distortion[index] != 0) truth.effects.Add(info.effect);
      }
    }
  }
  // Likewise focus (SPEC 4.1): the simulated camera refocuses per photo.
  for (const CameraTool& cam : truth.cams) {
    for (double f : cam.focus) {
      if (f != 0) truth.effects.Add(Effect::kFocus);
    }
  }
  return truth;
}

void ReadSimulate(const YamlNode& m, const ModelSettings& model, SimulationOptions* out,
                  bool* truth_from_paper) {
  if (const std::optional<YamlNode> n = m.Find("seed")) out->seed = n->AsUint64();
  if (const std::optional<YamlNode> n = m.Find("noise")) ReadNoise(*n, &out->noise);
  const std::optional<YamlNode> plan = m.Find("plan");
  if (plan) ReadPlan(*plan, &out->plan);
  if (const std::optional<YamlNode> n = m.Find("targets")) {
    for (const YamlNode& item : n->Items()) out->targets.boards.push_back(ReadBoard(item));
  }
  // SPEC 7.1: boards moved between sets of shots, one scene per placement.
  if (const std::optional<YamlNode> n = m.Find("placements")) {
    if (out->targets.boards.size() > 0) {
      n->Fail("either simulate.targets or simulate.placements (each placement lists its boards)");
    }
    for (const YamlNode& item : n->Items()) {
      const YamlNode name = item.Require("name");
      TargetScene scene;
      for (const YamlNode& board : item.Require("targets").Items()) {
        scene.boards.push_back(ReadBoard(board));
      }
      if (scene.boards.empty()) item.Require("targets").Fail("at least one board");
      if (!out->placements.emplace(name.AsString(), scene).second) {
        name.Fail("a placement name not used before");
      }
    }
  }
  if (const std::optional<YamlNode> n = m.Find("shots")) ReadShots(*n, &out->shots);
  const int plan_zooms = PlanNumZooms(out->plan);
  const std::optional<YamlNode> truth = m.Find("truth");
  *truth_from_paper = !truth;
  if (!truth) return;
  out->truth = ReadTruth(*truth, model, plan_zooms);
  if (out->truth.NumZooms() < plan_zooms) {
    const std::string expected = "zoom levels < " + std::to_string(out->truth.NumZooms()) +
                                 " (simulate.truth.cameras has one camera per zoom)";
    if (plan) plan->Require("zooms").Fail(expected);
    m.Fail(expected);
  }
}

void ReadScreen(const YamlNode& m, ScreenOptions* out) {
  ReadNumber(m, "pixel_margin_px", &out->pixel_margin_px, IsNonNegative,
             "a margin >= 0 [px] beyond the image");
  ReadNumber(m, "max_extent_m", &out->max_extent_m, IsPositive,
             "a distance > 0 [m] from the origin");
  ReadCount(m, "max_missing_zooms", &out->max_missing_zooms, 0, "a count of zoom levels");
  if (const std::optional<YamlNode> g = m.Find("gross_errors")) {
    GrossScreenOptions& o = out->gross_errors;
    g->Read("enabled", &o.enabled);
    ReadNumber(*g, "sphere_threshold", &o.sphere_threshold, IsPositive,
               "a threshold > 0 [robust sigmas]");
    ReadNumber(*g, "sphere_floor_m", &o.sphere_floor_m, IsNonNegative, "a distance >= 0 [m]");
  }
  const std::string problem = out->Check();
  if (!problem.empty()) m.Fail(problem);
}

void ReadDiagnose(const YamlNode& m, DiagnoseOptions* out) {
  m.Read("enabled", &out->enabled);
  m.Read("auto", &out->auto_add);
  ReadNumber(
      m, "significance", &out->significance, [](double x) { return x > 0 && x < 1; },
      "a test level in (0, 1)");
}

// --- dump ---------------------------------------------------------------------

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

void EmitTruth(YAML::Emitter& e, const InstrumentModel& truth) {
  e << YAML::BeginMap;
  e << YAML::Key << "kinematics" << YAML::Value << KinematicsName(truth.kinematics);
  e << YAML::Key << "base" << YAML::Value << YAML::Flow << YAML::BeginMap;
  EmitPose(e, truth.base);
  e << YAML::EndMap;
  if (truth.kinematics == Kinematics::kDh) {
    e << YAML::Key << "links" << YAML::Value << YAML::BeginSeq;
    for (const DhLink& link : truth.links)
      EmitNumbers(e, link.p.data(), link.p.size(), /*shortest=*/true);
    e << YAML::EndSeq;
  }
  e << YAML::Key << "edm" << YAML::Value << YAML::Flow << YAML::BeginMap;
  EmitPose(e, truth.edm);
  e << YAML::EndMap;
  e << YAML::Key << "cameras" << YAML::Value << YAML::BeginSeq;
  for (const CameraTool& cam : truth.cams) {
    e << YAML::Flow << YAML::BeginMap;
    EmitPose(e, cam.flange_from_cam);
    EmitCameraFields(e, cam);
    e << YAML::EndMap;
  }
  e << YAML::EndSeq;
  e << YAML::Key << "effects" << YAML::Value << YAML::BeginMap;
  for (Effect effect : truth.effects.List()) {
    if (!IsKinematic(effect)) continue;  // distortion lives in the cameras
    const EffectReportValue report = ToReportUnits(effect, truth.EffectValue(effect), {});
    e << YAML::Key << Info(effect).name << YAML::Value;
    EmitNumbers(e, report.value.data(), report.num, /*shortest=*/true);
  }
  e << YAML::EndMap;
  e << YAML::Key << "edm_cyclic_unit_length" << YAML::Value << Num(truth.edm_cyclic_unit_length);
  e << YAML::EndMap;
}

void EmitSimulate(YAML::Emitter& e, const SimulationOptions& sim, bool truth_from_paper) {
  e << YAML::BeginMap;
  e << YAML::Key << "seed" << YAML::Value << sim.seed;
  if (!truth_from_paper) {
    e << YAML::Key << "truth" << YAML::Value;
    EmitTruth(e, sim.truth);
  }
  e << YAML::Key << "noise" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "angle_arcsec" << YAML::Value
    << ExactScaled(sim.noise.angle_rad, kRadPerArcsec);
  e << YAML::Key << "distance_m" << YAML::Value << Num(sim.noise.distance_m);
  e << YAML::Key << "point_m" << YAML::Value << Num(sim.noise.point_m);
  e << YAML::Key << "pixel_px" << YAML::Value << Num(sim.noise.pixel_px);
  e << YAML::EndMap;
  const AcquisitionPlan& p = sim.plan;
  e << YAML::Key << "plan" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "sweeps" << YAML::Value << p.sweeps;
  e << YAML::Key << "sweep_points" << YAML::Value << p.sweep_points;
  e << YAML::Key << "edm_distances" << YAML::Value;
  EmitList(e, p.edm_distances);
  e << YAML::Key << "cam_ray_length" << YAML::Value << Num(p.cam_ray_length);
  e << YAML::Key << "pixel_offset" << YAML::Value << Num(p.pixel_offset);
  if (p.grid_phi_steps > 0 && p.grid_theta_steps > 0) {
    e << YAML::Key << "grid" << YAML::Value << YAML::Flow << YAML::BeginMap;
    e << YAML::Key << "phi_steps" << YAML::Value << p.grid_phi_steps;
    e << YAML::Key << "theta_steps" << YAML::Value << p.grid_theta_steps;
    e << YAML::Key << "edm_distances" << YAML::Value;
    EmitList(e, p.grid_edm_distances);
    e << YAML::Key << "cam_ray_lengths" << YAML::Value;
    EmitList(e, p.grid_cam_ray_lengths);
    e << YAML::Key << "pixels_per_axis" << YAML::Value << p.grid_pixels_per_axis;
    e << YAML::EndMap;
  }
  e << YAML::Key << "faces" << YAML::Value;
  EmitInts(e, p.faces);
  e << YAML::Key << "zooms" << YAML::Value;
  EmitInts(e, p.zooms);
  e << YAML::EndMap;
  auto emit_boards = [&e](const TargetScene& scene) {
    e << YAML::BeginSeq;
    for (const TagBoard& b : scene.boards) {
      e << YAML::Flow << YAML::BeginMap;
      e << YAML::Key << "family" << YAML::Value << b.family;
      e << YAML::Key << "first_id" << YAML::Value << b.first_id;
      e << YAML::Key << "rows" << YAML::Value << b.rows;
      e << YAML::Key << "cols" << YAML::Value << b.cols;
      e << YAML::Key << "tag_size" << YAML::Value << Num(b.tag_size);
      e << YAML::Key << "spacing" << YAML::Value << Num(b.spacing);
      EmitPose(e, PoseBlock::FromRigid(b.ref_from_board));
      if (b.warp[0] != 0 || b.warp[1] != 0) {
        e << YAML::Key << "warp" << YAML::Value;
        EmitNumbers(e, b.warp.data(), 2, /*shortest=*/true);
      }
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  };
  if (sim.placements.empty()) {
    e << YAML::Key << "targets" << YAML::Value;
    emit_boards(sim.targets);
  } else {
    e << YAML::Key << "placements" << YAML::Value << YAML::BeginSeq;
    for (const auto& [name, scene] : sim.placements) {
      e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << name;
      e << YAML::Key << "targets" << YAML::Value;
      emit_boards(scene);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  e << YAML::Key << "shots" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "shots_per_board" << YAML::Value << sim.shots.shots_per_board;
  e << YAML::Key << "fill" << YAML::Value << Num(sim.shots.fill);
  e << YAML::Key << "pointing_jitter" << YAML::Value << Num(sim.shots.pointing_jitter);
  e << YAML::Key << "report_focus_distance" << YAML::Value << sim.shots.report_focus_distance;
  e << YAML::EndMap;
  e << YAML::EndMap;
}

}  // namespace

const char* FaceModeName(FaceMode m) { return NameOf(kFaceModeNames, m).c_str(); }
const char* IntrinsicsModeName(IntrinsicsMode m) { return NameOf(kIntrinsicsNames, m).c_str(); }

RunConfig LoadConfig(const std::string& path, const std::vector<ConfigSection>& sections) {
  // A run's settings take a few kB; 4 MiB leaves room for long simulated
  // target lists and bounds what a runaway file costs to parse (~200 MB).
  const YamlDocument doc = YamlDocument::Load(path, std::uintmax_t{4} << 20, "a config");
  const YamlNode root = doc.Root();
  RunConfig config;
  const fs::path absolute = fs::absolute(path).lexically_normal();
  config.config_path = absolute.string();
  config.config_dir = absolute.parent_path().string();
  CalibrationOptions& options = config.calibration;

  if (const std::optional<YamlNode> n = root.Find("data")) ReadData(*n, config.config_dir, &config);
  if (const std::optional<YamlNode> n = root.Find("model")) ReadModel(*n, &options.model);
  if (const std::optional<YamlNode> n = root.Find("fit")) {
    ReadFit(*n, &options.fit);
    ReadNumber(
        *n, "max_sigma0", &options.checks.max_sigma0, [](double x) { return x > 1; },
        "a factor > 1 (a-posteriori over a-priori sigma beyond which a fit fails)");
  }
  options.fit.fit_intrinsics = options.model.intrinsics == IntrinsicsMode::kFit;
  const std::optional<YamlNode> simulate = root.Find("simulate");
  if (simulate) {
    config.simulate.emplace();
    ReadSimulate(*simulate, options.model, &*config.simulate, &config.truth_from_paper);
  }
  for (const ConfigSection& section : sections) {
    if (const std::optional<YamlNode> n = root.Find(section.key)) section.read(*n);
  }
  if (const std::optional<YamlNode> n = root.Find("diagnose")) ReadDiagnose(*n, &options.diagnose);
  if (const std::optional<YamlNode> n = root.Find("detect")) {
    ReadCount(*n, "jobs", &config.detect_jobs, 1, "detection threads");
  }
  if (const std::optional<YamlNode> n = root.Find("screen")) ReadScreen(*n, &options.screen);
  if (const std::optional<YamlNode> report = root.Find("report")) {
    if (const std::optional<YamlNode> n = report->Find("uncertainty_map")) {
      UncertaintyMapOptions& u = config.uncertainty_map;
      ReadNumber(
          *n, "range_m", &u.range_m, [](double x) { return x > 0; }, "a range > 0 [m]");
      if (const std::optional<YamlNode> cells = n->Find("cells")) {
        const std::vector<double> c = cells->AsDoubles(2);
        if (!(c[0] >= 1 && c[0] <= 1000 && c[1] >= 1 && c[1] <= 1000) || c[0] != std::floor(c[0]) ||
            c[1] != std::floor(c[1])) {
          cells->Fail("[columns, rows], integers 1..1000");
        }
        u.cols = static_cast<int>(c[0]);
        u.rows = static_cast<int>(c[1]);
      }
      ReadNumber(
          *n, "phi", &u.phi, [](double x) { return std::isfinite(x); }, "an angle [rad]");
      ReadNumber(
          *n, "theta", &u.theta, [](double x) { return x > 0 && x < 2 * M_PI; },
          "a zenith angle in (0, 2 pi) [rad]");
    }
  }
  std::string output = "out";
  root.Read("output", &output);
  // An empty name would resolve to the config's own folder, whose files
  // (the config itself, the user's data) the run's outputs would join.
  if (const std::optional<YamlNode> n = root.Find("output"); n && output.empty()) {
    n->Fail("a folder name (relative to the config's folder), not empty");
  }
  config.output_dir = Resolve(config.config_dir, output);

  doc.CheckAllKeysUsed();

  const bool have_data =
      !config.records_path.empty() || !config.pixels_path.empty() || !config.shots_path.empty();
  if (!have_data && !simulate) {
    throw InputError::Key(path, "data", 0, 0,
                          "data.records, data.pixels and/or data.shots, or a simulate section",
                          "neither");
  }
  if (have_data && simulate) {
    config.notes.push_back(path +
                           ": the simulate section is not used because data files are given");
  }
  return config;
}

std::string DumpConfig(const RunConfig& c, const std::vector<ConfigSection>& sections) {
  const CalibrationOptions& options = c.calibration;
  YAML::Emitter e;
  e << YAML::BeginMap;
  if (!c.records_path.empty() || !c.pixels_path.empty() || !c.shots_path.empty()) {
    e << YAML::Key << "data" << YAML::Value << YAML::BeginMap;
    for (auto [key, path] :
         {std::pair<const char*, const std::string*>{"records", &c.records_path},
          std::pair<const char*, const std::string*>{"pixels", &c.pixels_path},
          std::pair<const char*, const std::string*>{"shots", &c.shots_path},
          std::pair<const char*, const std::string*>{"targets", &c.targets_path}}) {
      if (path->empty()) continue;
      e << YAML::Key << key << YAML::Value;
      EmitYamlText(e, *path);
    }
    e << YAML::Key << "angle_unit" << YAML::Value << NameOf(kAngleUnitChoices, c.angle_unit);
    e << YAML::EndMap;
  }

  const ModelSettings& m = options.model;
  e << YAML::Key << "model" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "kinematics" << YAML::Value << KinematicsName(m.kinematics);
  e << YAML::Key << "effects" << YAML::Value << YAML::Flow << m.effects.Names();
  e << YAML::Key << "edm_cyclic" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
    << "unit_length" << YAML::Value << Num(m.edm_cyclic_unit_length) << YAML::EndMap;
  for (const DistortionChoice& choice : m.distortion_choices) {
    auto names = [](const std::vector<int>& indices) {
      std::vector<std::string> out;
      for (int i : indices) out.emplace_back(kDistortionCoefficientNames[i]);
      return out;
    };
    e << YAML::Key << Info(choice.group).name << YAML::Value << YAML::Flow << YAML::BeginMap;
    e << YAML::Key << "coefficients" << YAML::Value << YAML::Flow << names(choice.coefficients);
    if (!choice.zooms.empty()) {
      e << YAML::Key << "zooms" << YAML::Value << YAML::Flow << YAML::BeginMap;
      for (const auto& [zoom, list] : choice.zooms) {
        e << YAML::Key << zoom << YAML::Value << YAML::Flow << names(list);
      }
      e << YAML::EndMap;
    }
    e << YAML::EndMap;
  }
  e << YAML::Key << "faces" << YAML::Value << FaceModeName(m.faces);
  e << YAML::Key << "intrinsics" << YAML::Value << IntrinsicsModeName(m.intrinsics);
  if (!m.cameras.empty()) {
    e << YAML::Key << "cameras" << YAML::Value << YAML::BeginSeq;
    for (const CameraTool& cam : m.cameras) {
      e << YAML::Flow << YAML::BeginMap;
      EmitCameraFields(e, cam);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  e << YAML::EndMap;

  const FitOptions& f = options.fit;
  e << YAML::Key << "fit" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "sigmas" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "edm_m" << YAML::Value << Num(f.sigma_edm_m);
  e << YAML::Key << "cam_m" << YAML::Value << Num(f.sigma_cam_m);
  e << YAML::Key << "pixel_px" << YAML::Value << Num(f.sigma_pixel_px);
  e << YAML::EndMap;
  e << YAML::Key << "reestimate_sigmas" << YAML::Value << f.reestimate_sigmas;
  e << YAML::Key << "robust_loss" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "type" << YAML::Value << NameOf(kLossNames, f.loss);
  e << YAML::Key << "scale" << YAML::Value << Num(f.loss_scale);
  e << YAML::EndMap;
  e << YAML::Key << "gross_errors" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "enabled" << YAML::Value << f.gross_errors.enabled;
  e << YAML::Key << "loss_scale" << YAML::Value << Num(f.gross_errors.loss_scale);
  e << YAML::Key << "reject" << YAML::Value << Num(f.gross_errors.reject);
  e << YAML::Key << "max_fraction" << YAML::Value << Num(f.gross_errors.max_fraction);
  e << YAML::EndMap;
  e << YAML::Key << "max_iterations" << YAML::Value << f.max_iterations;
  e << YAML::Key << "translation_bound_m" << YAML::Value << Num(f.translation_bound_m);
  e << YAML::Key << "max_sigma0" << YAML::Value << Num(options.checks.max_sigma0);
  e << YAML::Key << "critical_region" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "min_zenith_deg" << YAML::Value << ExactScaled(f.min_zenith_rad, kRadPerDeg);
  e << YAML::Key << "max_zenith_deg" << YAML::Value << ExactScaled(f.max_zenith_rad, kRadPerDeg);
  e << YAML::EndMap;
  e << YAML::Key << "threads" << YAML::Value << f.num_threads;
  e << YAML::Key << "covariance" << YAML::Value << f.compute_covariance;
  e << YAML::Key << "covariance_clusters" << YAML::Value
    << NameOf(kClusterNames, f.covariance_clusters);
  e << YAML::Key << "verbose" << YAML::Value << f.verbose;
  e << YAML::EndMap;

  if (c.simulate) {
    e << YAML::Key << "simulate" << YAML::Value;
    EmitSimulate(e, *c.simulate, c.truth_from_paper);
  }
  for (const ConfigSection& section : sections) {
    const YAML::Node node = section.dump();
    if (!node.IsNull()) e << YAML::Key << section.key << YAML::Value << node;
  }
  if (c.detect_jobs != 1) {
    e << YAML::Key << "detect" << YAML::Value << YAML::Flow << YAML::BeginMap;
    e << YAML::Key << "jobs" << YAML::Value << c.detect_jobs;
    e << YAML::EndMap;
  }
  e << YAML::Key << "diagnose" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "enabled" << YAML::Value << options.diagnose.enabled;
  e << YAML::Key << "auto" << YAML::Value << options.diagnose.auto_add;
  e << YAML::Key << "significance" << YAML::Value << Num(options.diagnose.significance);
  e << YAML::EndMap;
  e << YAML::Key << "screen" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "pixel_margin_px" << YAML::Value << Num(options.screen.pixel_margin_px);
  e << YAML::Key << "max_extent_m" << YAML::Value << Num(options.screen.max_extent_m);
  e << YAML::Key << "max_missing_zooms" << YAML::Value << options.screen.max_missing_zooms;
  e << YAML::Key << "gross_errors" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "enabled" << YAML::Value << options.screen.gross_errors.enabled;
  e << YAML::Key << "sphere_threshold" << YAML::Value
    << Num(options.screen.gross_errors.sphere_threshold);
  e << YAML::Key << "sphere_floor_m" << YAML::Value
    << Num(options.screen.gross_errors.sphere_floor_m);
  e << YAML::EndMap;
  e << YAML::EndMap;
  e << YAML::Key << "report" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "uncertainty_map" << YAML::Value << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "range_m" << YAML::Value << Num(c.uncertainty_map.range_m);
  e << YAML::Key << "cells" << YAML::Value << YAML::Flow << YAML::BeginSeq << c.uncertainty_map.cols
    << c.uncertainty_map.rows << YAML::EndSeq;
  e << YAML::Key << "phi" << YAML::Value << Num(c.uncertainty_map.phi);
  e << YAML::Key << "theta" << YAML::Value << Num(c.uncertainty_map.theta);
  e << YAML::EndMap;
  e << YAML::EndMap;
  e << YAML::Key << "output" << YAML::Value;
  EmitYamlText(e, c.output_dir);
  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

}  // namespace rtscalib
