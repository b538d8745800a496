// `rtscalib show --output OUT --shot ID [--out DIR]`: one photo of a run
// with its observed corners and scaled residual arrows (app/photo_figure.h
// PhotoFigure), from the run's own files: residuals.csv (the residual
// table at the final model) and report.json (where the photos are, the image
// sizes). Nothing is predicted again.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "app/commands.h"
#include "app/figures.h"
#include "app/photo_figure.h"
#include "app/report_html.h"
#include "libcalib/io/safe_write.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;

// One CSV line into fields (RFC 4180 quotes, as ResidualsCsv writes them).
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

nlohmann::json ReadJson(const fs::path& p) {
  std::ifstream in(p);
  if (!in) {
    throw InputError::File(p.string(), 0, "the run's report",
                           "report.json of a run (is --output a run's output folder?)",
                           "no readable file");
  }
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw InputError::File(p.string(), 0, "contents", "JSON", e.what());
  }
}

}  // namespace

int RunShow(const ShowArgs& args) {
  const fs::path root(args.output);
  const nlohmann::json report = ReadJson(root / "report.json");
  const fs::path csv = root / "residuals.csv";
  std::ifstream in(csv);
  if (!in) {
    throw InputError::File(csv.string(), 0, "the run's residual table",
                           "residuals.csv beside report.json", "no readable file");
  }
  std::string line;
  std::map<std::string, size_t> col;
  std::vector<ObservationResidual> rows;
  std::map<std::string, int> shots;  // every shot, for the message when ID is not one
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> f = SplitCsv(line);
    if (col.empty()) {
      for (size_t i = 0; i < f.size(); ++i) col[f[i]] = i;
      for (const char* need : {"kind", "shot", "zoom", "face", "status", "obs_x", "obs_y", "res_x",
                               "res_y", "normalised", "target", "corner", "line"}) {
        if (!col.count(need)) {
          throw InputError::File(csv.string(), line_no, "header", std::string("column ") + need,
                                 "none");
        }
      }
      continue;
    }
    auto get = [&](const char* name) -> const std::string& { return f.at(col.at(name)); };
    if (f.size() < col.size() || get("kind") != "pixel") continue;
    ++shots[get("shot")];
    if (get("shot") != args.shot) continue;
    auto number = [&](const char* name) {
      const std::optional<double> v = ParseFiniteDouble(get(name));
      if (!v) throw InputError::Cell(csv.string(), line_no, name, "a number", get(name));
      return *v;
    };
    ObservationResidual o;
    o.group = ObsGroup::kPixel;
    o.shot = args.shot;
    o.zoom = static_cast<int>(number("zoom"));
    o.face = static_cast<int>(number("face"));
    o.target = static_cast<int>(number("target"));
    o.corner = static_cast<int>(number("corner"));
    o.line = static_cast<int>(number("line"));
    o.u = number("obs_x");
    o.v = number("obs_y");
    for (ResidualStatus s : {ResidualStatus::kFitted, ResidualStatus::kCriticalRegion,
                             ResidualStatus::kGrossError, ResidualStatus::kNotPredicted}) {
      if (get("status") == ResidualStatusName(s)) o.status = s;
    }
    o.valid = !get("res_x").empty();
    if (o.valid) {
      o.delta = Eigen::Vector3d(number("res_x"), number("res_y"), 0.0);
      o.size = o.delta.norm();
      o.normalised = number("normalised");
    }
    rows.push_back(o);
  }
  if (rows.empty()) {
    std::string known;
    int listed = 0;
    for (const auto& [s, n] : shots) {
      if (listed++ == 12) {
        known += ", ...";
        break;
      }
      known += (known.empty() ? "" : ", ") + s;
    }
    throw InputError::File(
        csv.string(), 0, "--shot",
        known.empty() ? "a shot of the run (the run has no photos)" : "a shot of the run: " + known,
        args.shot);
  }
  // Where the photo is, and the size of its zoom's images.
  PhotoSessionSummary photos;
  if (report.contains("photos")) {
    photos.shots_path = report["photos"].value("shots", std::string());
    for (const nlohmann::json& p : report["photos"].value("per_photo", nlohmann::json::array())) {
      PhotoSessionSummary::Photo ph;
      ph.shot = p.value("shot", std::string());
      ph.image = p.value("image", std::string());
      photos.photos.push_back(ph);
    }
  }
  const std::map<std::string, std::string> files = PhotoFiles(photos);
  const auto file = files.find(args.shot);
  const std::string zoom = std::to_string(rows.front().zoom);
  int width = 0, height = 0;
  if (report.contains("image_sizes") && report["image_sizes"].contains(zoom)) {
    width = report["image_sizes"][zoom].value("width", 0);
    height = report["image_sizes"][zoom].value("height", 0);
  }
  const Figure fig =
      PhotoFigure(args.shot, rows, file == files.end() ? "" : file->second, width, height);

  const fs::path out(args.out.empty() ? "." : args.out);
  if (!args.force) {
    for (const char* ext : {".html", ".vg.json", ".svg", ".png"}) {
      if (fs::exists(out / (fig.name + ext))) {
        throw std::invalid_argument("show: '" + (out / (fig.name + ext)).string() +
                                    "' exists; rtscalib does not overwrite files you have "
                                    "(--force replaces it)");
      }
    }
  }
  std::string note;
  WriteFigureFiles({fig}, out.string(), &note);
  WriteFileAtomic((out / (fig.name + ".html")).string(), FigurePage(fig));
  if (!note.empty()) std::cerr << "rtscalib show: " << note << "\n";
  const nlohmann::json& s = fig.summary;
  std::cout << "shot " << args.shot << " (zoom " << zoom << "): " << rows.size() << " corners, "
            << s.value("fitted_rows", 0) << " fitted, rms " << s.value("rms_px", 0.0)
            << " px; reference arrow " << s.value("arrow_scale_px", 0.0) << " px"
            << (s.value("photo", false) ? "" : "; the photo was not found, corners only") << "\n"
            << "written: " << (out / fig.name).string() << ".{html, vg.json"
            << (note.empty() ? ", svg, png" : "") << "}\n";
  return 0;
}

}  // namespace rtscalib::app
