#include "libcalib/plan/session.h"

#include "libcalib/io/model_io.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/sim/simulator.h"
#include "libcalib/text/errors.h"

namespace rtscalib {

PlanSession SessionFromConfig(const RunConfig& config, const PlanSettings& settings) {
  if (!config.simulate) {
    throw InputError::Key(config.config_path, "simulate", 0, 0,
                          "a `simulate` section for rtscalib plan: its truth is the a-priori "
                          "instrument (or plan.prior_model) and its targets or placements are "
                          "the boards the plan may use",
                          "none");
  }
  SimulationOptions sim = *config.simulate;
  if (config.truth_from_paper) sim.truth = PaperTruth(PlanNumZooms(sim.plan));
  PlanSession s;
  s.prior = settings.prior_model.empty() ? sim.truth : ReadModelYaml(settings.prior_model);
  s.calibration = config.calibration;
  s.scenes = sim.Scenes();
  if (!settings.board.empty()) {
    // The board a camera on its own is held at, as the calibration will
    // read it (any board of a targets.yaml, a chessboard too).
    if (config.calibration.model.kinematics != Kinematics::kNone) {
      throw InputError::Key(config.config_path, "plan.board", 0, 0,
                            "a camera on its own (model.kinematics: none), whose board poses "
                            "are planned; an instrument's boards are simulate's",
                            settings.board);
    }
    s.scenes.clear();
    s.scenes[""] = ReadTargets(settings.board);
  }
  s.board_poses_known =
      settings.board_poses_known ? *settings.board_poses_known : sim.placements.empty();
  // The records the session takes anyway (exact: only their Jacobian counts).
  s.fixed.records = PlanRecords(sim.plan, s.prior);
  s.fixed.records_source = "simulate.plan records";
  for (int z = 0; z < s.prior.NumZooms(); ++z) {
    s.fixed.image_sizes[z] = ImageSize{s.prior.cams[z].width, s.prior.cams[z].height};
  }
  return s;
}

}  // namespace rtscalib
