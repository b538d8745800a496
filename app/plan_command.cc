// `rtscalib plan` (SPEC 8, docs/plan.md): the session's shots before it is
// measured, or the shots to add to an earlier run. Writes plan.csv (the
// columns of a shots.csv, SPEC 7, the image column left for the user to
// fill), plan.json and figures/plan.* into the output folder, never
// replacing a file that exists.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/commands.h"
#include "app/photo_session.h"
#include "app/plan_figures.h"
#include "app/progress.h"
#include "libcalib/fit/parameterization.h"
#include "libcalib/config/config.h"
#include "libcalib/io/csv.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/plan/session.h"
#include "libcalib/plan/settings.h"
#include "libcalib/sim/simulator.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"
#include "render/settings.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Number(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

std::string PlanCsv(const PlanResult& plan, bool placements, bool focus, bool board_poses) {
  std::ostringstream o;
  if (board_poses) {
    o << "# rtscalib plan: hold the board as each row says (figures/plan.png shows\n"
         "# where it is seen), fill the image column with each photo's file, then\n"
         "# calibrate with data.shots: plan.csv (docs/plan.md). board_u_px, board_v_px:\n"
         "# where the board's centre is seen; distance from the camera; turn about the\n"
         "# image's vertical (> 0: its right edge nearer), tilt about its horizontal\n"
         "# (> 0: its bottom edge nearer).\n";
  } else {
    o << "# rtscalib plan: take the photos in this order (faces grouped, one walk per\n"
         "# placement), fill the image column with each photo's file, then calibrate\n"
         "# with data.shots: plan.csv (docs/plan.md). phi, theta in radians.\n";
  }
  o << "shot,face,zoom,phi,theta" << (placements ? ",placement" : "")
    << (focus ? ",focus_distance" : "")
    << (board_poses ? ",board_u_px,board_v_px,board_distance_m,board_turn_deg,board_tilt_deg" : "")
    << ",image\n";
  for (const PlanShot& s : plan.shots) {
    o << s.pointing.name << "," << s.pointing.face << "," << s.pointing.zoom << ",";
    // A camera on its own has no readings (SPEC 7.1: empty).
    if (board_poses)
      o << ",";
    else
      o << FormatDouble(s.pointing.phi) << "," << FormatDouble(s.pointing.theta);
    if (placements) o << "," << s.pointing.placement;
    if (focus) o << "," << FormatDouble(s.focus_distance);
    if (board_poses) {
      // Whole pixels and degrees (+ 0.0: no "-0").
      auto whole = [](double x) { return Fmt("%.0f", std::round(x) + 0.0); };
      o << "," << whole(s.board.centre_px.x()) << "," << whole(s.board.centre_px.y()) << ","
        << Fmt("%.3f", s.board.distance_m) << "," << whole(s.board.turn_deg) << ","
        << whole(s.board.tilt_deg);
    }
    o << ",\n";
  }
  return o.str();
}

