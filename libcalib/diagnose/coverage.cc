#include "libcalib/diagnose/coverage.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "libcalib/eval/error_measures.h"
#include "libcalib/model/focus.h"

namespace rtscalib {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g", v);
  return buf;
}

}  // namespace

Coverage MeasureCoverage(const Observations& obs, const InstrumentModel& model,
                         const FitOptions& fit) {
  Coverage c;
  std::vector<double> phis, zeniths, edm;
  c.corner_fraction.assign(model.NumZooms(), 0.0);
  auto corner = [&](int zoom, double u, double v) {
    if (zoom < 0 || zoom >= model.NumZooms()) return;
    const CameraTool& cam = model.cams[zoom];
    const double cx = cam.intrinsics[2], cy = cam.intrinsics[3];
    const double half_diag = 0.5 * std::hypot(cam.width, cam.height);
    c.corner_fraction[zoom] =
        std::max(c.corner_fraction[zoom], std::hypot(u - cx, v - cy) / half_diag);
  };
  auto pointing = [&](int face, double phi, double theta) {
    c.faces.insert(face);
    double p1 = phi, t1 = theta;
    if (face == 2) OtherFace(phi, theta, &p1, &t1);  // face-1 pointing of the same direction
    phis.push_back(std::fmod(std::fmod(p1, 2 * M_PI) + 2 * M_PI, 2 * M_PI));
    zeniths.push_back(ZenithOf(theta) * 180 / M_PI);
  };
  // The nearest and farthest camera target per zoom (SPEC 4.1's D).
  auto target = [&](int zoom, double d) {
    if (!(d > 0)) return;
    auto [it, fresh] = c.target_distance.emplace(zoom, std::make_pair(d, d));
    it->second.first = std::min(it->second.first, d);
    it->second.second = std::max(it->second.second, d);
  };
  for (const Record& r : obs.records) {
    if (InCriticalRegion(r.theta, fit.min_zenith_rad, fit.max_zenith_rad)) continue;
    ++c.records;
    pointing(r.face, r.phi, r.theta);
    if (r.tool == Tool::kEdm) {
      c.has_edm = true;
      edm.push_back(r.d);
    } else {
      c.has_cam = true;
      corner(r.zoom, r.u, r.v);
      target(r.zoom, r.d);
    }
  }
  const std::vector<double> focus = PhotoFocusDistances(model, obs.pixels, &obs.targets);
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    const PixelObservation& p = obs.pixels[i];
    if (InCriticalRegion(p.theta, fit.min_zenith_rad, fit.max_zenith_rad)) continue;
    ++c.pixels;
    c.has_cam = true;
    pointing(p.face, p.phi, p.theta);
    corner(p.zoom, p.uv.x(), p.uv.y());
    target(p.zoom, focus[i]);
  }
  if (!zeniths.empty()) {
    c.min_zenith_deg = *std::min_element(zeniths.begin(), zeniths.end());
    c.max_zenith_deg = *std::max_element(zeniths.begin(), zeniths.end());
  }
  if (!phis.empty()) {
    std::sort(phis.begin(), phis.end());
    double gap = 2 * M_PI - (phis.back() - phis.front());
    for (size_t i = 1; i < phis.size(); ++i) gap = std::max(gap, phis[i] - phis[i - 1]);
    c.phi_span_deg = (2 * M_PI - gap) * 180 / M_PI;
  }
  if (!edm.empty()) {
    std::sort(edm.begin(), edm.end());
    edm.erase(std::unique(edm.begin(), edm.end(),
                          [](double a, double b) { return std::abs(a - b) < 1e-6; }),
              edm.end());
    c.min_edm_m = edm.front();
    c.max_edm_m = edm.back();
    c.distinct_edm = static_cast<int>(edm.size());
    c.finest_edm_step_m = 0;
    for (size_t i = 1; i < edm.size(); ++i) {
      const double step = edm[i] - edm[i - 1];
      if (c.finest_edm_step_m == 0 || step < c.finest_edm_step_m) c.finest_edm_step_m = step;
    }
  }
  return c;
}

