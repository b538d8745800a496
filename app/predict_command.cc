#include <filesystem>
#include <iostream>

#include "app/commands.h"
#include "app/safe_write.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"
#include "libcalib/model/kinematics.h"

namespace rtscalib::app {

// SPEC 5: writes IN's rows with x, y, z (records) or u, v (pixels) replaced by
// the model's prediction.
int RunPredict(const PredictArgs& args) {
  if (args.records.empty() == args.pixels.empty()) {
    throw std::invalid_argument("predict: give exactly one of --records or --pixels");
  }
  if (std::filesystem::exists(args.out) && !args.force) {
    throw std::invalid_argument(
        "predict: '" + args.out +
        "' exists; rtscalib does not overwrite files you have (use --force)");
  }
  // kKeep also covers a file that appears while predicting.
  const Existing existing = args.force ? Existing::kReplace : Existing::kKeep;
  const InstrumentModel model = ReadModelYaml(args.model);
  if (!args.records.empty()) {
    RecordsFile in = ReadRecords(args.records);
    for (Record& r : in.records) {
      if (r.tool == Tool::kCam && r.zoom >= model.NumZooms()) {
        throw std::invalid_argument(
            args.records + ":" + std::to_string(r.line) + ": column 'zoom': the model has " +
            std::to_string(model.NumZooms()) + " zoom level(s), got " + std::to_string(r.zoom));
      }
      RequireDeterminedTool(model, r.tool, r.zoom, args.records, r.line);
      r.x = r.tool == Tool::kEdm ? PredictEdm(model, r.phi, r.theta, r.d)
                                 : PredictCam(model, r.zoom, r.phi, r.theta, r.u, r.v, r.d);
    }
    WriteFileAtomicWith(
        args.out, [&](const std::string& tmp) { WriteRecords(tmp, in.records); }, existing);
    std::cerr << "predict: " << in.records.size() << " records -> " << args.out << "\n";
    return 0;
  }
  PixelsFile in = ReadPixels(args.pixels);
  int behind = 0;
  for (PixelObservation& p : in.pixels) {
    if (p.zoom >= model.NumZooms()) {
      throw std::invalid_argument(
          args.pixels + ":" + std::to_string(p.line) + ": column 'zoom': the model has " +
          std::to_string(model.NumZooms()) + " zoom level(s), got " + std::to_string(p.zoom));
    }
    RequireDeterminedTool(model, Tool::kCam, p.zoom, args.pixels, p.line);
    Eigen::Vector2d uv;
    if (!PredictPixel(model, p.zoom, p.phi, p.theta, p.X, &uv)) {
      ++behind;
      uv.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    p.uv = uv;
  }
  WriteFileAtomicWith(
      args.out, [&](const std::string& tmp) { WritePixels(tmp, in.pixels); }, existing);
  std::cerr << "predict: " << in.pixels.size() << " pixel rows -> " << args.out;
  if (behind) std::cerr << " (" << behind << " points behind the camera written as nan)";
  std::cerr << "\n";
  return 0;
}

}  // namespace rtscalib::app
