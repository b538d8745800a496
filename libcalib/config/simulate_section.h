// The config's `simulate` section (docs/config.md, "simulate"): the
// simulated instrument's truth, noise, acquisition plan, boards and shots,
// read into SimulationOptions (libcalib/sim/options.h) and dumped back.
#pragma once

#include <yaml-cpp/yaml.h>

#include "libcalib/calibrate/options.h"
#include "libcalib/io/yaml_reader.h"
#include "libcalib/sim/options.h"

namespace rtscalib {

// Reads the section at `m`. The truth starts from the ideal model of `model`'s
// kinematics and cameras; without a `truth` key *truth_from_paper is set and
// the caller builds Klug's truth (PaperTruth, libcalib/sim/simulator.h).
void ReadSimulateSection(const YamlNode& m, const ModelSettings& model, SimulationOptions* out,
                         bool* truth_from_paper);

// The section with every default written out; the truth's rotations as
// quaternions, which read back bit for bit.
void EmitSimulateSection(YAML::Emitter& e, const SimulationOptions& sim, bool truth_from_paper);

}  // namespace rtscalib
