#include "app/figures.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <future>
#include <map>
#include <set>
#include <string_view>

#include "app/heat_map_figures.h"
#include "app/ladder_figures.h"
#include "app/photo_figure.h"
#include "app/residual_figures.h"
#include "app/vega.h"
#include "libcalib/io/safe_write.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Photos shown per zoom, worst first (rms of their fitted corners).
constexpr int kWorstPhotosPerZoom = 2;

}  // namespace

std::vector<Figure> MakeFigures(const PipelineResult& r, const json& history) {
  std::vector<Figure> figs;
  const CalibrationResult& c = r.calibration;
  const std::vector<ObservationResidual>& rows = c.residuals;

  // This run's stepwise ladder.
  if (c.ladder.size() > 1) {
    std::vector<Rung> rungs;
    for (size_t i = 0; i < c.ladder.size(); ++i) {
      const LadderStep& s = c.ladder[i];
      rungs.push_back(
          {"step " + std::to_string(i) + ": " + (s.added.empty() ? "start" : "+" + s.added),
           s.rms.edm_n ? s.rms.edm_m * 1e3 : NAN, s.rms.cam_n ? s.rms.cam_m * 1e3 : NAN,
           s.rms.pixels_n ? s.rms.pixels_px : NAN});
    }
    figs.push_back(LadderFigure(rungs, "ladder_stepwise",
                                "The ladder of this run (diagnose --auto)",
                                "Error of the fitted rows after each effect the forward stepwise "
                                "search added (rtscalib diagnose --auto)."));
  }
  // Across runs: earlier complete runs of this output folder, then this one.
  if (history.is_array() && !history.empty()) {
    const FinalErrors& e = c.final_errors;
    const json final = {{"records",
                         {{"edm", {{"rms_m", e.edm.rms_m}, {"n", e.edm.n}}},
                          {"cam", {{"rms_m", e.cam.rms_m}, {"n", e.cam.n}}}}},
                        {"pixels", {{"rms_px", e.pixels.rms_px}, {"n", e.pixels.n}}}};
    figs.push_back(RunsLadderFigure(history, c.model.effects.Names(), final));
  }

  // Maps per tool.
  std::set<int> faces, cam_zooms, pixel_zooms;
  bool edm = false;
  for (const ObservationResidual& o : rows) {
    if (!o.valid || o.status == ResidualStatus::kGrossError) continue;
    faces.insert(o.face);
    if (o.group == ObsGroup::kEdm) edm = true;
    if (o.group == ObsGroup::kCam) cam_zooms.insert(o.zoom);
    if (o.group == ObsGroup::kPixel && o.zoom < c.model.NumZooms()) pixel_zooms.insert(o.zoom);
  }
  std::set<int> pixel_zooms_mapped = pixel_zooms;
  const std::string model = KinematicsName(c.model.kinematics) + std::string(", effects: [") + [&] {
    std::string s;
    for (const std::string& n : c.model.effects.Names()) s += (s.empty() ? "" : ", ") + n;
    return s;
  }() + "]";
  // A camera-only calibration (kinematics none) has no pointings to map.
  if (c.model.kinematics == Kinematics::kNone) pixel_zooms_mapped.clear();
  if (edm) {
    figs.push_back(ErrorMap({"edm", "EDM points", "mm", 1e3, ObsGroup::kEdm, 0}, rows, faces,
                            c.fit_options, model));
  }
  for (int z : cam_zooms) {
    figs.push_back(
        ErrorMap({"cam_zoom" + std::to_string(z), "Camera points, zoom " + std::to_string(z), "mm",
                  1e3, ObsGroup::kCam, z},
                 rows, faces, c.fit_options, model));
  }
  for (int z : pixel_zooms_mapped) {
    figs.push_back(
        ErrorMap({"pixels_zoom" + std::to_string(z), "Image points, zoom " + std::to_string(z),
                  "px", 1.0, ObsGroup::kPixel, z},
                 rows, faces, c.fit_options, model));
  }

  // The image: binned residuals per zoom, then the worst photos.
  std::set<int> image_zooms = pixel_zooms;
  image_zooms.insert(cam_zooms.begin(), cam_zooms.end());
  for (int z : image_zooms) {
    if (z < c.model.NumZooms()) figs.push_back(ImageResiduals(z, c.model.cams[z], rows));
  }
  std::map<std::string, std::vector<ObservationResidual>> by_shot;
  for (const ObservationResidual& o : rows) {
    if (o.group == ObsGroup::kPixel && !o.shot.empty()) by_shot[o.shot].push_back(o);
  }
  std::map<int, std::vector<std::pair<double, std::string>>> worst;  // zoom -> (rms, shot)
  for (const auto& [shot, shot_rows] : by_shot) {
    double ss = 0;
    int n = 0;
    for (const ObservationResidual& o : shot_rows) {
      if (!Fitted(o)) continue;
      ss += o.size * o.size;
      ++n;
    }
    if (n > 0) worst[shot_rows.front().zoom].push_back({std::sqrt(ss / n), shot});
  }
  const std::map<std::string, std::string> files = PhotoFiles(r.photos);
  for (auto& [z, shots] : worst) {
    if (z >= c.model.NumZooms()) continue;
    std::sort(shots.rbegin(), shots.rend());
    for (size_t k = 0; k < shots.size() && k < kWorstPhotosPerZoom; ++k) {
      const auto file = files.find(shots[k].second);
      figs.push_back(PhotoFigure(shots[k].second, by_shot[shots[k].second],
                                 file == files.end() ? "" : file->second, c.model.cams[z].width,
                                 c.model.cams[z].height));
    }
  }
  figs.push_back(VariablesFigure(rows));
  figs.push_back(Histograms(rows));
  for (const UncertaintyMap& m : r.uncertainty_maps) {
    if (m.determined) {
      figs.push_back(
          UncertaintyFigure(m, r.uncertainty_options, c.model.cams[m.zoom], r.full_covariance));
    }
  }
  return figs;
}

