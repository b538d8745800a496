#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "app/commands.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/export/opencv_export.h"
#include "libcalib/export/surveyor_export.h"
#include "libcalib/export/urdf_export.h"
#include "libcalib/text/errors.h"
#include "libcalib/io/model_io.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw WriteError(path.string(), "the output stream failed");
}

}  // namespace

// Writes one export format of a model into --out (docs/exports.md). Every
// target file is checked before anything is written, so a refusal leaves the
// folder as it was.
int RunExport(const ExportArgs& args) {
  const InstrumentModel model = ReadModelYaml(args.model);
  const fs::path dir =
      args.out.empty() ? fs::absolute(args.model).parent_path() / "export" : fs::path(args.out);

  std::vector<fs::path> files;
  if (args.format == "opencv") {
    if (model.NumZooms() == 0) {
      throw std::invalid_argument("export: " + args.model + " has no cameras to export");
    }
    for (int z = 0; z < model.NumZooms(); ++z) {
      files.push_back(dir / OpenCvCameraFileName(z));
    }
  } else if (model.kinematics == Kinematics::kNone &&
             (args.format == "urdf" || args.format == "surveyor")) {
    throw std::invalid_argument("export: " + args.model +
                                " is a camera-only calibration (kinematics: none): it has no "
                                "kinematic chain or surveyor's constants; --format opencv "
                                "exports its cameras");
  } else if (args.format == "urdf") {
    files.push_back(dir / "instrument.urdf");
  } else if (args.format == "surveyor") {
    files.push_back(dir / "surveyor.txt");
    files.push_back(dir / "surveyor.json");
  } else {
    throw std::invalid_argument("export: --format must be opencv, urdf or surveyor, got '" +
                                args.format + "'");
  }
  std::string existing;
  for (const fs::path& f : files) {
    if (fs::exists(f)) existing += (existing.empty() ? "" : ", ") + f.string();
  }
  if (!existing.empty() && !args.force) {
    // The user's files are in the way: an input error (exit 1).
    throw InputError::File(existing, 0, "export",
                           "no file under these names (rtscalib does not overwrite files you "
                           "have; use --force)",
                           "existing file(s)");
  }
  fs::create_directories(dir);

  std::ostream& out = std::cout;
  if (args.format == "opencv") {
    for (int z = 0; z < model.NumZooms(); ++z) {
      WriteOpenCvCamera(files[z].string(), model, z);
      const CameraTool& cam = model.cams[z];
      out << "zoom " << z << ": " << files[z].string() << " (" << cam.width << "x" << cam.height
          << " px from model.yaml, " << OpenCvDistortionCount(model, z)
          << " distortion coefficients)\n";
      if (model.effects.Has(Effect::kFocus)) {
        out << "  focus (SPEC 4.1): camera_matrix is focused at infinity; the file holds "
               "focus_kf, focus_au, focus_av for fx (1 + kf/D), cx + au/D, cy + av/D at focus "
               "distance D\n";
      }
      // An extraction without given intrinsics sets the size from the
      // principal point (2 c + 1); flag it so that nobody mistakes it for the sensor's.
      if (cam.width == std::lround(2.0 * cam.intrinsics[2] + 1.0) &&
          cam.height == std::lround(2.0 * cam.intrinsics[3] + 1.0)) {
        out << "  note: the image size equals 2 * principal point + 1; it may have been "
               "estimated, not measured: check it against the sensor\n";
      }
    }
  } else if (args.format == "urdf") {
    UrdfOptions options;
    options.source = args.model;
    const UrdfExport urdf = ExportUrdf(model, options);
    WriteText(files[0], urdf.xml);
    out << "urdf: " << files[0].string() << " (" << KinematicsName(model.kinematics)
        << " kinematics; links " << kUrdfReferenceLink << ", " << kUrdfAlidadeLink << ", "
        << kUrdfTelescopeLink << ", " << kUrdfEdmLink << ", camera_zoom0.." << model.NumZooms() - 1
        << ")\n";
    out << "folded in exactly:" << (urdf.folded.empty() ? " nothing" : "") << "\n";
    for (const std::string& s : urdf.folded) out << "  " << s << "\n";
    out << "not held by the URDF (listed in its header comment):"
        << (urdf.not_held.empty() ? " nothing" : "") << "\n";
    for (const std::string& s : urdf.not_held) out << "  " << s << "\n";
  } else {
    const SurveyorConstants c = ComputeSurveyorConstants(model);
    const std::string text = SurveyorText(c);
    WriteText(files[0], text);
    WriteText(files[1], SurveyorJson(c));
    out << text << "\nsurveyor: " << files[0].string() << ", " << files[1].string() << "\n";
  }
  return 0;
}

}  // namespace rtscalib::app
