// The figures' plotted numbers recomputed from the files a run writes
// (residuals.csv, report.json's "residuals"), for any PipelineResult: the
// figures draw the calibration's own residual table and nothing else.
// Used by the demo (Zoom3Demo) and the photo session (PhotoSession) suites.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/figures.h"
#include "app/plot/vega_svg.h"
#include "app/reports.h"

namespace rtscalib::app::testing_figures {

// residuals.csv writes coordinates with %.10g and residuals with %.6g: a
// residual read back is within 1e-6 of itself relative, so means and rms of
// read-back residuals agree with the figure's to 1e-5 relative (10x margin).
constexpr double kCsvRelative = 1e-5;
// The bound for a sensible arrow: the reference arrow stands for at
// most 10 times the rms of the rows it draws.
constexpr double kMaxArrowOverRms = 10.0;

struct Row {
  std::map<std::string, std::string> f;
  double Num(const std::string& k) const { return std::stod(f.at(k)); }
  bool Has(const std::string& k) const { return !f.at(k).empty(); }
};

inline std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

inline std::vector<Row> ReadResidualsCsv(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> header;
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> f = Split(line);
    if (header.empty()) {
      header = f;
      continue;
    }
    Row r;
    for (size_t i = 0; i < header.size() && i < f.size(); ++i) r.f[header[i]] = f[i];
    rows.push_back(r);
  }
  return rows;
}

inline const nlohmann::json& Data(const nlohmann::json& spec, const std::string& name) {
  for (const nlohmann::json& d : spec["data"]) {
    if (d["name"] == name) return d["values"];
  }
  static const nlohmann::json none = nlohmann::json::array();
  ADD_FAILURE() << "no data '" << name << "' in the spec";
  return none;
}

