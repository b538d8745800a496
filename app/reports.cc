#include "app/reports.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include "app/diagnosis_report.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

using nlohmann::json;

constexpr double kArcsec = 180.0 * 3600.0 / M_PI;

// `determined` false: the start value, no sigmas (docs/conventions.md section 6).
json PoseJson(const PoseBlock& p, const PoseSigma* s, bool determined = true) {
  const Eigen::Vector3d e = p.Euler();
  json j = {{"euler", {e[0], e[1], e[2]}},
            {"t", {p.t[0], p.t[1], p.t[2]}},
            {"q", {p.q[0], p.q[1], p.q[2], p.q[3]}},
            {"determined", determined}};
  if (s && determined) {
    j["euler_sigma"] = {s->euler[0], s->euler[1], s->euler[2]};
    j["t_sigma"] = {s->t[0], s->t[1], s->t[2]};
  }
  return j;
}

json LinksJson(const InstrumentModel& m) {
  json links = json::array();
  if (m.kinematics != Kinematics::kDh) return links;
  for (int i = 0; i < 2; ++i) {
    json l = {{"d", m.links[i].p[kDhD]},
              {"gamma_offset", m.links[i].p[kDhGamma]},
              {"alpha", m.links[i].p[kDhAlpha]},
              {"a", m.links[i].p[kDhA]}};
    if (m.sigmas.valid) l["sigma"] = m.sigmas.links[i];
    links.push_back(l);
  }
  return links;
}

json ModelJson(const InstrumentModel& m) {
  const bool s = m.sigmas.valid;
  const bool chain = m.kinematics != Kinematics::kNone;
  json j = {{"kinematics", KinematicsName(m.kinematics)}, {"effects", m.effects.Names()}};
  // A camera-only model (SPEC 7.1) estimated no chain: nothing of it is
  // written as if it had been.
  if (chain) {
    j["base"] = PoseJson(m.base, s ? &m.sigmas.base : nullptr);
    j["links"] = LinksJson(m);
    j["edm"] = PoseJson(m.edm, s ? &m.sigmas.edm : nullptr, m.edm_determined);
  }
  json cams = json::array();
  for (int z = 0; z < m.NumZooms(); ++z) {
    const CameraTool& c = m.cams[z];
    json cj = {{"zoom", z},
               {"intrinsics", c.intrinsics},
               {"distortion", c.distortion},
               {"determined", c.determined}};
    if (chain) {
      cj["tool"] = PoseJson(
          c.flange_from_cam,
          s && z < (int)m.sigmas.cam_tools.size() ? &m.sigmas.cam_tools[z] : nullptr,
          c.determined);
    }
    if (s && c.determined && z < (int)m.sigmas.intrinsics.size())
      cj["intrinsics_sigma"] = m.sigmas.intrinsics[z];
    // Coefficients of enabled groups held by model.<group>.coefficients:
    // not estimated (model.yaml writes their sigma as `held`).
    json held = json::array();
    for (int i = 0; i < kNumDistortion; ++i) {
      if (m.effects.Has(DistortionGroupOf(i)) && c.distortion_held[i])
        held.push_back(kDistortionCoefficientNames[i]);
    }
    cj["distortion_held"] = held;
    cams.push_back(cj);
  }
  j["cameras"] = cams;
  json eff = json::object();
  for (Effect e : m.effects.List()) {
    if (!IsKinematic(e)) continue;
    const EffectInfo& info = Info(e);
    const EffectReportValue v =
        ToReportUnits(e, m.EffectValue(e), m.sigmas.effect_cov[static_cast<int>(e)]);
    json ej = json::object();
    for (int k = 0; k < v.num; ++k) {
      ej[info.param_names[k]] = {
          {"value", v.value[k]}, {"sigma", v.sigma[k]}, {"unit", info.report_units[k]}};
    }
    eff[info.name] = ej;
  }
  if (m.effects.Has(Effect::kBoardWarp)) {
    // One warp per board of estimated pose, by its first tag id.
    const EffectInfo& info = Info(Effect::kBoardWarp);
    const double scale = ReportScale(Effect::kBoardWarp);
    json wj = json::object();
    for (const BoardWarp& w : m.board_warps) {
      json bj = json::object();
      for (int k = 0; k < kNumBoardWarp; ++k) {
        bj[info.param_names[k]] = {{"value", w.w[k] * scale},
                                   {"sigma", std::sqrt(std::max(w.cov[3 * k], 0.0)) * scale},
                                   {"unit", info.report_units[k]}};
      }
      wj[std::to_string(w.first_id)] = bj;
    }
    eff[info.name] = wj;
  }
  j["effect_values"] = eff;
  // SPEC 7 / 7.1: the estimated board poses, one per board and placement
  // (camera-only: and zoom, in that zoom's camera frame).
  json boards = json::array();
  for (const EstimatedBoard& b : m.boards) {
    json bj = {{"board", b.board.first_id},
               {"name", b.Name()},
               {"frame", chain ? "ref_from_board" : "cam_from_board"},
               {"pose", PoseJson(b.pose, s ? &b.sigma : nullptr)}};
    if (!b.placement.empty()) bj["placement"] = b.placement;
    if (b.zoom >= 0) bj["zoom"] = b.zoom;
    boards.push_back(bj);
  }
  j["boards"] = boards;
  return j;
}

}  // namespace

