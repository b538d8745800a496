#include "libcalib/io/model_io.h"
#include "libcalib/io/yaml_writer.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>

#include "libcalib/fit/parameterization.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"
#include "libcalib/io/targets_io.h"
#include "libcalib/io/yaml_reader.h"

namespace rtscalib {
namespace {

constexpr const char* kModelFormat = "rtscalib-model";
constexpr int kModelVersion = 1;

// Derived values (Euler angles, report units) must match their parameter
// blocks to this relative tolerance; %.17g text and the trigonometry between
// them lose ~1e-15.
constexpr double kDerivedTolerance = 1e-9;
// The sigma of a distortion coefficient the fit did not estimate.
constexpr const char* kHeldSigma = "held";

// {name: value, ...} in flow style.
void EmitNamed(YAML::Emitter& e, const char* const* names, const double* x, int n) {
  e << YAML::Flow << YAML::BeginMap;
  for (int i = 0; i < n; ++i) e << YAML::Key << names[i] << YAML::Value << YamlDouble(x[i]);
  e << YAML::EndMap;
}

// `determined` false: the pose is its start value, not an estimate; it is
// written with `determined: false` and no sigma (never a sigma of 0).
void EmitPose(YAML::Emitter& e, const PoseBlock& pose, const PoseSigma* sigma,
              bool determined = true) {
  e << YAML::BeginMap;
  if (!determined) {
    e << YAML::Key << "determined" << YAML::Value << false;
    sigma = nullptr;
  }
  e << YAML::Key << "q" << YAML::Value;
  EmitNumbers(e, pose.q.data(), 4, /*shortest=*/false);
  e << YAML::Key << "t" << YAML::Value;
  EmitNumbers(e, pose.t.data(), 3, /*shortest=*/false);
  const Eigen::Vector3d euler = pose.Euler();
  e << YAML::Key << "euler" << YAML::Value;
  EmitNumbers(e, euler.data(), 3, /*shortest=*/false);
  if (sigma) {
    e << YAML::Key << "sigma" << YAML::Value << YAML::Flow << YAML::BeginMap;
    e << YAML::Key << "rotation" << YAML::Value;
    EmitNumbers(e, sigma->rotation.data(), 3, /*shortest=*/false);
    e << YAML::Key << "euler" << YAML::Value;
    EmitNumbers(e, sigma->euler.data(), 3, /*shortest=*/false);
    e << YAML::Key << "t" << YAML::Value;
    EmitNumbers(e, sigma->t.data(), 3, /*shortest=*/false);
    e << YAML::EndMap;
  }
  e << YAML::EndMap;
}

// board_warp: per board {first_id, si: [wx, wy] [m], covariance (2 x 2 row
// major [m^2]), report: {wx, wy} in mm}.
void EmitBoardWarps(YAML::Emitter& e, const InstrumentModel& model) {
  const EffectInfo& info = Info(Effect::kBoardWarp);
  const double scale = ReportScale(Effect::kBoardWarp);
  e << YAML::Key << "boards" << YAML::Value << YAML::BeginSeq;
  for (const BoardWarp& w : model.board_warps) {
    e << YAML::BeginMap;
    e << YAML::Key << "first_id" << YAML::Value << w.first_id;
    e << YAML::Key << "si" << YAML::Value;
    EmitNumbers(e, w.w.data(), kNumBoardWarp, /*shortest=*/false);
    if (model.sigmas.valid) {
      e << YAML::Key << "covariance" << YAML::Value;
      EmitNumbers(e, w.cov.data(), 4, /*shortest=*/false);
    }
    e << YAML::Key << "report" << YAML::Value << YAML::BeginMap;
    for (int i = 0; i < kNumBoardWarp; ++i) {
      e << YAML::Key << info.param_names[i] << YAML::Value << YAML::Flow << YAML::BeginMap;
      e << YAML::Key << "value" << YAML::Value << YamlDouble(w.w[i] * scale);
      if (model.sigmas.valid) {
        e << YAML::Key << "sigma" << YAML::Value
          << YamlDouble(std::sqrt(std::max(w.cov[3 * i], 0.0)) * scale);
      }
      e << YAML::Key << "unit" << YAML::Value << info.report_units[i];
      e << YAML::EndMap;
    }
    e << YAML::EndMap;
    e << YAML::EndMap;
  }
  e << YAML::EndSeq;
}

void EmitEffect(YAML::Emitter& e, const InstrumentModel& model, Effect effect) {
  const EffectInfo& info = Info(effect);
  e << YAML::BeginMap;
  e << YAML::Key << "name" << YAML::Value << info.name;
  if (IsBoardEffect(effect)) EmitBoardWarps(e, model);
  if (IsKinematic(effect)) {
    const std::array<double, 4>& cov = model.sigmas.effect_cov[static_cast<int>(effect)];
    e << YAML::Key << "si" << YAML::Value;
    EmitNumbers(e, model.EffectValue(effect).data(), info.num_params, /*shortest=*/false);
    if (model.sigmas.valid) {
      e << YAML::Key << "covariance" << YAML::Value;
      EmitNumbers(e, cov.data(), 4, /*shortest=*/false);
    }
    const EffectReportValue report = ToReportUnits(effect, model.EffectValue(effect), cov);
    e << YAML::Key << "report" << YAML::Value << YAML::BeginMap;
    for (int i = 0; i < info.num_params; ++i) {
      e << YAML::Key << info.param_names[i] << YAML::Value << YAML::Flow << YAML::BeginMap;
      e << YAML::Key << "value" << YAML::Value << YamlDouble(report.value[i]);
      if (model.sigmas.valid)
        e << YAML::Key << "sigma" << YAML::Value << YamlDouble(report.sigma[i]);
      e << YAML::Key << "unit" << YAML::Value << info.report_units[i];
      e << YAML::EndMap;
    }
    e << YAML::EndMap;
  }
  e << YAML::EndMap;
}

void EmitCamera(YAML::Emitter& e, const InstrumentModel& model, int zoom) {
  const CameraTool& cam = model.cams[zoom];
  const ModelSigmas& s = model.sigmas;
  e << YAML::BeginMap;
  e << YAML::Key << "zoom" << YAML::Value << zoom;
  e << YAML::Key << "width" << YAML::Value << cam.width;
  e << YAML::Key << "height" << YAML::Value << cam.height;
  if (!cam.determined) e << YAML::Key << "determined" << YAML::Value << false;
  // A camera-only model (SPEC 7.1) has no camera tool: none was estimated.
  if (model.kinematics != Kinematics::kNone) {
    e << YAML::Key << "flange_from_cam" << YAML::Value;
    EmitPose(e, cam.flange_from_cam, s.valid ? &s.cam_tools[zoom] : nullptr, cam.determined);
  }
  e << YAML::Key << "intrinsics" << YAML::Value;
  EmitNamed(e, kIntrinsicsParamNames, cam.intrinsics.data(), kNumIntrinsics);
  e << YAML::Key << "distortion" << YAML::Value;
  EmitNamed(e, kDistortionCoefficientNames, cam.distortion.data(), kNumDistortion);
  // The coefficients of enabled groups that the user held
  // (model.<group>.coefficients): not estimated, so that a reader knows.
  std::vector<std::string> held;
  for (int i = 0; i < kNumDistortion; ++i) {
    if (model.effects.Has(DistortionGroupOf(i)) && cam.distortion_held[i]) {
      held.emplace_back(kDistortionCoefficientNames[i]);
    }
  }
  if (!held.empty()) e << YAML::Key << "distortion_held" << YAML::Value << YAML::Flow << held;
  // SPEC 4.1: the intrinsics above are focused at infinity; at focus
  // distance D they are fx (1 + kf/D), fy (1 + kf/D), cx + au/D, cy + av/D.
  const bool focus = model.effects.Has(Effect::kFocus);
  if (focus) {
    e << YAML::Key << "focus" << YAML::Value;
    EmitNamed(e, kFocusParamNames, cam.focus.data(), kNumFocus);
  }
  if (s.valid && cam.determined) {
    e << YAML::Key << "intrinsics_sigma" << YAML::Value;
    EmitNamed(e, kIntrinsicsParamNames, s.intrinsics[zoom].data(), kNumIntrinsics);
    // A coefficient the fit did not free (held by the user, or of a group
    // not in the model) has no sigma: `held`, never a precision of 0.
    e << YAML::Key << "distortion_sigma" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (int i = 0; i < kNumDistortion; ++i) {
      e << YAML::Key << kDistortionCoefficientNames[i] << YAML::Value;
      if (DistortionIsFree(model, zoom, i)) {
        e << YamlDouble(s.distortion[zoom][i]);
      } else {
        e << kHeldSigma;
      }
    }
    e << YAML::EndMap;
    if (focus && zoom < static_cast<int>(s.focus.size())) {
      e << YAML::Key << "focus_sigma" << YAML::Value;
      EmitNamed(e, kFocusParamNames, s.focus[zoom].data(), kNumFocus);
    }
  }
  if (!cam.valid_region.empty()) {
    e << YAML::Key << "valid_region" << YAML::Value << YAML::BeginSeq;
    for (const Eigen::Vector2d& p : cam.valid_region)
      EmitNumbers(e, p.data(), 2, /*shortest=*/false);
    e << YAML::EndSeq;
  }
  e << YAML::EndMap;
}

// --- reading ----------------------------------------------------------------

// What a number of model.yaml may be: a finite value, or a standard
// deviation (>= 0, or .nan where nothing was estimated: a negative sigma
// would make every uncertainty that uses it wrong without a sign of it).
enum class Number { kValue, kSigma };

double ReadNumber(const YamlNode& n, Number kind) {
  if (kind == Number::kValue) return n.AsDouble();
  const double x = n.AsDoubleOrNan();
  if (x < 0) n.Fail("a standard deviation >= 0 (or .nan where it was not estimated)");
  return x;
}

void ReadNumbersInto(const YamlNode& n, double* out, int size, Number kind = Number::kValue) {
  const std::vector<YamlNode> items = n.Items();
  if (static_cast<int>(items.size()) != size) {
    n.Fail("a list of " + std::to_string(size) + " numbers");
  }
  for (int i = 0; i < size; ++i) out[i] = ReadNumber(items[i], kind);
}

void ReadNamedInto(const YamlNode& m, const char* const* names, double* out, int size,
                   Number kind = Number::kValue) {
  for (int i = 0; i < size; ++i) out[i] = ReadNumber(m.Require(names[i]), kind);
}

// Whether a `determined` key (absent in files before it existed: true) says
// the block was estimated.
bool ReadDetermined(const YamlNode& m) {
  const std::optional<YamlNode> n = m.Find("determined");
  return !n || n->AsBool();
}

// A sigma that was never estimated: NaN, never 0.
void SetNotEstimated(PoseSigma* sigma) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  sigma->rotation.fill(nan);
  sigma->euler.fill(nan);
  sigma->t.fill(nan);
}

PoseBlock ReadPose(const YamlNode& m, bool with_sigma, PoseSigma* sigma,
                   bool* determined = nullptr) {
  PoseBlock pose;
  const bool estimated = ReadDetermined(m);
  if (determined) *determined = estimated;
  if (!estimated) {
    SetNotEstimated(sigma);
    with_sigma = false;
  }
  const YamlNode q = m.Require("q");
  ReadNumbersInto(q, pose.q.data(), 4);
  RequireUnitQuaternion(q, pose.q.data());
  ReadNumbersInto(m.Require("t"), pose.t.data(), 3);
  const YamlNode euler_node = m.Require("euler");
  double euler[3];
  ReadNumbersInto(euler_node, euler, 3);
  const Eigen::Matrix3d from_euler =
      RotationFromEuler<double>(Eigen::Vector3d(euler[0], euler[1], euler[2]));
  if ((from_euler - pose.ToRigid().rotation).cwiseAbs().maxCoeff() > kDerivedTolerance) {
    euler_node.Fail("the Euler angles [a, b, g] of q (predictions use q; edit both together)");
  }
  if (with_sigma) {
    const YamlNode s = m.Require("sigma");
    ReadNumbersInto(s.Require("rotation"), sigma->rotation.data(), 3, Number::kSigma);
    ReadNumbersInto(s.Require("euler"), sigma->euler.data(), 3, Number::kSigma);
    ReadNumbersInto(s.Require("t"), sigma->t.data(), 3, Number::kSigma);
  }
  return pose;
}

// A 2 x 2 covariance (row major): variances >= 0, symmetric, |rho| <= 1.
void ReadCovariance2(const YamlNode& c, std::array<double, 4>* out) {
  std::array<double, 4>& cov = *out;
  const std::vector<YamlNode> items = c.Items();
  if (items.size() != 4) c.Fail("a list of 4 numbers (a 2 x 2 covariance, row major)");
  for (int i = 0; i < 4; ++i) cov[i] = items[i].AsDoubleOrNan();
  const bool nan = std::isnan(cov[0]) || std::isnan(cov[3]);
  // Symmetric to round-off: a covariance from the solver's inverse may
  // differ in its last digits between (0, 1) and (1, 0); it is made exactly
  // symmetric here.
  const double scale = std::sqrt(std::abs(cov[0] * cov[3]));
  if (!nan && (cov[0] < 0 || cov[3] < 0 || !(std::abs(cov[1] - cov[2]) <= 1e-9 * scale) ||
               cov[1] * cov[2] > cov[0] * cov[3] * (1 + 1e-9))) {
    c.Fail("a covariance: variances >= 0, symmetric, |correlation| <= 1");
  }
  if (!nan) cov[1] = cov[2] = 0.5 * (cov[1] + cov[2]);
}

// board_warp's `boards` (EmitBoardWarps); each first_id once. Whether every
// warp belongs to a board of the file is checked once the boards are read.
void ReadBoardWarps(const YamlNode& m, bool with_sigma, InstrumentModel* model) {
  const EffectInfo& info = Info(Effect::kBoardWarp);
  const double scale = ReportScale(Effect::kBoardWarp);
  for (const YamlNode& item : m.Require("boards").Items()) {
    BoardWarp w;
    const YamlNode id = item.Require("first_id");
    w.first_id = id.AsInt();
    if (w.first_id < 0) id.Fail("the board's first tag id (an integer >= 0)");
    if (model->WarpOf(w.first_id)) id.Fail("each board once");
    ReadNumbersInto(item.Require("si"), w.w.data(), kNumBoardWarp);
    if (with_sigma) ReadCovariance2(item.Require("covariance"), &w.cov);
    const YamlNode report = item.Require("report");
    for (int i = 0; i < kNumBoardWarp; ++i) {
      const YamlNode p = report.Require(info.param_names[i]);
      const double value = p.Require("value").AsDouble();
      if (with_sigma) ReadNumber(p.Require("sigma"), Number::kSigma);
      const YamlNode unit = p.Require("unit");
      if (unit.AsString() != info.report_units[i]) unit.Fail(info.report_units[i]);
      if (std::fabs(value / scale - w.w[i]) > kDerivedTolerance * std::hypot(w.w[0], w.w[1])) {
        report.Fail("report values that convert to si (predictions use si; edit both together)");
      }
    }
    model->board_warps.push_back(w);
  }
}

void ReadEffect(const YamlNode& m, bool with_sigma, InstrumentModel* model) {
  const YamlNode name = m.Require("name");
  const std::optional<Effect> effect = EffectFromName(name.AsString());
  if (!effect) {
    std::vector<std::string> valid;
    for (const EffectInfo& info : EffectCatalogue()) valid.emplace_back(info.name);
    name.FailChoice(valid);
  }
  if (model->effects.Has(*effect)) name.Fail("each effect once");
  model->effects.Add(*effect);
  if (IsBoardEffect(*effect)) ReadBoardWarps(m, with_sigma, model);
  if (!IsKinematic(*effect)) return;
  const EffectInfo& info = Info(*effect);
  std::array<double, 2>& si = model->EffectValue(*effect);
  ReadNumbersInto(m.Require("si"), si.data(), info.num_params);
  std::array<double, 4>& cov = model->sigmas.effect_cov[static_cast<int>(*effect)];
  if (with_sigma) ReadCovariance2(m.Require("covariance"), &cov);
  // The report values are derived; they must still say what si says.
  const YamlNode report = m.Require("report");
  std::array<double, 2> values{0, 0};
  for (int i = 0; i < info.num_params; ++i) {
    const YamlNode p = report.Require(info.param_names[i]);
    values[i] = p.Require("value").AsDouble();
    if (with_sigma) ReadNumber(p.Require("sigma"), Number::kSigma);
    const YamlNode unit = p.Require("unit");
    if (unit.AsString() != info.report_units[i]) unit.Fail(info.report_units[i]);
  }
  const std::array<double, 2> from_report = FromReportUnits(*effect, values);
  // Relative to the effect's amplitude: a polar pair's small component may
  // carry the whole conversion error of the large one.
  const double amplitude = std::hypot(si[0], si[1]);
  for (int i = 0; i < info.num_params; ++i) {
    if (std::fabs(from_report[i] - si[i]) > kDerivedTolerance * amplitude) {
      report.Fail("report values that convert to si (predictions use si; edit both together)");
    }
  }
}

// The item of `effects` that names effect `e` (it is there: ReadEffect read it).
std::optional<YamlNode> FindEffect(const YamlNode& root, Effect e) {
  for (const YamlNode& item : root.Require("effects").Items()) {
    if (item.Require("name").AsString() == Info(e).name) return item;
  }
  return std::nullopt;
}

}  // namespace

