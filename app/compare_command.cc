// `rtscalib compare A/model.yaml B/model.yaml [--output DIR]` (docs/compare.md):
// per zoom the projection difference of the two calibrations after the best
// rotation between their camera frames, and the parameter differences with
// their combined sigmas (libcalib/api/compare.h). Prints the text; with
// --output also writes compare.txt, compare.json and figures/compare_zoomN.{vg.json, svg, png}
// there (never replacing a file that exists).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/commands.h"
#include "app/figures.h"
#include "app/heat_map_figures.h"
#include "libcalib/api/compare.h"
#include "libcalib/diagnose/statistics.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json JsonNumber(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

CalibratedInstrument LoadModel(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    throw InputError::File(path, 0, "model", "a model.yaml written by a run", "no such file");
  }
  return CalibratedInstrument::Load(path);
}

std::string Text(const CompareArgs& args, const Comparison& c) {
  std::ostringstream o;
  o << "Comparison of\n  A: " << args.a << "\n  B: " << args.b << "\n\n";
  o << "Projection difference per zoom (px, after the best rotation between the camera "
       "frames; "
    << args.cols << "x" << args.rows << " cells):\n";
  o << "  zoom      rms      max   inside: rms      max   rotation removed\n";
  for (const ZoomDifference& z : c.zooms) {
    if (!z.compared) {
      o << "  " << z.zoom << ": not determined in A or B\n";
      continue;
    }
    char row[160];
    std::snprintf(row, sizeof(row), "  %4d %8.3g %8.3g   %11.3g %8.3g   %.3g\"\n", z.zoom, z.rms_px,
                  z.max_px, z.inside_rms_px, z.inside_max_px, z.rotation_rad * 180 / M_PI * 3600);
    o << row;
  }
  o << "\nParameter differences B - A (tangent coordinates, SI units; sigma = sqrt(sigma_A^2 "
       "+ sigma_B^2), "
    << (c.full_covariance ? "from the full covariances" : "from model.yaml's sigmas") << "):\n";
  o << "  parameter                        difference        sigma   normalised\n";
  for (const ParameterDifference& p : c.parameters) {
    if (!p.has_sigma && p.difference == 0) continue;  // held in both, equal
    char row[200];
    const std::string name = p.block + "[" + std::to_string(p.index) + "]";
    if (p.has_sigma) {
      std::snprintf(row, sizeof(row), "  %-28s %14.6g %12.4g %12.3f\n", name.c_str(), p.difference,
                    p.sigma, p.normalised);
    } else {
      std::snprintf(row, sizeof(row), "  %-28s %14.6g %12s %12s\n", name.c_str(), p.difference,
                    "held", "-");
    }
    o << row;
  }
  o << "\nMean square of the normalised differences: " << Fmt("%.3g", c.mean_square_normalised)
    << " over " << c.num_normalised
    << " parameters (about 1 for two fits of one instrument whose sigmas are right)\n";
  if (c.effective_parameters > 0) {
    // Correlated differences: chi^2_nu / nu (libcalib/api/compare.h).
    const double nu = c.effective_parameters;
    o << "  correlated as they are, they count as " << Fmt("%.3g", nu)
      << " independent ones: for right sigmas the mean square lies between "
      << Fmt("%.2g", ChiSquareCritical(0.995, nu) / nu) << " and "
      << Fmt("%.3g", ChiSquareCritical(0.005, nu) / nu) << " (99 %)\n";
  }
  for (const std::string& n : c.notes) o << "note: " << n << "\n";
  return o.str();
}