std::string BoardsText(const InstrumentModel& m) {
  if (m.boards.empty()) return "";
  const bool chain = m.kinematics != Kinematics::kNone;
  std::ostringstream o;
  o << "Boards of unknown pose, one pose per board and placement ("
    << (chain ? "ref_from_board" : "cam_from_board, each zoom's camera frame")
    << "; t [m], Euler a, b, g [deg], +- 1 sigma)\n";
  for (const EstimatedBoard& b : m.boards) {
    const Eigen::Vector3d e = b.pose.Euler() * 180.0 / M_PI;
    char row[320];
    if (m.sigmas.valid) {
      std::snprintf(row, sizeof row,
                    "  %-32s t %+.4f %+.4f %+.4f (+- %.1e %.1e %.1e)  euler %+.3f %+.3f %+.3f "
                    "(+- %.1e %.1e %.1e)\n",
                    b.Name().c_str(), b.pose.t[0], b.pose.t[1], b.pose.t[2], b.sigma.t[0],
                    b.sigma.t[1], b.sigma.t[2], e[0], e[1], e[2], b.sigma.euler[0] * 180 / M_PI,
                    b.sigma.euler[1] * 180 / M_PI, b.sigma.euler[2] * 180 / M_PI);
    } else {
      std::snprintf(row, sizeof row, "  %-32s t %+.4f %+.4f %+.4f  euler %+.3f %+.3f %+.3f\n",
                    b.Name().c_str(), b.pose.t[0], b.pose.t[1], b.pose.t[2], e[0], e[1], e[2]);
    }
    o << row;
  }
  o << "\n";
  return o.str();
}

namespace {

json ErrorsJson(const ModelErrors& e) {
  return {
      {"edm", StatsJson(e.edm)}, {"cam", StatsJson(e.cam)}, {"compound", StatsJson(e.compound)}};
}

json FitJson(const FitSummary& f) {
  json corr = json::array();
  for (const auto& [name, rho] : f.strong_correlations)
    corr.push_back({{"pair", name}, {"rho", rho}});
  return {{"converged", f.converged},
          {"iterations", f.iterations},
          {"initial_cost", f.initial_cost},
          {"final_cost", f.final_cost},
          {"seconds", f.seconds},
          {"residuals", f.num_residuals},
          {"parameters", f.num_parameters},
          {"excluded_critical_region", f.excluded_critical},
          {"sigma_edm_m", f.sigma_edm_m},
          {"sigma_cam_m", f.sigma_cam_m},
          {"sigma_pixel_px", f.sigma_pixel_px},
          {"sigma_pixel_px_per_zoom", f.sigma_pixel_px_zoom},
          {"sigma_rounds", f.sigma_rounds},
          {"sigmas_converged", f.sigmas_converged},
          {"covariance_clusters", f.covariance_clusters},
          {"fixed_gauges", f.fixed_gauges},
          {"strong_correlations", corr},
          {"downweighted", f.downweighted},
          {"message", f.message}};
}

}  // namespace

json StatsJson(const ErrorStats& s) {
  return {
      {"mean_m", s.mean_m}, {"std_m", s.std_m}, {"rms_m", s.rms_m}, {"max_m", s.max_m}, {"n", s.n}};
}

namespace {

namespace fs = std::filesystem;

// A complete run's report.json, or throws. `keep_history`: with its
// "history" (the runs before it, as HistoryJson listed them); else only
// "model" and "final".
json ReadRunReport(const HistoryEntry& h, bool keep_history) {
  std::ifstream in(h.dir + "/report.json", std::ios::binary);
  if (!in) throw std::runtime_error("no report.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return json::parse(text, [keep_history](int depth, json::parse_event_t event, const json& parsed) {
    return depth != 1 || event != json::parse_event_t::key || parsed == "model" ||
           parsed == "final" || (keep_history && parsed == "history");
  });
}

}  // namespace

json HistoryJson(const OutputFolder& out) {
  const std::vector<HistoryEntry>& earlier = out.earlier();
  // The numbers of complete runs as the latest complete run's report.json
  // lists them: each report.json holds the history of the runs before it,
  // so reading every run's report would read the square of the folder's
  // runs (a folder of 150 runs: 12 MB of JSON for each new run). A run
  // that list does not hold (or holds as not complete), or whose report.json
  // is gone, is read itself.
  std::map<std::string, json> listed;
  for (auto h = earlier.rbegin(); h != earlier.rend(); ++h) {
    if (h->state != RunState::kComplete) continue;
    try {
      const json r = ReadRunReport(*h, true);
      json& own = listed[h->name];
      if (r.contains("model")) own["kinematics"] = r["model"].value("kinematics", "");
      if (r.contains("model")) own["effects"] = r["model"].value("effects", json::array());
      if (r.contains("final")) own["final"] = r["final"];
      for (const json& e : r.value("history", json::array())) {
        if (e.is_object() && e.value("status", "") == RunStateName(RunState::kComplete) &&
            e.contains("run") && e["run"].is_string()) {
          listed[e["run"].get<std::string>()] = e;
        }
      }
    } catch (const std::exception&) {
      // Read run by run below.
    }
    break;
  }
  json runs = json::array();
  for (const HistoryEntry& h : earlier) {
    json entry = {{"run", h.name}, {"status", RunStateName(h.state)}};
    if (!h.reason.empty()) entry["reason"] = h.reason;
    // Only a complete run's numbers are results; a killed or failed run's
    // report.json (if any) may be from a later stage than its model.
    if (h.state != RunState::kComplete) {
      runs.push_back(entry);
      continue;
    }
    const auto it = listed.find(h.name);
    std::error_code ec;
    if (it != listed.end() && fs::exists(h.dir + "/report.json", ec)) {
      for (const char* key : {"kinematics", "effects", "final"}) {
        if (it->second.contains(key)) entry[key] = it->second[key];
      }
      runs.push_back(entry);
      continue;
    }
    json r;
    try {
      r = ReadRunReport(h, false);
    } catch (const std::exception&) {
      entry["status"] = RunStateName(RunState::kIncomplete);
      entry["reason"] = "report.json missing or unreadable";
      runs.push_back(entry);
      continue;
    }
    if (r.contains("model")) entry["kinematics"] = r["model"].value("kinematics", "");
    if (r.contains("model")) entry["effects"] = r["model"].value("effects", json::array());
    if (r.contains("final")) entry["final"] = r["final"];
    runs.push_back(entry);
  }
  return runs;
}