std::vector<std::vector<std::string>> WriteFigureFiles(const std::vector<Figure>& figures,
                                                       const std::string& dir, std::string* note,
                                                       VegaRenderer* renderer) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw WriteError(dir, ec.message() + " (creating the folder)");
  std::vector<json> specs;
  for (const Figure& f : figures) specs.push_back(f.spec);
  // The specs go to node first; the .vg.json files are written while it
  // draws, and each figure's SVG and PNG as soon as its PNG is drawn: a
  // checked write waits for the disk (its fsync, about a millisecond a file
  // here), beside the drawing rather than after it.
  std::future<void> written_specs = std::async(std::launch::async, [&] {
    for (const Figure& f : figures) {
      WriteFileAtomic((fs::path(dir) / (f.name + ".vg.json")).string(), f.spec.dump() + "\n");
    }
  });
  const VegaRenderer::Drawn write = [&](size_t i, const RenderedFigure& fig) {
    WriteFileAtomic((fs::path(dir) / (figures[i].name + ".svg")).string(), fig.svg);
    WriteFileAtomic(
        (fs::path(dir) / (figures[i].name + ".png")).string(),
        std::string_view(reinterpret_cast<const char*>(fig.png.data()), fig.png.size()));
  };
  note->clear();
  const std::vector<RenderedFigure> drawn = renderer != nullptr
                                                ? renderer->Draw(specs, note, write)
                                                : RenderFigures(specs, note, write);
  written_specs.get();
  std::vector<std::vector<std::string>> written(figures.size());
  for (size_t i = 0; i < figures.size(); ++i) {
    written[i].push_back(figures[i].name + ".vg.json");
    if (i >= drawn.size()) continue;
    if (drawn[i].png.empty()) {
      *note += std::string(note->empty() ? "figures: " : "; ") + figures[i].name +
               " has no SVG or PNG (" + drawn[i].error + ")";
      continue;
    }
    written[i].push_back(figures[i].name + ".svg");
    written[i].push_back(figures[i].name + ".png");
  }
  return written;
}

}  // namespace rtscalib::app
