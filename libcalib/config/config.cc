#include "libcalib/config/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <thread>

#include "libcalib/config/fields.h"
#include "libcalib/config/simulate_section.h"
#include "libcalib/fit/options.h"
#include "libcalib/io/yaml_reader.h"
#include "libcalib/io/yaml_writer.h"
#include "libcalib/model/effects.h"
#include "libcalib/model/instrument.h"
#include "libcalib/screen/options.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {
namespace {

namespace fs = std::filesystem;

// A calibration may also be camera-only (SPEC 7.1: model.kinematics none).
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
    CriticalRegion& limits = out->critical_region;
    double deg = 0;
    if (ReadNumber(*region, "min_zenith_deg", &deg, in_range, expected)) {
      limits.min_zenith_rad = deg * kRadPerDeg;
    }
    if (ReadNumber(*region, "max_zenith_deg", &deg, in_range, expected)) {
      limits.max_zenith_rad = deg * kRadPerDeg;
    }
    // Each limit is in range by now: what CriticalRegion::Check (the rule
    // the fit applies) still refuses is their order, said in the config's
    // degrees at the key.
    if (!limits.Check().empty()) {
      const std::optional<YamlNode> at = region->Find("max_zenith_deg");
      (at ? *at : *region->Find("min_zenith_deg"))
          .Fail("max_zenith_deg > min_zenith_deg (" +
                FormatShortestDouble(limits.min_zenith_rad / kRadPerDeg) + " deg)");
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
  const std::optional<YamlNode> simulate = root.Find("simulate");
  if (simulate) {
    config.simulate.emplace();
    ReadSimulateSection(*simulate, options.model, &*config.simulate, &config.truth_from_paper);
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
  const CriticalRegion& region = f.critical_region;
  e << YAML::Key << "min_zenith_deg" << YAML::Value
    << ExactScaled(region.min_zenith_rad, kRadPerDeg);
  e << YAML::Key << "max_zenith_deg" << YAML::Value
    << ExactScaled(region.max_zenith_rad, kRadPerDeg);
  e << YAML::EndMap;
  e << YAML::Key << "threads" << YAML::Value << f.num_threads;
  e << YAML::Key << "covariance" << YAML::Value << f.compute_covariance;
  e << YAML::Key << "covariance_clusters" << YAML::Value
    << NameOf(kClusterNames, f.covariance_clusters);
  e << YAML::Key << "verbose" << YAML::Value << f.verbose;
  e << YAML::EndMap;

  if (c.simulate) {
    e << YAML::Key << "simulate" << YAML::Value;
    EmitSimulateSection(e, *c.simulate, c.truth_from_paper);
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