std::string HistoryText(const json& history) {
  if (!history.is_array() || history.empty()) return "";
  std::ostringstream o;
  o << "\nEarlier runs in this output folder (history/), oldest first\n";
  for (const json& h : history) {
    o << "  " << h.value("run", std::string("?"));
    const std::string status = h.value("status", std::string("complete"));
    if (status != "complete") {
      o << "  " << status;
      if (h.contains("reason")) o << " (" << h.value("reason", std::string()) << ")";
      o << ": not a result\n";
      continue;
    }
    o << "  " << h.value("kinematics", std::string("?")) << ", effects: [";
    std::string sep;
    for (const json& e : h.value("effects", json::array())) {
      o << sep << e.get<std::string>();
      sep = ", ";
    }
    o << "]";
    const json final = h.value("final", json::object());
    for (const char* tool : {"edm", "cam"}) {
      if (final.contains("records") && final["records"].contains(tool) &&
          final["records"][tool].value("n", 0) > 0) {
        o << "  " << tool << " rms "
          << Fmt("%.3f", final["records"][tool].value("rms_m", 0.0) * 1e3) << " mm";
      }
    }
    if (final.contains("pixels") && final["pixels"].value("n", 0) > 0) {
      o << "  pixels rms " << Fmt("%.3f", final["pixels"].value("rms_px", 0.0)) << " px";
    }
    o << "\n";
  }
  return o.str();
}

json ReportJson(const RunConfig& config, const PipelineResult& r, const OutputFolder& out,
                const json& history) {
  json j;
  j["rtscalib"] = {{"version", "0.1.0"}, {"config", config.config_path}, {"run", out.run().name}};
  j["data"] = {{"records", r.obs.records.size()},
               {"pixels", r.obs.pixels.size()},
               {"records_source", r.obs.records_source},
               {"pixels_source", r.obs.pixels_source},
               {"angle_unit", AngleUnitName(r.obs.angle_unit)},
               {"simulated", r.simulated},
               {"excluded_critical_region", r.calibration.fit.excluded_critical}};
  if (r.calibration.extraction) {
    const ExtractionResult& e = *r.calibration.extraction;
    json joints = json::array();
    for (const JointFeature& f : e.joints) {
      joints.push_back({{"joint", f.joint},
                        {"trajectory", TrajectoryName(f.trajectory)},
                        {"points", f.num_points},
                        {"center", {f.center.x(), f.center.y(), f.center.z()}},
                        {"axis", {f.axis.x(), f.axis.y(), f.axis.z()}},
                        {"radius_m", f.radius},
                        {"circle_rms_m", f.circle_rms},
                        {"plane_rms_m", f.plane_rms}});
    }
    j["extraction"] = {{"model", ModelJson(e.model)},
                       {"joints", joints},
                       {"excluded_face2", e.excluded.face2},
                       {"excluded_critical_region", e.excluded.critical_zenith},
                       {"notes", e.notes}};
  }
  if (r.calibration.simplified) {
    j["simplification"] = {{"model", ModelJson(*r.calibration.simplified)},
                           {"closed_form", r.calibration.closed_form}};
  }
  if (r.calibration.table4) {
    j["table4"] = {{"A",
                    {{"dh", ErrorsJson(r.calibration.table4->dh_a)},
                     {"simplified", ErrorsJson(r.calibration.table4->simplified_a)}}},
                   {"B",
                    {{"dh", ErrorsJson(r.calibration.table4->dh_b)},
                     {"simplified", ErrorsJson(r.calibration.table4->simplified_b)}}}};
  }
  j["table5"] = {
      {"reduced", ErrorsJson(r.calibration.table5.reduced)},
      {"cross", r.calibration.table5.has_cross ? ErrorsJson(r.calibration.table5.cross) : json()},
      {"full", ErrorsJson(r.calibration.table5.full)},
      {"reduced_rows", r.calibration.table5.reduced_rows},
      {"full_rows", r.calibration.table5.full_rows},
      {"scalarised_objective_full", ScalarisedObjective(r.calibration.table5.full.compound)}};
  j["model"] = ModelJson(r.calibration.model);
  j["fit"] = FitJson(r.calibration.fit);
  j["fit"]["intrinsics_fitted"] = r.calibration.intrinsics_fitted;
  // The reduced set's own refinement (Klug Sec. 4.3), where it ran apart.
  if (r.calibration.table5.has_cross) j["reduced_fit"] = FitJson(r.calibration.reduced.fit);
  if (r.calibration.faces) {
    const FaceComparison& f = *r.calibration.faces;
    j["faces"] = {{"valid", f.valid},
                  {"note", f.note},
                  {"collimation_arcsec", f.collimation * kArcsec},
                  {"tilting_axis_arcsec", f.tilting_axis * kArcsec},
                  {"vertical_index_arcsec", f.vertical_index * kArcsec},
                  {"face1", ModelJson(f.face1)},
                  {"face2", ModelJson(f.face2)}};
  }
  j["final"] = {{"records",
                 {{"edm", StatsJson(r.calibration.final_errors.edm)},
                  {"cam", StatsJson(r.calibration.final_errors.cam)}}},
                {"pixels",
                 {{"rms_px", r.calibration.final_errors.pixels.rms_px},
                  {"n", r.calibration.final_errors.pixels.n}}}};
  j["diagnosis"] = DiagnosisJson(r.calibration);
  if (r.render.ran) {
    j["rendering"] = {{"shots", r.render.shots},
                      {"tags_expected", r.render.expected_tags},
                      {"tags_found", r.render.found_tags},
                      {"skipped_border", r.render.skipped_border},
                      {"skipped_grazing", r.render.skipped_grazing},
                      {"skipped_small", r.render.skipped_small},
                      {"detection_rms_px", r.render.detection_rms_px},
                      {"render_seconds", r.render.render_seconds},
                      {"detect_seconds", r.render.detect_seconds},
                      {"images", r.render.image_dir}};
  }
  if (r.photos.ran) {
    const PhotoSessionSummary& p = r.photos;
    json photos = json::array();
    for (const PhotoSessionSummary::Photo& ph : p.photos) {
      photos.push_back({{"line", ph.line},
                        {"shot", ph.shot},
                        {"image", ph.image},
                        {"face", ph.face},
                        {"zoom", ph.zoom},
                        {"width", ph.width},
                        {"height", ph.height},
                        {"tags", ph.tags},
                        {"tags_of_boards", ph.tags_of_boards},
                        {"shift_rms_px", ph.shift_rms_px}});
    }
    j["photos"] = {{"shots", p.shots_path},
                   {"targets", p.targets_path},
                   {"boards_with_pose", p.boards_with_pose},
                   {"boards_without_pose", p.boards_without_pose},
                   {"photos", static_cast<int>(p.photos.size())},
                   {"photos_without_tags", p.photos_without_tags},
                   {"tags", p.tags},
                   {"apriltags", p.apriltags},
                   {"point_corners", p.point_corners},
                   {"from_neighbours", p.from_neighbours},
                   {"corners", p.corners},
                   {"dropped",
                    {{"unrefined", p.unrefined},
                     {"not_on_boards", p.not_on_boards},
                     {"duplicates", p.duplicates}}},
                   {"detection_check",
                    {{"refined_vs_apriltag_rms_px", p.shift_rms_px},
                     {"refined_vs_apriltag_max_px", p.shift_max_px}}},
                   {"seconds", p.seconds},
                   {"images_per_second", p.images_per_second},
                   {"jobs", p.jobs},
                   {"per_photo", photos},
                   {"warnings", p.warnings}};
  }
  {
    json sizes = json::object();
    for (const auto& [z, source] : r.calibration.size_source) {
      const CameraTool& c = r.calibration.model.cams.at(z);
      sizes[std::to_string(z)] = {{"width", c.width}, {"height", c.height}, {"source", source}};
    }
    j["image_sizes"] = sizes;
    const Coverage& cov = r.calibration.coverage;
    json zooms = json::array();
    for (const ImageCoverage& c : cov.images) {
      zooms.push_back({{"zoom", c.zoom},
                       {"points", c.points},
                       {"cells", kCoverageCells},
                       {"counts", c.counts},
                       {"covered_fraction", c.covered_fraction},
                       {"corner_fraction", cov.corner_fraction[c.zoom]},
                       {"corners_covered", c.corners_covered}});
    }
    j["coverage"] = {{"zooms", zooms}, {"warnings", r.calibration.coverage_warnings}};
  }
  json gross = json::array();
  for (const ExcludedRow& e : r.calibration.gross_rows) {
    gross.push_back({{"file", e.pixel ? r.obs.pixels_source : r.obs.records_source},
                     {"line", e.line},
                     {"reason", e.reason}});
  }
  j["gross_errors"] = gross;
  if (!r.uncertainty_maps.empty()) {
    // Projection uncertainty per zoom (docs/output.md); null where no value.
    auto num = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
    const UncertaintyMapOptions& o = r.uncertainty_options;
    json zooms = json::array();
    for (const UncertaintyMap& m : r.uncertainty_maps) {
      json z = {
          {"zoom", m.zoom}, {"determined", m.determined}, {"up_to_rotation", m.up_to_rotation}};
      if (m.determined) {
        // Summary keys without a value (no cell inside a valid region, as
        // for records-only data) are left out, never null.
        auto put = [&](const char* key, double x) {
          if (std::isfinite(x)) z[key] = x;
        };
        put("min_px", m.min_px);
        put("median_px", m.median_px);
        put("max_px", m.max_px);
        put("inside_median_px", m.inside_median_px);
        put("inside_max_px", m.inside_max_px);
        z["cells_outside_valid_region"] = m.cells_outside;
        json sigma = json::array();
        for (double x : m.sigma_px) sigma.push_back(num(x));
        z["sigma_px"] = sigma;
        z["inside"] = std::vector<int>(m.inside.begin(), m.inside.end());
      }
      zooms.push_back(z);
    }
    j["uncertainty"] = {{"range_m", o.range_m},
                        {"phi", o.phi},
                        {"theta", o.theta},
                        {"cells", {o.cols, o.rows}},
                        {"full_covariance", r.full_covariance},
                        {"zooms", zooms}};
  }
  j["residuals"] = ResidualsJson(r);
  j["notes"] = r.notes;
  j["history"] = history;
  return j;
}

