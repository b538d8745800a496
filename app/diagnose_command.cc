// `rtscalib diagnose --config X [--auto]`: the run of `rtscalib --config X`
// with the diagnosis switched on (and, with --auto, the forward stepwise
// ladder), printing the diagnosis instead of the paper's tables. Everything
// is written to the output folder as by a run.
#include "app/commands.h"

namespace rtscalib::app {

int RunDiagnose(RunArgs args) {
  args.diagnose = true;
  return RunCalibration(args);
}

}  // namespace rtscalib::app