void WriteModelYaml(const std::string& path, const InstrumentModel& model,
                    const ModelMetadata& metadata) {
  const ModelSigmas& s = model.sigmas;
  YAML::Emitter e;
  e << YAML::Comment(
      "rtscalib instrument model. Radians, metres, pixels. q = [x, y, z, w]; "
      "euler = [a, b, g] with R = Rz(g) Ry(b) Rx(a) (derived from q, for reading). "
      "Effects: si = the values predictions use, report = the same in report units.");
  e << YAML::BeginMap;
  e << YAML::Key << "format" << YAML::Value << kModelFormat;
  e << YAML::Key << "version" << YAML::Value << kModelVersion;
  e << YAML::Key << "metadata" << YAML::Value << YAML::BeginMap;
  for (const auto& [key, value] : metadata) {
    e << YAML::Key;
    EmitYamlText(e, key);
    e << YAML::Value;
    EmitYamlText(e, value);
  }
  e << YAML::EndMap;
  e << YAML::Key << "kinematics" << YAML::Value << KinematicsName(model.kinematics);
  e << YAML::Key << "edm_cyclic_unit_length" << YAML::Value
    << YamlDouble(model.edm_cyclic_unit_length);
  e << YAML::Key << "uncertainties" << YAML::Value << s.valid;
  // A camera-only model (kinematics none, SPEC 7.1) estimated no chain: no
  // base, EDM or camera tool is written as if it had been.
  const bool chain = model.kinematics != Kinematics::kNone;
  if (chain) {
    e << YAML::Key << "base" << YAML::Value;
    EmitPose(e, model.base, s.valid ? &s.base : nullptr);
    e << YAML::Key << "edm" << YAML::Value;
    EmitPose(e, model.edm, s.valid ? &s.edm : nullptr, model.edm_determined);
  }
  if (model.kinematics == Kinematics::kDh) {
    e << YAML::Key << "links" << YAML::Value << YAML::BeginSeq;
    for (int i = 0; i < 2; ++i) {
      e << YAML::Flow << YAML::BeginMap;
      for (int k = 0; k < 4; ++k) {
        e << YAML::Key << kDhParamNames[k] << YAML::Value << YamlDouble(model.links[i].p[k]);
      }
      if (s.valid) {
        e << YAML::Key << "sigma" << YAML::Value;
        EmitNamed(e, kDhParamNames, s.links[i].data(), 4);
      }
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  e << YAML::Key << "effects" << YAML::Value << YAML::BeginSeq;
  for (Effect effect : model.effects.List()) EmitEffect(e, model, effect);
  e << YAML::EndSeq;
  e << YAML::Key << "cameras" << YAML::Value << YAML::BeginSeq;
  for (int z = 0; z < model.NumZooms(); ++z) EmitCamera(e, model, z);
  e << YAML::EndSeq;
  // SPEC 7: the boards of unknown pose and the points of unknown position
  // estimated with the instrument (absent when there are none, as in files
  // written before they existed).
  if (!model.boards.empty()) {
    e << YAML::Key << "boards" << YAML::Value << YAML::BeginSeq;
    for (const EstimatedBoard& b : model.boards) {
      // The layout in targets.yaml's keys (targets_io.h), read back by ReadBoardLayout.
      e << YAML::BeginMap;
      const TagBoard& layout = b.board;
      if (layout.kind == BoardKind::kAprilTag) {
        e << YAML::Key << "family" << YAML::Value << layout.family;
      } else if (layout.kind == BoardKind::kCharuco) {
        e << YAML::Key << "type" << YAML::Value << "charuco";
        e << YAML::Key << "dictionary" << YAML::Value << layout.family;
      } else {
        e << YAML::Key << "type" << YAML::Value << "chessboard";
      }
      e << YAML::Key << "first_id" << YAML::Value << layout.first_id;
      e << YAML::Key << "rows" << YAML::Value << layout.rows;
      e << YAML::Key << "cols" << YAML::Value << layout.cols;
      if (layout.IsPointBoard()) {
        e << YAML::Key << "square_size" << YAML::Value << YamlDouble(layout.square_size);
        if (layout.kind == BoardKind::kCharuco) {
          e << YAML::Key << "marker_size" << YAML::Value << YamlDouble(layout.marker_size);
        }
      } else {
        e << YAML::Key << "tag_size" << YAML::Value << YamlDouble(layout.tag_size);
        e << YAML::Key << "spacing" << YAML::Value << YamlDouble(layout.spacing);
        if (layout.border_bits != 1) {
          e << YAML::Key << "border_bits" << YAML::Value << layout.border_bits;
        }
        if (layout.ids_from == IdOrigin::kBottomLeft) {
          e << YAML::Key << "ids_from" << YAML::Value << "bottom_left";
        }
      }
      // SPEC 7.1: the placement the pose is of, and camera-only its zoom,
      // whose camera frame is then the reference (cam_from_board).
      if (!b.placement.empty()) {
        e << YAML::Key << "placement" << YAML::Value;
        EmitYamlText(e, b.placement);
      }
      if (b.zoom >= 0) e << YAML::Key << "zoom" << YAML::Value << b.zoom;
      e << YAML::Key << (chain ? "ref_from_board" : "cam_from_board") << YAML::Value;
      EmitPose(e, b.pose, s.valid ? &b.sigma : nullptr);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  if (!model.points.empty()) {
    e << YAML::Key << "points" << YAML::Value << YAML::BeginSeq;
    for (const EstimatedPoint& p : model.points) {
      e << YAML::Flow << YAML::BeginMap;
      e << YAML::Key << "name" << YAML::Value << p.name;
      e << YAML::Key << "x" << YAML::Value;
      EmitNumbers(e, p.x.data(), 3, /*shortest=*/false);
      if (s.valid) {
        e << YAML::Key << "sigma" << YAML::Value;
        EmitNumbers(e, p.sigma.data(), 3, /*shortest=*/false);
      }
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  e << YAML::EndMap;
  if (!e.good()) throw std::logic_error("model.yaml emitter: " + e.GetLastError());

  std::ofstream out(path, std::ios::binary);
  out << e.c_str() << "\n";
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
}

InstrumentModel ReadModelYaml(const std::string& path, ModelMetadata* metadata) {
  const YamlDocument doc = YamlDocument::Load(path);
  const YamlNode root = doc.Root();
  root.RequireFormat(kModelFormat, kModelVersion);

  ModelMetadata meta;
  if (const std::optional<YamlNode> m = root.Find("metadata")) {
    for (const YamlNode::Entry& entry : m->Entries()) {
      meta.emplace_back(entry.key.AsString(), entry.value.AsString());
    }
  }

  InstrumentModel model;
  model.kinematics =
      root.Require("kinematics")
          .AsEnum<Kinematics>({{"dh", Kinematics::kDh},
                               {"spherical", Kinematics::kSpherical},
                               {"none", Kinematics::kNone}});
  const bool chain = model.kinematics != Kinematics::kNone;
  const YamlNode unit = root.Require("edm_cyclic_unit_length");
  model.edm_cyclic_unit_length = unit.AsDouble();
  if (!(model.edm_cyclic_unit_length > 0)) unit.Fail("a unit length > 0 [m]");
  const bool with_sigma = root.Require("uncertainties").AsBool();
  ModelSigmas& s = model.sigmas;
  s.valid = with_sigma;
  if (chain) {
    model.base = ReadPose(root.Require("base"), with_sigma, &s.base);
    model.edm = ReadPose(root.Require("edm"), with_sigma, &s.edm, &model.edm_determined);
  } else {
    model.edm_determined = false;  // camera-only: no EDM, base and tools the identity
  }
  if (model.kinematics == Kinematics::kDh) {
    const YamlNode links = root.Require("links");
    const std::vector<YamlNode> items = links.Items();
    if (items.size() != 2) links.Fail("2 DH links");
    for (int i = 0; i < 2; ++i) {
      ReadNamedInto(items[i], kDhParamNames, model.links[i].p.data(), 4);
      if (with_sigma) {
        ReadNamedInto(items[i].Require("sigma"), kDhParamNames, s.links[i].data(), 4,
                      Number::kSigma);
      }
    }
  }
  for (const YamlNode& item : root.Require("effects").Items()) ReadEffect(item, with_sigma, &model);

  const YamlNode cameras = root.Require("cameras");
  for (const YamlNode& item : cameras.Items()) {
    const int zoom = model.NumZooms();
    const YamlNode zoom_node = item.Require("zoom");
    if (zoom_node.AsInt() != zoom) {
      zoom_node.Fail("zoom " + std::to_string(zoom) + " (cameras are listed in zoom order)");
    }
    CameraTool cam;
    for (auto [key, value] : {std::pair<const char*, int*>{"width", &cam.width},
                              std::pair<const char*, int*>{"height", &cam.height}}) {
      const YamlNode n = item.Require(key);
      *value = n.AsInt();
      if (*value <= 0) n.Fail(std::string("an image ") + key + " > 0 [px]");
    }
    PoseSigma tool_sigma;
    cam.determined = ReadDetermined(item);
    bool tool_determined = cam.determined;
    if (chain) {
      cam.flange_from_cam =
          ReadPose(item.Require("flange_from_cam"), with_sigma, &tool_sigma, &tool_determined);
    }
    if (tool_determined != cam.determined) {
      item.Require("flange_from_cam")
          .Fail(std::string("determined: ") + (cam.determined ? "true" : "false") +
                " as the camera's (a camera is determined as a whole)");
    }
    ReadNamedInto(item.Require("intrinsics"), kIntrinsicsParamNames, cam.intrinsics.data(),
                  kNumIntrinsics);
    ReadNamedInto(item.Require("distortion"), kDistortionCoefficientNames, cam.distortion.data(),
                  kNumDistortion);
    if (const std::optional<YamlNode> held = item.Find("distortion_held")) {
      std::vector<std::string> names(std::begin(kDistortionCoefficientNames),
                                     std::end(kDistortionCoefficientNames));
      for (const YamlNode& name : held->Items()) {
        const auto it = std::find(names.begin(), names.end(), name.AsString());
        if (it == names.end()) name.FailChoice(names);
        cam.distortion_held[it - names.begin()] = true;
      }
    }
    const bool focus = model.effects.Has(Effect::kFocus);
    if (focus) {
      ReadNamedInto(item.Require("focus"), kFocusParamNames, cam.focus.data(), kNumFocus);
    }
    if (with_sigma) {
      s.cam_tools.push_back(tool_sigma);
      s.intrinsics.emplace_back();
      s.distortion.emplace_back();
      if (focus) {
        s.focus.emplace_back();
        if (cam.determined) {
          ReadNamedInto(item.Require("focus_sigma"), kFocusParamNames, s.focus.back().data(),
                        kNumFocus, Number::kSigma);
        } else {
          s.focus.back().fill(std::numeric_limits<double>::quiet_NaN());
        }
      }
      if (cam.determined) {
        ReadNamedInto(item.Require("intrinsics_sigma"), kIntrinsicsParamNames,
                      s.intrinsics.back().data(), kNumIntrinsics, Number::kSigma);
        // `held`: not estimated; 0 in memory, so that it adds no uncertainty.
        const YamlNode sigma = item.Require("distortion_sigma");
        for (int i = 0; i < kNumDistortion; ++i) {
          const YamlNode n = sigma.Require(kDistortionCoefficientNames[i]);
          s.distortion.back()[i] =
              n.IsScalar() && n.AsString() == kHeldSigma ? 0.0 : ReadNumber(n, Number::kSigma);
        }
      } else {
        s.intrinsics.back().fill(std::numeric_limits<double>::quiet_NaN());
        s.distortion.back().fill(std::numeric_limits<double>::quiet_NaN());
      }
    }
    if (const std::optional<YamlNode> region = item.Find("valid_region")) {
      for (const YamlNode& p : region->Items()) {
        const std::vector<double> uv = p.AsDoubles(2);
        cam.valid_region.emplace_back(uv[0], uv[1]);
      }
    }
    model.cams.push_back(cam);
  }
  if (const std::optional<YamlNode> boards = root.Find("boards")) {
    for (const YamlNode& item : boards->Items()) {
      EstimatedBoard b;
      b.board = ReadBoardLayout(item);  // targets.yaml's rules (targets_io.h)
      if (const std::optional<YamlNode> placement = item.Find("placement")) {
        b.placement = placement->AsString();
      }
      if (const std::optional<YamlNode> zoom = item.Find("zoom")) {
        b.zoom = zoom->AsInt();
        if (b.zoom < 0 || b.zoom >= model.NumZooms()) {
          zoom->Fail("a zoom level of the model's cameras (0.." +
                     std::to_string(model.NumZooms() - 1) + ")");
        }
      }
      b.pose = ReadPose(item.Require(chain ? "ref_from_board" : "cam_from_board"), with_sigma,
                        &b.sigma);
      b.board.ref_from_board = b.pose.ToRigid();
      b.board.pose_known = false;  // estimated, not surveyed
      model.boards.push_back(b);
    }
  }
  // board_warp: a warp for every board, and every warp of a board.
  if (model.effects.Has(Effect::kBoardWarp)) {
    const YamlNode warps = FindEffect(root, Effect::kBoardWarp)->Require("boards");
    for (const EstimatedBoard& b : model.boards) {
      if (!model.WarpOf(b.board.first_id)) {
        warps.Fail("a warp of every board in `boards` (board " +
                   std::to_string(b.board.first_id) + " has none)");
      }
    }
    const std::vector<YamlNode> items = warps.Items();
    for (size_t i = 0; i < model.board_warps.size(); ++i) {
      bool seen = false;
      for (const EstimatedBoard& b : model.boards) {
        seen = seen || b.board.first_id == model.board_warps[i].first_id;
      }
      if (!seen) {
        items[i].Require("first_id").Fail("the first_id of a board in `boards`");
      }
    }
    SyncBoardWarps(&model);
  }
  if (const std::optional<YamlNode> points = root.Find("points")) {
    for (const YamlNode& item : points->Items()) {
      EstimatedPoint p;
      p.name = item.Require("name").AsString();
      ReadNumbersInto(item.Require("x"), p.x.data(), 3);
      if (with_sigma) ReadNumbersInto(item.Require("sigma"), p.sigma.data(), 3, Number::kSigma);
      model.points.push_back(p);
    }
  }
  doc.CheckAllKeysUsed();
  if (metadata) *metadata = std::move(meta);
  return model;
}

}  // namespace rtscalib