// ---------------------------------------------------------------------------
const std::vector<std::string>& ResidualColumns() {
  static const std::vector<std::string> columns = {"kind",
                                                   "index",
                                                   "line",
                                                   "status",
                                                   "face",
                                                   "zoom",
                                                   "phi",
                                                   "theta",
                                                   "d",
                                                   "shot",
                                                   "placement",
                                                   "target",
                                                   "corner",
                                                   "point",
                                                   "obs_x",
                                                   "obs_y",
                                                   "obs_z",
                                                   "pred_x",
                                                   "pred_y",
                                                   "pred_z",
                                                   "res_x",
                                                   "res_y",
                                                   "res_z",
                                                   "size",
                                                   "sigma",
                                                   "normalised",
                                                   "along_m",
                                                   "hz_rad",
                                                   "zenith_rad",
                                                   "target_distance_m",
                                                   "image_radius_px",
                                                   "u",
                                                   "v",
                                                   "image_du",
                                                   "image_dv",
                                                   "reason"};
  return columns;
}

std::string ResidualsCsv(const PipelineResult& r) {
  // Some 27,000 rows of 30 fields for a photo session: appended to one
  // string, the numbers by std::to_chars (AppendSignificant, printf's %.*g
  // to the character), rather than through a stream and snprintf.
  std::string o =
      "# rtscalib residual table: every observation at the final model (docs/output.md)\n";
  for (size_t i = 0; i < ResidualColumns().size(); ++i) {
    if (i) o += ',';
    o += ResidualColumns()[i];
  }
  o += '\n';
  // ",x" with x to `digits` significant digits, or "," alone for a value
  // that is not there (not finite, or not `shown`).
  auto num = [&o](double x, int digits, bool shown = true) {
    o += ',';
    if (shown && std::isfinite(x)) AppendSignificant(&o, x, digits);
  };
  auto integer = [&o](long long i, bool shown = true) {
    o += ',';
    if (shown) o += std::to_string(i);
  };
  // Text fields: quoted when they hold a comma or a quote (RFC 4180).
  auto text = [&o](const std::string& t) {
    o += ',';
    if (t.find_first_of(",\"\n") == std::string::npos) {
      o += t;
      return;
    }
    o += '"';
    for (char c : t) o += c == '"' ? std::string("\"\"") : std::string(1, c);
    o += '"';
  };
  o.reserve(o.size() + 300 * r.calibration.residuals.size());
  for (const ObservationResidual& x : r.calibration.residuals) {
    const bool px = x.group == ObsGroup::kPixel;
    o += px ? "pixel" : x.group == ObsGroup::kEdm ? "edm" : "cam";
    integer(x.index);
    integer(x.line);
    o += ',';
    o += ResidualStatusName(x.status);
    integer(x.face);
    integer(x.zoom);
    num(x.phi, 10);
    num(x.theta, 10);
    num(x.d, 10, !px);
    text(x.shot);
    text(x.placement);
    integer(x.target, px);
    integer(x.corner, px);
    text(x.point);
    const int k = px ? 2 : 3;
    for (const Eigen::Vector3d* v : {&x.observed, &x.predicted}) {
      for (int i = 0; i < 3; ++i) num((*v)[i], 10, x.valid && i < k);
    }
    for (int i = 0; i < 3; ++i) num(x.delta[i], 6, x.valid && i < k);
    num(x.size, 6, x.valid);
    num(x.sigma, 6);
    num(x.normalised, 6, x.valid);
    num(x.along, 6, x.valid && !px);
    num(x.hz, 6, x.valid);
    num(x.zenith, 6, x.valid);
    num(x.target_distance, 8, x.valid);
    num(x.image_radius, 8, x.image_radius >= 0);
    const bool image = px || x.group == ObsGroup::kCam;
    num(x.u, 10, image);
    num(x.v, 10, image);
    num(x.image_delta.x(), 6);
    num(x.image_delta.y(), 6);
    text(x.reason);
    o += '\n';
  }
  return o;
}