json Json(const CompareArgs& args, const Comparison& c) {
  json zooms = json::array();
  for (const ZoomDifference& z : c.zooms) {
    json cells = json::array();
    for (double x : z.diff_px) cells.push_back(JsonNumber(x));
    zooms.push_back({{"zoom", z.zoom},
                     {"compared", z.compared},
                     {"rms_px", JsonNumber(z.rms_px)},
                     {"max_px", JsonNumber(z.max_px)},
                     {"inside_rms_px", JsonNumber(z.inside_rms_px)},
                     {"inside_max_px", JsonNumber(z.inside_max_px)},
                     {"rotation_rad", z.rotation_rad},
                     {"fit_cells", z.fit_cells},
                     {"cells", {z.cols, z.rows}},
                     {"diff_px", cells},
                     {"inside", std::vector<int>(z.inside.begin(), z.inside.end())}});
  }
  json params = json::array();
  for (const ParameterDifference& p : c.parameters) {
    params.push_back({{"block", p.block},
                      {"index", p.index},
                      {"unit", p.unit},
                      {"a", p.a},
                      {"b", p.b},
                      {"difference", p.difference},
                      {"sigma", p.has_sigma ? json(p.sigma) : json(nullptr)},
                      {"normalised", p.has_sigma ? json(p.normalised) : json(nullptr)}});
  }
  return {{"a", args.a},
          {"b", args.b},
          {"full_covariance", c.full_covariance},
          {"zooms", zooms},
          {"parameters", params},
          {"mean_square_normalised", c.mean_square_normalised},
          {"effective_parameters", c.effective_parameters},
          {"num_normalised", c.num_normalised},
          {"notes", c.notes}};
}

}  // namespace

int RunCompare(const CompareArgs& args) {
  const CalibratedInstrument a = LoadModel(args.a);
  const CalibratedInstrument b = LoadModel(args.b);
  // What makes two models incomparable is named on the second file.
  if (a.NumZooms() != b.NumZooms()) {
    throw InputError::File(args.b, 0, "zoom levels",
                           std::to_string(a.NumZooms()) + " zoom level(s) as " + args.a + " has",
                           std::to_string(b.NumZooms()));
  }
  for (int z = 0; z < a.NumZooms(); ++z) {
    if (a.ImageWidth(z) != b.ImageWidth(z) || a.ImageHeight(z) != b.ImageHeight(z)) {
      throw InputError::File(
          args.b, 0, "image size of zoom " + std::to_string(z),
          std::to_string(a.ImageWidth(z)) + "x" + std::to_string(a.ImageHeight(z)) + " as in " +
              args.a,
          std::to_string(b.ImageWidth(z)) + "x" + std::to_string(b.ImageHeight(z)));
    }
  }
  CompareOptions o;
  o.cols = args.cols;
  o.rows = args.rows;
  const Comparison c = CompareInstruments(a, b, o);
  const std::string text = Text(args, c);
  if (!args.output.empty()) {
    const fs::path dir(args.output);
    std::vector<Figure> figs;
    for (const ZoomDifference& z : c.zooms) {
      if (z.compared) figs.push_back(DifferenceFigure(z));
    }
    std::vector<fs::path> files = {dir / "compare.txt", dir / "compare.json"};
    for (const Figure& f : figs) {
      for (const char* ext : {".vg.json", ".svg", ".png"})
        files.push_back(dir / "figures" / (f.name + ext));
    }
    for (const fs::path& f : files) {
      std::error_code ec;
      if (fs::exists(f, ec)) {
        throw std::invalid_argument("compare --output: '" + f.string() +
                                    "' exists; rtscalib does not overwrite files you have");
      }
    }
    std::string note;
    WriteFigureFiles(figs, (dir / "figures").string(), &note);
    if (!note.empty()) std::cerr << "rtscalib compare: " << note << "\n";
    WriteFileAtomic((dir / "compare.json").string(), Json(args, c).dump(2) + "\n", Existing::kKeep);
    WriteFileAtomic((dir / "compare.txt").string(), text, Existing::kKeep);
  }
  std::cout << text;
  if (!args.output.empty())
    std::cout << "written: " << args.output << "/{compare.txt, compare.json, figures/}\n";
  return 0;
}

}  // namespace rtscalib::app