json PlanJson(const PlanResult& plan, const PlanOptions& options, const std::string& mode) {
  json j;
  j["mode"] = mode;
  j["goal_met"] = plan.goal_met;
  j["limits"] = plan.limits;
  j["shots"] = plan.shots.size();
  j["candidates"] = plan.candidates;
  j["max_shots"] = options.max_shots;
  j["motor_travel_deg"] = plan.motor_travel_rad * 180.0 / M_PI;
  json goal;
  for (const auto& [name, sigma] : options.goal.sigmas) goal["sigmas"][name] = sigma;
  goal["projection_px"] = options.goal.projection_px;
  j["goal"] = goal;
  json constants = json::array();
  for (const PredictedConstant& c : plan.constants) {
    json e = {{"name", c.name},
              {"unit", c.unit},
              {"sigma", Number(c.sigma)},
              {"determined", c.determined},
              {"sigma_all_candidates", Number(c.sigma_all_candidates)},
              {"sigma_without_plan", Number(c.sigma_fixed)}};
    if (c.goal > 0) e["goal"] = c.goal;
    constants.push_back(e);
  }
  j["constants"] = constants;
  json proj = json::array();
  for (const PredictedProjection& p : plan.projection) {
    json e = {{"zoom", p.zoom}, {"worst_px", Number(p.worst_px)}};
    if (p.goal_px > 0) e["goal_px"] = p.goal_px;
    proj.push_back(e);
  }
  j["projection"] = proj;
  json shots = json::array();
  for (const PlanShot& s : plan.shots) {
    json e = {{"shot", s.pointing.name},   {"face", s.pointing.face},
              {"zoom", s.pointing.zoom},   {"phi", s.pointing.phi},
              {"theta", s.pointing.theta}, {"placement", s.pointing.placement},
              {"points", s.points},        {"determines", s.determines}};
    if (s.focus_distance > 0) e["focus_distance"] = s.focus_distance;
    if (s.board_pose) {
      e["board"] = {{"centre_px", {s.board.centre_px.x(), s.board.centre_px.y()}},
                    {"distance_m", s.board.distance_m},
                    {"turn_deg", s.board.turn_deg},
                    {"tilt_deg", s.board.tilt_deg},
                    {"cam_from_board",
                     {{"R",
                       {{s.cam_from_board.rotation(0, 0), s.cam_from_board.rotation(0, 1),
                         s.cam_from_board.rotation(0, 2)},
                        {s.cam_from_board.rotation(1, 0), s.cam_from_board.rotation(1, 1),
                         s.cam_from_board.rotation(1, 2)},
                        {s.cam_from_board.rotation(2, 0), s.cam_from_board.rotation(2, 1),
                         s.cam_from_board.rotation(2, 2)}}},
                      {"t",
                       {s.cam_from_board.translation.x(), s.cam_from_board.translation.y(),
                        s.cam_from_board.translation.z()}}}}};
    }
    json buys = json::object();
    for (const auto& [name, sigma] : s.sigma_without) buys[name] = Number(sigma);
    if (!s.sigma_without.empty()) e["sigma_without_this_shot"] = buys;
    shots.push_back(e);
  }
  j["plan"] = shots;
  return j;
}

json ReadReport(const std::string& report_path) {
  std::ifstream in(report_path);
  if (!in)
    throw InputError::File(report_path, 0, "report", "the run's report.json", "no such file");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw InputError::File(report_path, 0, "report", "JSON", e.what());
  }
}

// The pixel noise the earlier run's photos showed: its a-posteriori pixel
// sigma (report.json fit.sigma_pixel_px), where it is larger than the
// config's a-priori one. The photos to add, of the same camera, boards and
// detector, will be as noisy as those taken: a plan with an a-priori sigma
// that the detector does not reach on these photos would promise sigmas
// the next run does not report. The records keep their a-priori sigmas
// (the tracker's own accuracy); a run whose model lacks an effect fits
// them worse than that, and the diagnosis says which effect to add first.
// Returns what it took, for plan.json.
json TakeObservedPixelSigma(const json& report, FitOptions* fit) {
  json taken = json::object();
  if (!report.contains("fit") || !report["fit"].contains("sigma_pixel_px")) return taken;
  const json& observed = report["fit"]["sigma_pixel_px"];
  if (observed.is_number() && std::isfinite(observed.get<double>()) &&
      observed.get<double>() > fit->sigma_pixel_px) {
    taken["sigma_pixel_px"] = {{"a_priori", fit->sigma_pixel_px}, {"observed", observed}};
    fit->sigma_pixel_px = observed.get<double>();
  }
  return taken;
}

// Every kinematic effect the earlier run's diagnosis ranked as not
// identifiable.
std::vector<Effect> NotIdentifiable(const json& r) {
  std::vector<Effect> out;
  if (!r.contains("diagnosis") || !r["diagnosis"].contains("ranking")) return out;
  for (const json& e : r["diagnosis"]["ranking"]) {
    if (!e.is_object() || e.value("identifiable", true)) continue;
    const std::optional<Effect> effect = EffectFromName(e.value("effect", std::string()));
    if (effect && IsKinematic(*effect)) out.push_back(*effect);
  }
  return out;
}

}  // namespace