json ResidualsJson(const PipelineResult& r) {
  json status = json::object();
  for (ResidualStatus s : {ResidualStatus::kFitted, ResidualStatus::kCriticalRegion,
                           ResidualStatus::kGrossError, ResidualStatus::kNotPredicted}) {
    status[ResidualStatusName(s)] = 0;
  }
  double ss[3] = {0, 0, 0};
  int n[3] = {0, 0, 0};
  std::map<int, std::pair<double, int>> zooms;
  for (const ObservationResidual& x : r.calibration.residuals) {
    status[ResidualStatusName(x.status)] = status[ResidualStatusName(x.status)].get<int>() + 1;
    if (x.status != ResidualStatus::kFitted) continue;
    const int g = static_cast<int>(x.group);
    ss[g] += x.size * x.size;
    ++n[g];
    if (x.group == ObsGroup::kPixel) {
      zooms[x.zoom].first += x.size * x.size;
      ++zooms[x.zoom].second;
    }
  }
  auto rms = [](double s, int k) { return k ? std::sqrt(s / k) : 0.0; };
  json per_zoom = json::array();
  for (const auto& [z, v] : zooms)
    per_zoom.push_back({{"zoom", z}, {"n", v.second}, {"rms_px", rms(v.first, v.second)}});
  return {{"file", "residuals.csv"},
          {"rows", r.calibration.residuals.size()},
          {"columns", ResidualColumns()},
          {"status", status},
          {"fitted",
           {{"edm", {{"n", n[0]}, {"rms_m", rms(ss[0], n[0])}}},
            {"cam", {{"n", n[1]}, {"rms_m", rms(ss[1], n[1])}}},
            {"pixels", {{"n", n[2]}, {"rms_px", rms(ss[2], n[2])}, {"zooms", per_zoom}}}}}};
}

json FiguresJson(const std::vector<Figure>& figures,
                 const std::vector<std::vector<std::string>>& files, const std::string& note) {
  json list = json::array();
  for (size_t i = 0; i < figures.size(); ++i) {
    const Figure& f = figures[i];
    json files_j = json::array();
    for (const std::string& name : files[i]) files_j.push_back("figures/" + name);
    list.push_back({{"name", f.name},
                    {"section", f.section},
                    {"title", f.title},
                    {"files", files_j},
                    {"summary", f.summary}});
  }
  json j = {{"library", "vega 5 (Debian libjs-vega)"}, {"list", list}};
  if (!note.empty()) j["note"] = note;
  return j;
}

// ---------------------------------------------------------------------------
std::string GrossRowsText(const PipelineResult& r) {
  const std::vector<ExcludedRow>& rows = r.calibration.gross_rows;
  if (rows.empty()) return "";
  std::ostringstream o;
  o << "Gross errors: " << rows.size()
    << " rows taken out before the fit (docs/refinement.md, \"Gross errors\"):\n";
  constexpr size_t kListed = 50;
  for (size_t i = 0; i < rows.size() && i < kListed; ++i) {
    const ExcludedRow& e = rows[i];
    o << "  " << (e.pixel ? r.obs.pixels_source : r.obs.records_source) << ":" << e.line << ": "
      << e.reason << "\n";
  }
  if (rows.size() > kListed) {
    o << "  ... and " << rows.size() - kListed << " more (report.json lists every row)\n";
  }
  return o.str();
}

// ---------------------------------------------------------------------------
std::string PlanHint(const RunConfig& config, const PipelineResult& r) {
  // The photos that fill the gaps: the planner's, toward the worst
  // projection sigma the points' hull has now, over the whole image.
  double inside_max = 0;
  for (const UncertaintyMap& m : r.uncertainty_maps) {
    if (std::isfinite(m.inside_max_px)) inside_max = std::max(inside_max, m.inside_max_px);
  }
  if (r.calibration.coverage_warnings.empty() || !(inside_max > 0)) return "";
  return "The photos to add (where to hold the board, or where to point): rtscalib plan --from " +
         config.output_dir + " --projection-px " + Fmt("%.2g", inside_max) +
         " (the worst projection sigma inside the points' hull now, over the whole image; "
         "docs/plan.md)";
}

