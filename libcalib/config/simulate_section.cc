#include "libcalib/config/simulate_section.h"

#include <algorithm>
#include <string>
#include <vector>

#include "libcalib/config/fields.h"
#include "libcalib/io/yaml_writer.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"

namespace rtscalib {
namespace {

// A simulated instrument has a chain (model.kinematics may also be none).
const Names<Kinematics> kKinematicsNames = {{"dh", Kinematics::kDh},
                                            {"spherical", Kinematics::kSpherical}};

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

}  // namespace

void ReadSimulateSection(const YamlNode& m, const ModelSettings& model, SimulationOptions* out,
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

namespace {

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

}  // namespace

void EmitSimulateSection(YAML::Emitter& e, const SimulationOptions& sim, bool truth_from_paper) {
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

}  // namespace rtscalib
