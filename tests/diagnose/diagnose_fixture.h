// Simulated instruments for the diagnosis tests: a truth with one flaw, data
// with noise, the baseline model fitted without the flaw.
#pragma once

#include <random>

#include "libcalib/diagnose/diagnose.h"
#include "libcalib/eval/error_measures.h"
#include "libcalib/fit/refine.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/sim/simulator.h"

namespace rtscalib::testing_diagnose {

// Noise of the simulated instrument: 1 arcsec per angle reading, 10 um per
// EDM distance and per coordinate of a returned point (a PLT 300-class device).
inline NoiseOptions PaperNoise() {
  NoiseOptions n;
  n.angle_rad = 1.0 / 206264.806;
  n.distance_m = 1e-5;
  n.point_m = 1e-5;
  return n;
}

// Small but complete: the paper's sweeps plus an 8 x 5 grid in both faces,
// EDM distances over a decade (and sampling the 1.5 m cyclic unit), camera
// rays through a 4 x 4 pixel grid.
inline AcquisitionPlan SmallPlan() {
  AcquisitionPlan plan;
  plan.grid_phi_steps = 8;
  plan.grid_theta_steps = 5;
  plan.faces = {1, 2};
  plan.edm_distances = {1.0, 2.0, 7.0, 30.0};
  plan.grid_edm_distances = {1.0, 1.4, 2.3, 5.0, 12.0, 31.0};
  plan.grid_cam_ray_lengths = {1.0};
  plan.grid_pixels_per_axis = 4;
  return plan;
}

inline InstrumentModel SphericalTruth() {
  InstrumentModel m = IdealModel(Kinematics::kSpherical, 1, PaperTruth(1).cams[0]);
  m.cams[0].flange_from_cam =
      PoseBlock::FromRigid(Rigid3::FromEuler({2e-3, -1e-3, 4e-3}, {1e-4, -2e-4, 3e-4}));
  m.edm.t = {2e-4, -1e-4, 0.0};
  m.base = PoseBlock::FromRigid(Rigid3::FromEuler({1e-4, -2e-4, 0.3}, {1.0, 2.0, 0.5}));
  return m;
}

// The truth moved by about a millimetre and a milliradian in every free
// parameter, effects removed (what a good extraction gives): the baseline
// fit starts here.
inline InstrumentModel Perturbed(const InstrumentModel& truth, std::uint64_t seed) {
  InstrumentModel m = PerturbedStart(truth, seed);
  for (CameraTool& c : m.cams) c.distortion.fill(0.0);
  m.effects = EffectSet();
  return m;
}

struct Fitted {
  SimulatedData data;
  InstrumentModel truth;
  InstrumentModel model;
  FitOptions options;
  FitSummary fit;
};

// Fits the truth's kinematics without effects to `data`. With
// `fit_intrinsics` false the intrinsics stay at the truth's (what a device
// API that reports its camera gives).
inline Fitted FitBaseline(SimulatedData data, const InstrumentModel& truth, std::uint64_t seed,
                          bool fit_intrinsics = true) {
  Fitted f;
  f.data = std::move(data);
  f.truth = truth;
  f.model = Perturbed(truth, seed);
  f.options.fit_intrinsics = fit_intrinsics;
  f.options.num_threads = 1;
  f.fit = Refine(f.data.obs, f.options, &f.model);
  return f;
}

inline Diagnosis DiagnoseFitted(const Fitted& f, const DiagnosisSettings& s = {}) {
  return Diagnose(f.data.obs, f.model, ContextOf(f.options, f.fit), s);
}

// RMS of the record point distances over the rows the fit uses.
inline double RecordsRms(const InstrumentModel& m, const Fitted& f) {
  return RmsOfModel(f.data.obs, m, f.options).records_m;
}

}  // namespace rtscalib::testing_diagnose