std::string ReportText(const RunConfig& config, const PipelineResult& r) {
  std::ostringstream o;
  auto stats = [](const ErrorStats& s) {
    return s.n == 0 ? std::string("        -          ")
                    : Fmt("%.2e", s.mean_m) + " +- " + Fmt("%.2e", s.std_m);
  };
  auto dh_table = [&](const InstrumentModel& m, const char* title) {
    o << title << "\n  joint   alpha_i        a_i [m]        gamma_i                  d_i [m]\n";
    const char* var[2] = {"phi", "theta"};
    for (int i = 0; i < 2; ++i) {
      const auto& p = m.links[i].p;
      o << "  " << i + 1 << "       " << Fmt("%+.6f", p[kDhAlpha]) << "     "
        << Fmt("%+.4e", p[kDhA]) << "    " << var[i] << " " << (p[kDhGamma] < 0 ? "- " : "+ ")
        << Fmt("%.6f", std::abs(p[kDhGamma])) << "      " << Fmt("%+.4e", p[kDhD]) << "\n";
    }
  };
  auto pose_row = [&](const char* name, const PoseBlock& p, bool determined = true) {
    const Eigen::Vector3d e = p.Euler();
    o << "  " << std::left << std::setw(12) << name << std::right;
    for (int i = 0; i < 3; ++i) o << Fmt("%+.4f", e[i]) << "  ";
    for (int i = 0; i < 3; ++i) o << Fmt("%+.4e", p.t[i]) << "  ";
    if (!determined) o << "(not determined by the data: start value)";
    o << "\n";
  };
  auto transforms = [&](const InstrumentModel& m, const char* title) {
    o << title << "\n  transform   alpha    beta     gamma    t_x [m]      t_y [m]      t_z [m]\n";
    pose_row("M_B", m.base);
    for (int z = 0; z < m.NumZooms(); ++z)
      pose_row(("M_T(CAM" + std::to_string(z) + ")").c_str(), m.cams[z].flange_from_cam,
               m.cams[z].determined);
    pose_row("M_T(EDM)", m.edm, m.edm_determined);
  };

  o << "rtscalib report\n===============\nconfig: " << config.config_path << "\n";
  o << "data: " << r.obs.records.size() << " records (" << r.obs.records_source << "), "
    << r.obs.pixels.size() << " pixel observations" << (r.simulated ? " [simulated]" : "") << "\n";
  // The readings' unit as the files gave it; every angle below is in radians
  // (or the unit its column names), converted when the files were read.
  o << "readings (phi, theta) given in: " << AngleUnitName(r.obs.angle_unit)
    << (r.obs.angle_unit == AngleUnit::kRad ? "" : " (data.angle_unit)")
    << "; angles below in radians unless a unit is named\n\n";
  if (r.calibration.extraction) {
    dh_table(r.calibration.extraction->model, "Table 1 - extracted DH parameters (Klug Sec. 3)");
    o << "\n";
    transforms(r.calibration.extraction->model,
               "Table 2 - extracted base and tool transforms (Euler a, b, g: Eq. 83)");
    o << "\n";
  }
  if (!r.calibration.closed_form.empty())
    o << "Simplified model (Sec. 4.1):\n" << r.calibration.closed_form << "\n\n";
  if (r.calibration.table4) {
    o << "Table 4 - error of the extracted (DH) and the simplified model [m], mean +- std (Eq. "
         "92/93)\n";
    o << "  method  tool        e_DH                    e_simplified\n";
    const ModelErrors* rows[4] = {&r.calibration.table4->dh_a, &r.calibration.table4->simplified_a,
                                  &r.calibration.table4->dh_b, &r.calibration.table4->simplified_b};
    for (int m = 0; m < 2; ++m) {
      const ModelErrors& dh = *rows[2 * m];
      const ModelErrors& si = *rows[2 * m + 1];
      const char* method = m == 0 ? "(A)" : "(B)";
      o << "  " << method << "     EDM       " << stats(dh.edm) << "   " << stats(si.edm) << "\n";
      o << "          camera    " << stats(dh.cam) << "   " << stats(si.cam) << "\n";
      o << "          compound  " << stats(dh.compound) << "   " << stats(si.compound) << "\n";
    }
    o << "\n";
  }
  const bool camera_only = r.calibration.model.kinematics == Kinematics::kNone;
  if (!r.obs.records.empty()) {
    o << "Table 5 - refined model, method B [m]\n  tool        e_optimized             "
         "e_optimized,cross       e_optimized,full\n";
    const Table5& t = r.calibration.table5;
    auto row5 = [&](const char* name, const ErrorStats& a, const ErrorStats& b,
                    const ErrorStats& c) {
      o << "  " << std::left << std::setw(10) << name << std::right << stats(a) << "   "
        << (t.has_cross ? stats(b) : std::string("       n/a         ")) << "   " << stats(c)
        << "\n";
    };
    row5("EDM", t.reduced.edm, t.cross.edm, t.full.edm);
    row5("camera", t.reduced.cam, t.cross.cam, t.full.cam);
    row5("compound", t.reduced.compound, t.cross.compound, t.full.compound);
    o << "  (reduced set: " << t.reduced_rows << " records; full set: " << t.full_rows
      << " records)\n\n";
  }
  if (r.calibration.model.kinematics == Kinematics::kDh) {
    dh_table(r.calibration.model, "Table 6 - refined DH parameters");
    o << "\n";
  }
  if (camera_only) {
    o << "Camera-only calibration (kinematics none): no kinematic chain, base or camera tool "
         "was estimated\n\n";
  } else {
    transforms(r.calibration.model, "Table 7 - refined base and tool transforms");
    o << "\n";
  }
  if (r.calibration.model.sigmas.valid) {
    o << "Intrinsics per zoom (fx, fy, cx, cy [px] +- sigma)\n";
    for (int z = 0; z < r.calibration.model.NumZooms(); ++z) {
      const auto& k = r.calibration.model.cams[z].intrinsics;
      const auto& s = r.calibration.model.sigmas.intrinsics[z];
      o << "  zoom " << z << ":";
      if (!r.calibration.model.cams[z].determined) {
        for (int i = 0; i < 4; ++i) o << "  " << Fmt("%.3f", k[i]);
        o << "  (not determined by the data: start value)\n";
        continue;
      }
      for (int i = 0; i < 4; ++i) o << "  " << Fmt("%.3f", k[i]) << " +- " << Fmt("%.3f", s[i]);
      o << "\n";
    }
    o << "\n";
  }
  if (!r.calibration.model.effects.Empty()) {
    o << "Effects (report units)\n";
    for (Effect e : r.calibration.model.effects.List()) {
      if (e == Effect::kFocus) {
        // SPEC 4.1, per zoom in report units.
        const InstrumentModel& m = r.calibration.model;
        for (int z = 0; z < m.NumZooms(); ++z) {
          o << "  focus zoom " << z << ":";
          for (int i = 0; i < kNumFocus; ++i) {
            const double sigma = z < static_cast<int>(m.sigmas.focus.size())
                                     ? m.sigmas.focus[z][i] * kFocusReportScale[i]
                                     : 0.0;
            o << "  " << kFocusParamNames[i] << " = "
              << Fmt("%.4g", m.cams[z].focus[i] * kFocusReportScale[i]) << " +- "
              << Fmt("%.2g", sigma) << " " << kFocusReportUnits[i];
          }
          o << "\n";
        }
        continue;
      }
      if (IsBoardEffect(e)) {
        // One warp per board of estimated pose, in mm.
        const double scale = ReportScale(e);
        for (const BoardWarp& w : r.calibration.model.board_warps) {
          o << "  " << Info(e).name << " board " << w.first_id;
          for (int k = 0; k < kNumBoardWarp; ++k) {
            o << "  " << Info(e).param_names[k] << " = " << Fmt("%.4g", w.w[k] * scale)
              << " +- " << Fmt("%.2g", std::sqrt(std::max(w.cov[3 * k], 0.0)) * scale) << " "
              << Info(e).report_units[k];
          }
          o << "\n";
        }
        continue;
      }
      if (!IsKinematic(e)) {
        o << "  " << Info(e).name << " (per zoom, see model.yaml)\n";
        continue;
      }
      const EffectReportValue v =
          ToReportUnits(e, r.calibration.model.EffectValue(e),
                        r.calibration.model.sigmas.effect_cov[static_cast<int>(e)]);
      o << "  " << std::left << std::setw(16) << Info(e).name << std::right;
      for (int k = 0; k < v.num; ++k) {
        o << "  " << Info(e).param_names[k] << " = " << Fmt("%.4g", v.value[k]) << " +- "
          << Fmt("%.2g", v.sigma[k]) << " " << Info(e).report_units[k];
      }
      o << "\n";
    }
    o << "\n";
  }
  o << BoardsText(r.calibration.model);
  if (r.calibration.faces && r.calibration.faces->valid) {
    o << "Two-face check (one model per face)\n  collimation "
      << Fmt("%.2f", r.calibration.faces->collimation * kArcsec) << "\"  tilting axis "
      << Fmt("%.2f", r.calibration.faces->tilting_axis * kArcsec) << "\"  vertical index "
      << Fmt("%.2f", r.calibration.faces->vertical_index * kArcsec) << "\"\n\n";
  }
  const FinalErrors& f = r.calibration.final_errors;
  if (r.render.ran) {
    o << "Synthetic shots: " << r.render.shots << " rendered, " << r.render.found_tags << " of "
      << r.render.expected_tags << " visible tags detected (skipped: " << r.render.skipped_border
      << " at the border, " << r.render.skipped_grazing << " grazing, " << r.render.skipped_small
      << " too small); detected vs exact corners RMS " << Fmt("%.3f", r.render.detection_rms_px)
      << " px\n\n";
  }
  if (r.photos.ran) {
    const PhotoSessionSummary& p = r.photos;
    o << "Photos (" << p.shots_path << ", boards " << p.targets_path << ": " << p.boards_with_pose
      << " with pose, " << p.boards_without_pose << " without): " << PhotoSessionLine(p);
    if (p.tag_boards) {
      o << "; tags dropped: " << p.unrefined << " unrefined, " << p.not_on_boards
        << " not on a board, " << p.duplicates << " duplicated";
    }
    o << "; " << p.jobs << " job(s)\n";
    // The shift against libapriltag's corners only where it found tags.
    o << "  line  shot                      zoom face  size         found"
      << (p.tag_boards ? "    shift_rms" : "") << "\n";
    for (const PhotoSessionSummary::Photo& ph : p.photos) {
      char row[256];
      std::snprintf(row, sizeof row, "  %4d  %-24s  %4d %4d  %5dx%-5d  %3d/%-3d", ph.line,
                    ph.shot.c_str(), ph.zoom, ph.face, ph.width, ph.height, ph.tags,
                    ph.tags_of_boards);
      o << row;
      if (p.tag_boards) o << Fmt("  %.3f px", ph.shift_rms_px);
      o << "\n";
    }
    for (const std::string& w : p.warnings) o << "  WARNING: " << w << "\n";
    o << "\n";
  }
  {
    const Coverage& cov = r.calibration.coverage;
    if (!cov.images.empty()) {
      o << "Image coverage of the fitted points (" << kCoverageCells << "x" << kCoverageCells
        << " cells):\n";
      for (const ImageCoverage& c : cov.images) {
        const auto src = r.calibration.size_source.find(c.zoom);
        o << "  zoom " << c.zoom << ": " << c.width << "x" << c.height << " px ("
          << (src == r.calibration.size_source.end() ? "?" : src->second) << "), " << c.points
          << " points, " << Fmt("%.0f", 100 * c.covered_fraction) << "% of the image covered, "
          << "farthest " << Fmt("%.0f", 100 * cov.corner_fraction[c.zoom])
          << "% of the half-diagonal, corners " << (c.corners_covered ? "covered" : "NOT covered")
          << "\n";
      }
      for (const std::string& w : r.calibration.coverage_warnings) o << "  WARNING: " << w << "\n";
      if (const std::string hint = PlanHint(config, r); !hint.empty()) o << "  " << hint << "\n";
      o << "\n";
    }
  }
  if (!r.uncertainty_maps.empty()) {
    const UncertaintyMapOptions& u = r.uncertainty_options;
    o << "Projection uncertainty (1 sigma, worst direction, px) of "
      << MapSubject(r.uncertainty_maps.front(), u) << ", " << u.cols << "x" << u.rows << " cells, "
      << (r.full_covariance ? "full covariance" : "diagonal approximation") << ":\n";
    o << "  zoom      min   median      max   inside: median      max   cells outside\n";
    for (const UncertaintyMap& m : r.uncertainty_maps) {
      if (!m.determined) {
        o << "  " << m.zoom << ": not determined by the data\n";
        continue;
      }
      char row[160];
      std::snprintf(row, sizeof(row), "  %4d %8.3g %8.3g %8.3g   %14.3g %8.3g   %d of %d\n", m.zoom,
                    m.min_px, m.median_px, m.max_px, m.inside_median_px, m.inside_max_px,
                    m.cells_outside, m.cols * m.rows);
      o << row;
    }
    o << "\n";
  }
  o << "Final (all observations): ";
  if (!r.obs.records.empty()) {
    o << "EDM " << stats(f.edm) << " m (n=" << f.edm.n << "), camera " << stats(f.cam)
      << " m (n=" << f.cam.n << ")" << (f.pixels.n > 0 ? ", " : "");
  }
  if (f.pixels.n > 0)
    o << "pixels rms " << Fmt("%.3f", f.pixels.rms_px) << " px (n=" << f.pixels.n << ")";
  o << "\nRefinement: " << (r.calibration.fit.converged ? "converged" : "NOT converged") << " in "
    << r.calibration.fit.iterations << " iterations, " << Fmt("%.3f", r.calibration.fit.seconds)
    << " s; excluded (critical region): " << r.calibration.fit.excluded_critical << "\n";
  o << "Gauge freedoms held:\n";
  for (const std::string& g : r.calibration.fit.fixed_gauges) o << "  - " << g << "\n";
  o << StrongCorrelationsText(r.calibration.fit);
  o << FitSigmasText(r.calibration.fit, !r.obs.records.empty()) << "\n";
  o << GrossRowsText(r);
  for (const std::string& n : r.notes) o << "note: " << n << "\n";
  return o.str();
}