int RunPlan(const PlanArgs& args) {
  if (args.config.empty() == args.from.empty()) {
    throw std::invalid_argument("plan: expected exactly one of --config FILE.yaml or --from OUT");
  }
  const bool from = !args.from.empty();
  const std::string config_path =
      from ? (fs::path(args.from) / "latest" / "config.yaml").string() : args.config;
  std::error_code ec;
  if (!fs::exists(config_path, ec)) {
    throw InputError::File(config_path, 0, "config",
                           from ? "the run's config.yaml (OUT/latest/config.yaml)" : "a config",
                           "no such file");
  }
  render::RenderSettings render;
  PlanSettings settings;
  const std::string config_dir = fs::absolute(config_path).parent_path().string();
  const RunConfig config = LoadConfig(config_path, {render::RenderConfigSection(&render),
                                                    PlanConfigSection(&settings, config_dir)});
  PlanSession session;
  if (from && !config.simulate) {
    // A run of real data: the boards are the ones it estimated (below).
    session.calibration = config.calibration;
  } else {
    session = SessionFromConfig(config, settings);
  }
  PlanOptions options = settings.options;
  for (const std::string& goal : args.goals) {
    // NAME=SIGMA, checked by the command line's parser.
    const size_t eq = goal.find('=');
    const double sigma = ParseFiniteDouble(goal.substr(eq + 1)).value_or(0);
    const std::string name = goal.substr(0, eq);
    auto& sigmas = options.goal.sigmas;
    sigmas.erase(std::remove_if(sigmas.begin(), sigmas.end(),
                                [&](const auto& g) { return g.first == name; }),
                 sigmas.end());
    sigmas.push_back({name, sigma});
  }
  if (args.projection_px > 0) options.goal.projection_px = args.projection_px;
  std::string mode = "plan";
  std::vector<std::string> added_effects;
  json observed_sigmas = json::object();
  if (from) {
    mode = "add to " + args.from;
    // The earlier run's model is the prior; its observations (the config's
    // data, or its simulated session) are measured already.
    const std::string model_path = (fs::path(args.from) / "model.yaml").string();
    session.prior = ReadModelYaml(model_path);
    if (!session.prior.boards.empty()) {
      // The boards where the run estimated them, in its reference frame.
      session.scenes.clear();
      for (const EstimatedBoard& b : session.prior.boards) {
        TagBoard board = b.board;
        board.ref_from_board = b.pose.ToRigid();
        session.scenes[b.placement].boards.push_back(board);
      }
      session.board_poses_known = false;
    } else {
      // The run estimated no board: its boards' corners were known.
      session.board_poses_known = true;
      if (!config.targets_path.empty() && session.scenes.empty())
        session.scenes[""] = ReadTargets(config.targets_path);
    }
    // What the run measured: its data files; a simulated run's records.csv
    // and pixels.csv (written into its history entry); a photo session's
    // photos, detected again.
    const fs::path latest = fs::path(args.from) / "latest";
    session.fixed = Observations();
    if (!config.records_path.empty()) {
      session.fixed.records = ReadRecords(config.records_path, config.angle_unit).records;
    } else if (fs::exists(latest / "records.csv", ec)) {
      session.fixed.records = ReadRecords((latest / "records.csv").string()).records;
    }
    if (!config.pixels_path.empty()) {
      session.fixed.pixels = ReadPixels(config.pixels_path, config.angle_unit).pixels;
    } else if (fs::exists(latest / "pixels.csv", ec)) {
      session.fixed.pixels = ReadPixels((latest / "pixels.csv").string()).pixels;
    }
    if (!config.shots_path.empty()) {
      Progress progress(args.quiet);
      LoadPhotoSession(config.shots_path, config.targets_path, config.detect_jobs, &session.fixed,
                       &progress, config.angle_unit);
    }
    if (session.fixed.records.empty() && session.fixed.pixels.empty()) {
      throw InputError::File(args.from, 0, "run",
                             "a run whose observations can be read again (data files, or a "
                             "simulated run's records.csv and pixels.csv)",
                             "none found");
    }
    for (int z = 0; z < session.prior.NumZooms(); ++z) {
      session.fixed.image_sizes.try_emplace(
          z, ImageSize{session.prior.cams[z].width, session.prior.cams[z].height});
    }
    // The effects the diagnosis could not determine (and the kinematics do
    // not contain) are estimated in the plan; the goal: each amplitude to 1
    // in its report unit (1 arcsec, 1 ppm, 1 mm), unless plan.goal names it.
    const json report = ReadReport((fs::path(args.from) / "report.json").string());
    observed_sigmas = TakeObservedPixelSigma(report, &session.calibration.fit);
    for (Effect effect : NotIdentifiable(report)) {
      if (ContainedInKinematics(session.calibration.model.kinematics, effect)) continue;
      session.calibration.model.effects.Add(effect);
      const std::string name = std::string(Info(effect).name) + "." + Info(effect).param_names[0];
      added_effects.push_back(Info(effect).name);
      bool named = false;
      for (const auto& g : options.goal.sigmas) named = named || g.first == name;
      if (!named) options.goal.sigmas.push_back({name, 1.0});
    }
    if (added_effects.empty() && !args.quiet) {
      std::cout << "rtscalib plan: the run's diagnosis found no effect it could not determine; "
                   "planning toward the goal alone\n";
    }
  }
  PlanResult plan;
  try {
    plan = PlanShots(session, options);
  } catch (const std::invalid_argument& e) {
    // The planner names the plan key ("plan.zooms: ..."): the config's file
    // with it.
    const std::string what = e.what();
    const size_t colon = what.find(": ");
    if (what.rfind("plan.", 0) != 0 || colon == std::string::npos) throw;
    throw InputError::Key(config.config_path, what.substr(0, colon), 0, 0,
                          "a value this session and model allow", what.substr(colon + 2));
  }

  const std::string out_dir = !args.output.empty() ? args.output
                              : from               ? (fs::path(args.from) / "plan").string()
                                                   : config.output_dir;
  fs::create_directories(out_dir, ec);
  if (ec) throw WriteError(out_dir, ec.message());
  for (const char* name : {"plan.csv", "plan.json"}) {
    if (fs::exists(fs::path(out_dir) / name, ec)) {
      throw InputError::File((fs::path(out_dir) / name).string(), 0, "output",
                             "no file of this name (rtscalib does not overwrite files you have)",
                             "it exists; choose another --output");
    }
  }
  // A camera on its own: where to hold the board, also in a plan of no shot.
  const bool board_poses = config.calibration.model.kinematics == Kinematics::kNone;
  bool placements = board_poses, focus = false;
  for (const PlanShot& s : plan.shots) {
    placements = placements || !s.pointing.placement.empty();
    focus = focus || s.focus_distance > 0;
  }
  json j = PlanJson(plan, options, mode);
  if (from) {
    j["effects_not_identifiable"] = added_effects;
    j["observed_sigmas"] = observed_sigmas;
  }
  std::string note;
  const std::vector<Figure> figures{PlanFigure(plan)};
  if (!plan.shots.empty()) {
    const std::string fig_dir = (fs::path(out_dir) / "figures").string();
    bool taken = false;
    for (const char* ext : {".vg.json", ".svg", ".png"})
      taken = taken || fs::exists(fs::path(fig_dir) / (std::string("plan") + ext), ec);
    if (!taken) {
      WriteFigureFiles(figures, fig_dir, &note);
      j["figures"] = {"figures/plan.vg.json"};
    }
  }
  WriteFileAtomic((fs::path(out_dir) / "plan.csv").string(),
                  PlanCsv(plan, placements, focus, board_poses), Existing::kKeep);
  WriteFileAtomic((fs::path(out_dir) / "plan.json").string(), j.dump(2) + "\n", Existing::kKeep);
  if (!args.quiet) {
    std::cout << "rtscalib plan: " << plan.shots.size() << " shots of " << plan.candidates
              << " candidates; "
              << (options.goal.Empty() ? "no goal: the D-optimal choice of max_shots photos"
                  : plan.goal_met      ? "goal met"
                                       : "goal NOT met")
              << "\n";
    for (const std::string& l : plan.limits) std::cout << "  limit: " << l << "\n";
    for (const PredictedConstant& c : plan.constants) {
      if (c.goal > 0)
        std::cout << "  " << c.name << ": sigma " << Significant(c.sigma, 3) << " " << c.unit
                  << " (goal " << Significant(c.goal, 3) << ")\n";
    }
    for (const PredictedProjection& p : plan.projection)
      std::cout << "  projection zoom " << p.zoom << ": worst " << Significant(p.worst_px, 3)
                << " px\n";
    std::cout << "  wrote " << out_dir << "/plan.csv, plan.json"
              << (note.empty() ? "" : " (" + note + ")") << "\n";
  }
  return 0;
}

}  // namespace rtscalib::app
