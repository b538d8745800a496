#include "app/figures.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <set>
#include <string_view>

#include "app/heat_map_figures.h"
#include "app/ladder_figures.h"
#include "app/photo_figure.h"
#include "app/plot/vega.h"
#include "app/residual_figures.h"
#include "libcalib/io/safe_write.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Photos shown per zoom, worst first (rms of their fitted corners).
constexpr int kWorstPhotosPerZoom = 2;

}  // namespace

void MakeFigures(const PipelineResult& r, const json& history,
                 const std::function<void(Figure)>& made) {
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
    made(LadderFigure(rungs, "ladder_stepwise",
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
    made(RunsLadderFigure(history, c.model.effects.Names(), final));
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
    made(ErrorMap({"edm", "EDM points", "mm", 1e3, ObsGroup::kEdm, 0}, rows, faces,
                            c.fit_options, model));
  }
  for (int z : cam_zooms) {
    made(
        ErrorMap({"cam_zoom" + std::to_string(z), "Camera points, zoom " + std::to_string(z), "mm",
                  1e3, ObsGroup::kCam, z},
                 rows, faces, c.fit_options, model));
  }
  for (int z : pixel_zooms_mapped) {
    made(
        ErrorMap({"pixels_zoom" + std::to_string(z), "Image points, zoom " + std::to_string(z),
                  "px", 1.0, ObsGroup::kPixel, z},
                 rows, faces, c.fit_options, model));
  }

  // The image: binned residuals per zoom, then the worst photos.
  std::set<int> image_zooms = pixel_zooms;
  image_zooms.insert(cam_zooms.begin(), cam_zooms.end());
  for (int z : image_zooms) {
    if (z < c.model.NumZooms()) made(ImageResiduals(z, c.model.cams[z], rows));
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
      made(PhotoFigure(shots[k].second, by_shot[shots[k].second],
                                 file == files.end() ? "" : file->second, c.model.cams[z].width,
                                 c.model.cams[z].height));
    }
  }
  made(VariablesFigure(rows));
  made(Histograms(rows));
}

std::vector<Figure> MakeFigures(const PipelineResult& r, const json& history) {
  std::vector<Figure> figs;
  MakeFigures(r, history, [&](Figure f) { figs.push_back(std::move(f)); });
  for (Figure& f : MakeUncertaintyFigures(r)) figs.push_back(std::move(f));
  return figs;
}

std::vector<Figure> MakeUncertaintyFigures(const PipelineResult& r) {
  std::vector<Figure> figs;
  for (const UncertaintyMap& m : r.uncertainty_maps) {
    if (m.determined) {
      figs.push_back(UncertaintyFigure(m, r.uncertainty_options, r.calibration.model.cams[m.zoom],
                                       r.full_covariance));
    }
  }
  return figs;
}

FigureFiles::FigureFiles(std::string dir, VegaRenderer* renderer) : dir_(std::move(dir)) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw WriteError(dir_, ec.message() + " (creating the folder)");
  if (renderer == nullptr) own_ = std::make_unique<VegaRenderer>();
  renderer_ = renderer != nullptr ? renderer : own_.get();
  // The drawings are collected on a thread of their own from now on; each
  // figure's files are written on the thread that drew its PNG, while the
  // next figures are made and drawn.
  drawing_ = std::async(std::launch::async, [this] {
    std::vector<RenderedFigure> drawn = renderer_->Collect(
        &note_, [this](size_t i, const RenderedFigure& fig) { Write(i, &fig); });
    drawn_at_ = std::chrono::steady_clock::now();
    return drawn;
  });
}

FigureFiles::~FigureFiles() {
  if (!drawing_.valid()) return;
  renderer_->End();
  drawing_.wait();
}

void FigureFiles::Add(size_t index, Figure figure) {
  std::string text = figure.spec.dump();
  const nlohmann::json* spec = nullptr;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto [at, added] = figures_.emplace(index, std::make_pair(std::move(figure), text));
    if (!added) throw std::logic_error("FigureFiles: figure " + std::to_string(index) + " twice");
    spec = &at->second.first.spec;  // stays in the map's node until Finish
  }
  renderer_->Add(index, *spec);
}

void FigureFiles::End() { renderer_->End(); }

// The spec's file, and with a drawing its SVG and PNG: a checked write
// waits for the disk (its fsync, about a millisecond a file here), beside
// the drawing rather than after it.
void FigureFiles::Write(size_t index, const RenderedFigure* drawn) {
  const std::pair<Figure, std::string>* f = nullptr;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    f = &figures_.at(index);
    if (!spec_written_.insert(index).second) f = nullptr;
  }
  if (f == nullptr) return;
  const fs::path base = fs::path(dir_) / f->first.name;
  WriteFileAtomic(base.string() + ".vg.json", f->second + "\n");
  if (drawn == nullptr) return;
  WriteFileAtomic(base.string() + ".svg", drawn->svg);
  // No PNG without librsvg, or when librsvg refused the SVG.
  if (drawn->png.empty()) return;
  WriteFileAtomic(base.string() + ".png",
                  std::string_view(reinterpret_cast<const char*>(drawn->png.data()),
                                   drawn->png.size()));
}

std::vector<std::vector<std::string>> FigureFiles::Finish(std::string* note,
                                                          std::vector<Figure>* figures) {
  renderer_->End();
  const std::vector<RenderedFigure> drawn = drawing_.get();
  *note = note_;
  std::vector<std::vector<std::string>> written;
  figures->clear();
  for (auto& [i, f] : figures_) {
    if (i != figures->size()) throw std::logic_error("FigureFiles: no figure " +
                                                     std::to_string(figures->size()));
    // The specs of figures that were not drawn.
    Write(i, nullptr);
    written.push_back({f.first.name + ".vg.json"});
    if (i < drawn.size()) {
      const RenderedFigure& d = drawn[i];
      if (!d.svg.empty()) written.back().push_back(f.first.name + ".svg");
      if (!d.png.empty()) written.back().push_back(f.first.name + ".png");
      // A missing librsvg is said once, in the renderer's note; a figure
      // that could not be drawn, or whose PNG librsvg refused, by name.
      if (d.svg.empty() || !d.error.empty()) {
        *note += std::string(note->empty() ? "figures: " : "; ") + f.first.name + " has no " +
                 (d.svg.empty() ? "SVG or PNG" : "PNG") + " (" + d.error + ")";
      }
    }
    figures->push_back(std::move(f.first));
  }
  return written;
}

std::vector<std::vector<std::string>> WriteFigureFiles(const std::vector<Figure>& figures,
                                                       const std::string& dir, std::string* note,
                                                       VegaRenderer* renderer) {
  FigureFiles files(dir, renderer);
  std::vector<size_t> bytes;
  for (const Figure& f : figures) bytes.push_back(f.spec.dump().size());
  for (size_t i : LargestFirst(bytes)) files.Add(i, figures[i]);
  std::vector<Figure> added;
  return files.Finish(note, &added);
}

}  // namespace rtscalib::app