std::string StrongCorrelationsText(const FitSummary& fit) {
  if (fit.strong_correlations.empty()) return "";
  // The strongest first: two runs of the same data differ in the last
  // digits (the fit's threads sum in varying order), so a pair near the
  // 0.95 threshold may be listed in one run and not in the other; first in
  // parameter order, such a pair moved every pair after it out of the
  // list or into it. Ties (|rho| = 1.000 to three decimals, typical of a
  // camera's rotation against its principal point) in parameter order.
  // The pairs with an estimated board pose are counted on one line, not
  // listed: each placement's pose correlates with the principal point (in
  // any calibration from boards of unknown pose), and a session of many
  // placements has hundreds of such pairs that would hide the pairs among
  // the model's own parameters. report.json lists every pair.
  constexpr size_t kListed = 16;
  std::vector<std::pair<std::string, double>> pairs;
  size_t with_boards = 0;
  double boards_max = 0;
  for (const auto& p : fit.strong_correlations) {
    if (p.first.find("board[") == std::string::npos) {
      pairs.push_back(p);
    } else {
      ++with_boards;
      boards_max = std::max(boards_max, std::abs(p.second));
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return std::round(1e3 * std::abs(a.second)) > std::round(1e3 * std::abs(b.second));
  });
  std::ostringstream o;
  o << "Strongly correlated parameters (|rho| > 0.95), the strongest first:\n";
  for (size_t i = 0; i < std::min(pairs.size(), kListed); ++i)
    o << "  " << pairs[i].first << "  rho = " << Fmt("%+.3f", pairs[i].second) << "\n";
  if (pairs.size() > kListed) {
    o << "  ... and " << pairs.size() - kListed
      << " more pairs (report.json fit.strong_correlations)\n";
  }
  if (with_boards > 0) {
    o << "  " << with_boards << " pair(s) with an estimated board pose, |rho| up to "
      << Fmt("%.3f", boards_max)
      << ": where a board stands trades with what moves its image alike (the principal "
         "point, a camera's rotation), as in any calibration from boards of unknown pose "
         "(report.json fit.strong_correlations lists them)\n";
  }
  return o.str();
}

