#include <filesystem>
#include <iostream>
#include <vector>

#include "app/commands.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/api/rtscalib.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"
#include "libcalib/io/records.h"

namespace rtscalib::app {

namespace {

// How many skipped rows --skip-bad names on stderr; the count is always given.
constexpr size_t kNamedSkippedRows = 20;

// A row the model cannot predict, as an error naming file, line and the
// columns that made it so.
InputError RowError(const std::string& file, int line, const PredictionError& e, bool pixels) {
  switch (e.failure) {
    case PredictionFailure::kNoSuchZoom:
      return InputError::Cell(file, line, "zoom", e.expected, e.got);
    case PredictionFailure::kNotDetermined:
      // The EDM tool is named by the row's tool, a camera by its zoom.
      return InputError::Cell(file, line, e.got == "edm" ? "tool" : "zoom", e.expected, e.got);
    case PredictionFailure::kOutsideImage:
      // A records row's u, v are input; a pixels row's u, v are the projection of X, Y, Z.
      return InputError::File(file, line, pixels ? "columns X, Y, Z" : "columns u, v", e.expected,
                              e.got);
    case PredictionFailure::kUntrustedPixel:
      return InputError::File(file, line, "columns u, v", e.expected, e.got);
    case PredictionFailure::kBehindCamera:
    case PredictionFailure::kUntrustedPoint:
      return InputError::File(file, line, "columns X, Y, Z", e.expected, e.got);
    case PredictionFailure::kNoSuchBoard:
      return InputError::File(file, line, "columns target, corner, placement", e.expected, e.got);
    case PredictionFailure::kNonFinite:
      break;
  }
  return InputError::File(file, line, "row", e.expected, e.got);
}

// Collects the rows that cannot be predicted: the first one stops the command
// unless --skip-bad, which keeps going and reports them at the end.
class BadRows {
 public:
  BadRows(std::string file, bool skip, bool pixels)
      : file_(std::move(file)), skip_(skip), pixels_(pixels) {}

  // Throws without --skip-bad; otherwise the row is left out.
  void Add(int line, const PredictionError& e) {
    InputError error = RowError(file_, line, e, pixels_);
    if (!skip_) {
      std::cerr << "predict: (--skip-bad writes the other rows and lists the skipped ones)\n";
      throw error;
    }
    errors_.push_back(std::move(error));
  }

  void Report(size_t total) const {
    if (errors_.empty()) return;
    std::cerr << "predict: skipped " << errors_.size() << " of " << total
              << " rows the model cannot predict";
    if (errors_.size() > kNamedSkippedRows) std::cerr << " (the first " << kNamedSkippedRows << ")";
    std::cerr << ":\n";
    for (size_t i = 0; i < errors_.size() && i < kNamedSkippedRows; ++i) {
      std::cerr << "  " << errors_[i].what() << "\n";
    }
  }

 private:
  std::string file_;
  bool skip_;
  bool pixels_;
  std::vector<InputError> errors_;
};

}  // namespace

// SPEC 5: writes IN's rows with x, y, z (records) or u, v (pixels) replaced by
// the model's prediction. A row the model cannot predict (libcalib/api/rtscalib.h:
// no such zoom, pixel outside the image, point behind the camera, non-finite
// result) is an error naming its file and line; with --skip-bad it is left out
// of OUT and listed on stderr.
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
  const AngleUnit unit = AngleUnitArg("predict", args.angle_unit);
  const CalibratedInstrument instrument = CalibratedInstrument::Load(args.model);
  if (!args.records.empty()) {
    RecordsFile in = ReadRecords(args.records, unit);
    BadRows bad(args.records, args.skip_bad, false);
    std::vector<Record> out;
    out.reserve(in.records.size());
    for (Record& r : in.records) {
      try {
        r.x = r.tool == Tool::kEdm ? instrument.EdmPoint(r.phi, r.theta, r.d)
                                   : instrument.CameraPoint(r.zoom, r.phi, r.theta, r.u, r.v, r.d);
        out.push_back(r);
      } catch (const PredictionError& e) {
        bad.Add(r.line, e);
      }
    }
    WriteFileAtomicWith(
        args.out, [&](const std::string& tmp) { WriteRecords(tmp, out, unit, in.covariates); },
        existing);
    bad.Report(in.records.size());
    std::cerr << "predict: " << out.size() << " records -> " << args.out << "\n";
    return 0;
  }
  PixelsFile in = ReadPixels(args.pixels, unit);
  BadRows bad(args.pixels, args.skip_bad, true);
  std::vector<PixelObservation> out;
  out.reserve(in.pixels.size());
  // SPEC 4.1: each photo's D, its focus_distance or the centroid of its
  // points as the model places them (zeros without the focus effect).
  const std::vector<double> focus = PredictionFocusDistances(instrument.Model(), in.pixels);
  for (size_t i = 0; i < in.pixels.size(); ++i) {
    PixelObservation& p = in.pixels[i];
    try {
      // SPEC 7: empty X, Y, Z = a corner of a board the model estimated, as
      // it stood in the row's placement (SPEC 7.1).
      p.uv = p.X_known ? instrument.Pixel(p.zoom, p.phi, p.theta, p.X, focus[i])
                       : instrument.BoardCornerPixel(p.zoom, p.phi, p.theta, p.target, p.corner,
                                                     p.placement, focus[i]);
      out.push_back(p);
    } catch (const PredictionError& e) {
      bad.Add(p.line, e);
    }
  }
  WriteFileAtomicWith(
      args.out,
      [&](const std::string& tmp) {
        WritePixels(tmp, out, unit, in.image_sizes, in.covariates);
      },
      existing);
  bad.Report(in.pixels.size());
  std::cerr << "predict: " << out.size() << " pixel rows -> " << args.out << "\n";
  return 0;
}

}  // namespace rtscalib::app