std::vector<std::string> WhatWouldHelp(Effect e, const Coverage& c, const InstrumentModel& model,
                                       const CoverageRules& rules) {
  std::vector<std::string> out;
  const bool steep = c.min_zenith_deg < rules.steep_zenith_deg ||
                     c.max_zenith_deg > 180.0 - rules.steep_zenith_deg;
  auto need_steep = [&] {
    if (!steep) {
      out.push_back("steep sights (zenith angle below " + Num(rules.steep_zenith_deg) +
                    " deg or above " + Num(180.0 - rules.steep_zenith_deg) +
                    " deg; the data span " + Num(c.min_zenith_deg) + " to " +
                    Num(c.max_zenith_deg) + " deg)");
    }
  };
  auto need_faces = [&] {
    if (c.faces.size() < 2) out.push_back("the other face (face 2 readings of the same pointings)");
  };
  auto need_turn = [&] {
    if (c.phi_span_deg < rules.full_turn_deg) {
      out.push_back("pointings all around the horizon (the data span " + Num(c.phi_span_deg) +
                    " deg of phi; a full turn separates once- and twice-per-turn terms)");
    }
  };
  auto need_wide_zenith = [&] {
    if (c.max_zenith_deg - c.min_zenith_deg < rules.wide_zenith_deg) {
      out.push_back("a wider range of zenith angles (the data span " + Num(c.min_zenith_deg) +
                    " to " + Num(c.max_zenith_deg) + " deg)");
    }
  };
  auto need_edm = [&] {
    if (!c.has_edm) out.push_back("EDM records (tool edm in records.csv)");
  };
  auto need_long_distances = [&] {
    if (c.has_edm &&
        (c.max_edm_m < rules.distance_ratio * c.min_edm_m || c.max_edm_m < rules.long_distance_m)) {
      out.push_back("longer EDM distances (more than " + Num(rules.distance_ratio) +
                    " times the shortest and " + Num(rules.long_distance_m) +
                    " m or more; the data span " + Num(c.min_edm_m) + " to " + Num(c.max_edm_m) +
                    " m)");
    }
  };
  auto need_fine_distances = [&] {
    const double u = model.edm_cyclic_unit_length;
    if (c.has_edm &&
        (c.distinct_edm < 6 || c.finest_edm_step_m > u / 4 || c.max_edm_m - c.min_edm_m < u)) {
      out.push_back("EDM distances spaced finer than U/4 = " + Num(u / 4) +
                    " m over at least one unit length U = " + Num(u) + " m (the data have " +
                    std::to_string(c.distinct_edm) + " distinct distances)");
    }
  };
  auto need_image_corners = [&] {
    if (!c.has_cam) {
      out.push_back(
          "camera observations (pixels.csv, or cam rows spread over the image in records.csv)");
      return;
    }
    for (size_t z = 0; z < c.corner_fraction.size(); ++z) {
      if (c.corner_fraction[z] > 0 && c.corner_fraction[z] < rules.corner_fraction) {
        out.push_back("points near the image corners at zoom " + std::to_string(z) +
                      " (the farthest reaches " + Num(100 * c.corner_fraction[z]) +
                      "% of the half-diagonal)");
      }
    }
  };
  auto need_near_and_far = [&] {
    if (!c.has_cam) {
      out.push_back("camera observations (photos or cam rows) of targets near and far");
      return;
    }
    for (const auto& [zoom, range] : c.target_distance) {
      if (range.second < rules.focus_distance_ratio * range.first) {
        out.push_back("targets near and far at zoom " + std::to_string(zoom) +
                      " (the farthest at least " + Num(rules.focus_distance_ratio) +
                      " times the nearest; the data span " + Num(range.first) + " to " +
                      Num(range.second) + " m)");
      }
    }
  };
  // What data each effect needs is a column of the catalogue (effects.h); the
  // advice is given in DataNeed order.
  for (int bit = 0; bit < kNumDataNeeds; ++bit) {
    const auto need = static_cast<DataNeed>(1u << bit);
    if (!(Info(e).needs & need)) continue;
    switch (need) {
      case kNeedNone:
        break;
      case kNeedFullTurn:
        need_turn();
        break;
      case kNeedSteepSights:
        need_steep();
        break;
      case kNeedWideZenith:
        need_wide_zenith();
        break;
      case kNeedBothFaces:
        need_faces();
        break;
      case kNeedEdm:
        need_edm();
        break;
      case kNeedLongDistances:
        need_long_distances();
        break;
      case kNeedFineDistances:
        need_fine_distances();
        break;
      case kNeedImageCorners:
        need_image_corners();
        break;
      case kNeedNearAndFar:
        need_near_and_far();
        break;
    }
  }
  return out;
}

}  // namespace rtscalib