std::string FitSigmasText(const FitSummary& fit, bool records) {
  std::ostringstream o;
  o << "A-posteriori sigmas: ";
  if (records) {
    o << "EDM " << Fmt("%.3g", fit.sigma_edm_m * 1e3) << " mm, camera "
      << Fmt("%.3g", fit.sigma_cam_m * 1e3) << " mm, ";
  }
  o << "pixels " << Fmt("%.3g", fit.sigma_pixel_px) << " px";
  std::string zooms;
  for (size_t z = 0; z < fit.sigma_pixel_px_zoom.size(); ++z) {
    if (fit.sigma_pixel_px_zoom[z] <= 0) continue;
    zooms += (zooms.empty() ? "" : ", ") + std::string("zoom ") + std::to_string(z) + " " +
             Fmt("%.3g", fit.sigma_pixel_px_zoom[z]);
  }
  if (!zooms.empty()) o << " (" << zooms << ")";
  if (fit.sigma_rounds > 0 && !fit.sigmas_converged) {
    o << ", still moving by more than " << Fmt("%g", 100 * kSigmaSettled) << " % after "
      << fit.sigma_rounds << " rounds of the variance-component estimate";
  }
  o << "; covariance: "
    << (fit.covariance_clusters > 0
            ? "cluster-robust over " + std::to_string(fit.covariance_clusters) +
                  " clusters (fit.covariance_clusters), never below the independent-error one."
            : std::string("independent errors of these sigmas."));
  return o.str();
}

}  // namespace rtscalib::app