// Every figure of `r` against residuals.csv; returns the figures checked.
inline std::vector<Figure> CheckFiguresAgainstResidualFile(const PipelineResult& r) {
  const std::vector<Row> rows = ReadResidualsCsv(ResidualsCsv(r));
  EXPECT_EQ(rows.size(), r.obs.records.size() + r.obs.pixels.size())
      << "one row per observation as given";
  const nlohmann::json summary = ResidualsJson(r);
  int status_total = 0;
  for (const auto& [k, v] : summary["status"].items()) status_total += v.get<int>();
  EXPECT_EQ(status_total, static_cast<int>(rows.size()));

  const std::vector<Figure> figs = MakeFigures(r, nlohmann::json::array());
  int image_figures = 0, photo_figures = 0;
  for (const Figure& f : figs) {
    SCOPED_TRACE(f.name);
    // Its files are drawn in process (app/plot/vega_svg.h), which refuses a spec
    // beyond the part of Vega it draws: every figure the run makes is in it.
    EXPECT_NO_THROW(vega::DrawSvg(f.spec));
    if (f.section == "image") {
      ++image_figures;
      const int zoom = f.summary["zoom"];
      const nlohmann::json& cells = Data(f.spec, "cells");
      int fitted = 0;
      double ss = 0;
      std::map<std::pair<int, int>, std::pair<Eigen::Vector2d, int>> mine;
      for (const Row& row : rows) {
        if (row.f.at("kind") == "edm" || row.f.at("status") != "fitted" ||
            static_cast<int>(row.Num("zoom")) != zoom || !row.Has("image_du"))
          continue;
        ++fitted;
        const Eigen::Vector2d d(row.Num("image_du"), row.Num("image_dv"));
        ss += d.squaredNorm();
        // The cell of the observed pixel, by the cell bounds the figure plots.
        for (const nlohmann::json& c : cells) {
          if (row.Num("u") >= c["u0"].get<double>() && row.Num("u") < c["u1"].get<double>() &&
              row.Num("v") >= c["v0"].get<double>() && row.Num("v") < c["v1"].get<double>()) {
            auto& m = mine.try_emplace({c["i"], c["j"]}, Eigen::Vector2d::Zero(), 0).first->second;
            m.first += d;
            ++m.second;
            break;
          }
        }
      }
      EXPECT_GT(fitted, 0);
      if (fitted == 0) continue;
      EXPECT_EQ(f.summary["fitted_rows"].get<int>(), fitted) << "counts equal the fitted rows";
      int plotted = 0;
      for (const nlohmann::json& c : cells) {
        plotted += c["n"].get<int>();
        const auto m = mine.find({c["i"], c["j"]});
        const int n = m == mine.end() ? 0 : m->second.second;
        EXPECT_EQ(c["n"].get<int>(), n) << c.dump();
        if (n == 0) continue;
        const Eigen::Vector2d mean = m->second.first / n;
        const double tol = kCsvRelative * std::max(1.0, mean.norm()) * 10;
        EXPECT_NEAR(c["du"].get<double>(), mean.x(), tol);
        EXPECT_NEAR(c["dv"].get<double>(), mean.y(), tol);
      }
      EXPECT_EQ(plotted, fitted);
      const double rms = std::sqrt(ss / fitted);
      EXPECT_NEAR(f.summary["rms_px"].get<double>(), rms, kCsvRelative * rms);
      EXPECT_GT(f.summary["arrow_scale_px"].get<double>(), 0);
      EXPECT_LE(f.summary["arrow_scale_px"].get<double>(), kMaxArrowOverRms * rms);
    } else if (f.section == "photos") {
      ++photo_figures;
      const std::string shot = f.summary["shot"];
      int all = 0, fitted = 0;
      double ss = 0;
      for (const Row& row : rows) {
        if (row.f.at("kind") != "pixel" || row.f.at("shot") != shot) continue;
        ++all;
        if (row.f.at("status") != "fitted") continue;
        ++fitted;
        ss += std::pow(row.Num("res_x"), 2) + std::pow(row.Num("res_y"), 2);
      }
      EXPECT_GT(fitted, 0);
      if (fitted == 0) continue;
      EXPECT_EQ(Data(f.spec, "corners").size(), static_cast<size_t>(all));
      EXPECT_EQ(f.summary["fitted_rows"].get<int>(), fitted);
      const double rms = std::sqrt(ss / fitted);
      EXPECT_NEAR(f.summary["rms_px"].get<double>(), rms, kCsvRelative * rms);
      EXPECT_LE(f.summary["arrow_scale_px"].get<double>(), kMaxArrowOverRms * rms);
    } else if (f.section == "histograms") {
      std::map<std::string, int> coords;
      for (const Row& row : rows) {
        if (row.f.at("status") != "fitted") continue;
        const std::string kind = row.f.at("kind");
        coords[kind == "pixel" ? "pixels" : kind] += kind == "pixel" ? 2 : 3;
      }
      for (const nlohmann::json& g : f.summary["groups"]) {
        EXPECT_EQ(g["values"].get<int>(), coords[g["group"].get<std::string>()]) << g.dump();
      }
    } else if (f.section == "maps") {
      // Fitted and critical-region rows of the map's group and zoom.
      const std::string name = f.name;
      const std::string kind = name.find("edm") != std::string::npos        ? "edm"
                               : name.find("cam_zoom") != std::string::npos ? "cam"
                                                                            : "pixel";
      const int zoom = kind == "edm" ? -1 : std::stoi(name.substr(name.rfind("zoom") + 4));
      int n = 0;
      for (const Row& row : rows) {
        const std::string st = row.f.at("status");
        if (row.f.at("kind") != kind || (st != "fitted" && st != "critical_region")) continue;
        if (zoom >= 0 && static_cast<int>(row.Num("zoom")) != zoom) continue;
        ++n;
      }
      int plotted = 0;
      for (const nlohmann::json& c : Data(f.spec, "cells")) plotted += c["n"].get<int>();
      EXPECT_EQ(plotted, n);
    }
  }
  // Every zoom with image observations has its binned figure, every zoom
  // with photos at least one photo.
  std::map<int, int> zooms, shot_zooms;
  for (const Row& row : rows) {
    if (row.f.at("kind") == "edm" || row.f.at("status") != "fitted") continue;
    ++zooms[static_cast<int>(row.Num("zoom"))];
    if (row.f.at("kind") == "pixel" && row.Has("shot"))
      ++shot_zooms[static_cast<int>(row.Num("zoom"))];
  }
  EXPECT_EQ(image_figures, static_cast<int>(zooms.size()));
  EXPECT_GE(photo_figures, static_cast<int>(shot_zooms.size()));
  return figs;
}

}  // namespace rtscalib::app::testing_figures
