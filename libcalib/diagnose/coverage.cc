#include "libcalib/diagnose/coverage.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <set>

#include "libcalib/eval/error_measures.h"
#include "libcalib/model/focus.h"
#include "libcalib/model/kinematics.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {

Coverage MeasureCoverage(const Observations& obs, const InstrumentModel& model,
                         const FitOptions& fit) {
  Coverage c;
  std::vector<double> phis, zeniths, edm;
  c.corner_fraction.assign(model.NumZooms(), 0.0);
  std::vector<ImageCoverage> images(model.NumZooms());
  std::vector<std::array<bool, 4>> ninths(model.NumZooms(), {false, false, false, false});
  auto corner = [&](int zoom, double u, double v) {
    if (zoom < 0 || zoom >= model.NumZooms()) return;
    const CameraTool& cam = model.cams[zoom];
    const double cx = cam.intrinsics[2], cy = cam.intrinsics[3];
    const double half_diag = 0.5 * std::hypot(cam.width, cam.height);
    c.corner_fraction[zoom] =
        std::max(c.corner_fraction[zoom], std::hypot(u - cx, v - cy) / half_diag);
    if (cam.width <= 0 || cam.height <= 0) return;
    ImageCoverage& g = images[zoom];
    if (g.counts.empty()) g.counts.assign(kCoverageCells * kCoverageCells, 0);
    ++g.points;
    // Pixel centres are integers (SPEC 2): the image spans [-0.5, W - 0.5).
    const double fu = (u + 0.5) / cam.width, fv = (v + 0.5) / cam.height;
    const int i = std::clamp(static_cast<int>(fu * kCoverageCells), 0, kCoverageCells - 1);
    const int j = std::clamp(static_cast<int>(fv * kCoverageCells), 0, kCoverageCells - 1);
    ++g.counts[j * kCoverageCells + i];
    const int i3 = std::clamp(static_cast<int>(fu * 3), 0, 2);
    const int j3 = std::clamp(static_cast<int>(fv * 3), 0, 2);
    if (i3 != 1 && j3 != 1) ninths[zoom][(j3 / 2) * 2 + i3 / 2] = true;
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
    if (fit.critical_region.Contains(r.theta)) continue;
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
  // Each photo's view of each board of estimated pose, once: the direction
  // from the board's centre to the camera in the board frame (its z points
  // away from the camera), as tilts about the board's axes.
  std::set<std::pair<std::string, const EstimatedBoard*>> seen;
  auto board_view = [&](const PixelObservation& p) {
    if (p.zoom < 0 || p.zoom >= model.NumZooms()) return;
    const EstimatedBoard* b = model.BoardOf(p.target, p.placement, p.zoom);
    if (!b || !seen.insert({p.shot, b}).second) return;
    const Rigid3 board_from_cam =
        b->pose.ToRigid().Inverse() * RefFromCam(model, p.zoom, p.phi, p.theta);
    const Eigen::Vector3d centre(0.5 * b->board.Width(), 0.5 * b->board.Height(), 0.0);
    const Eigen::Vector3d to_camera = board_from_cam.translation - centre;
    const double tx = std::atan2(to_camera.x(), -to_camera.z()) * 180 / M_PI;
    const double ty = std::atan2(to_camera.y(), -to_camera.z()) * 180 / M_PI;
    auto [it, fresh] = c.boards.emplace(b->board.first_id, BoardViews{});
    BoardViews& v = it->second;
    if (fresh || v.views == 0) {
      v.tilt_x_min = v.tilt_x_max = tx;
      v.tilt_y_min = v.tilt_y_max = ty;
    }
    ++v.views;
    v.tilt_x_min = std::min(v.tilt_x_min, tx);
    v.tilt_x_max = std::max(v.tilt_x_max, tx);
    v.tilt_y_min = std::min(v.tilt_y_min, ty);
    v.tilt_y_max = std::max(v.tilt_y_max, ty);
  };
  for (size_t i = 0; i < obs.pixels.size(); ++i) {
    const PixelObservation& p = obs.pixels[i];
    if (fit.critical_region.Contains(p.theta)) continue;
    ++c.pixels;
    board_view(p);
    c.has_cam = true;
    pointing(p.face, p.phi, p.theta);
    corner(p.zoom, p.uv.x(), p.uv.y());
    target(p.zoom, focus[i]);
  }
  for (int z = 0; z < model.NumZooms(); ++z) {
    ImageCoverage& g = images[z];
    if (g.points == 0) continue;
    g.zoom = z;
    g.width = model.cams[z].width;
    g.height = model.cams[z].height;
    g.covered_fraction = static_cast<double>(std::count_if(g.counts.begin(), g.counts.end(),
                                                           [](int n) { return n > 0; })) /
                         g.counts.size();
    g.corners_covered = ninths[z][0] && ninths[z][1] && ninths[z][2] && ninths[z][3];
    c.images.push_back(std::move(g));
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
      out.push_back("steep sights (zenith angle below " + Significant(rules.steep_zenith_deg, 3) +
                    " deg or above " + Significant(180.0 - rules.steep_zenith_deg, 3) +
                    " deg; the data span " + Significant(c.min_zenith_deg, 3) + " to " +
                    Significant(c.max_zenith_deg, 3) + " deg)");
    }
  };
  auto need_faces = [&] {
    if (c.faces.size() < 2) out.push_back("the other face (face 2 readings of the same pointings)");
  };
  auto need_turn = [&] {
    if (c.phi_span_deg < rules.full_turn_deg) {
      out.push_back("pointings all around the horizon (the data span " +
                    Significant(c.phi_span_deg, 3) +
                    " deg of phi; a full turn separates once- and twice-per-turn terms)");
    }
  };
  auto need_wide_zenith = [&] {
    if (c.max_zenith_deg - c.min_zenith_deg < rules.wide_zenith_deg) {
      out.push_back("a wider range of zenith angles (the data span " +
                    Significant(c.min_zenith_deg, 3) + " to " + Significant(c.max_zenith_deg, 3) +
                    " deg)");
    }
  };
  auto need_edm = [&] {
    if (!c.has_edm) out.push_back("EDM records (tool edm in records.csv)");
  };
  auto need_long_distances = [&] {
    if (c.has_edm &&
        (c.max_edm_m < rules.distance_ratio * c.min_edm_m || c.max_edm_m < rules.long_distance_m)) {
      out.push_back("longer EDM distances (more than " + Significant(rules.distance_ratio, 3) +
                    " times the shortest and " + Significant(rules.long_distance_m, 3) +
                    " m or more; the data span " + Significant(c.min_edm_m, 3) + " to " +
                    Significant(c.max_edm_m, 3) + " m)");
    }
  };
  auto need_fine_distances = [&] {
    const double u = model.edm_cyclic_unit_length;
    if (c.has_edm &&
        (c.distinct_edm < 6 || c.finest_edm_step_m > u / 4 || c.max_edm_m - c.min_edm_m < u)) {
      out.push_back("EDM distances spaced finer than U/4 = " + Significant(u / 4, 3) +
                    " m over at least one unit length U = " + Significant(u, 3) +
                    " m (the data have " + std::to_string(c.distinct_edm) + " distinct distances)");
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
                      " (the farthest reaches " + Significant(100 * c.corner_fraction[z], 3) +
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
                      " (the farthest at least " + Significant(rules.focus_distance_ratio, 3) +
                      " times the nearest; the data span " + Significant(range.first, 3) + " to " +
                      Significant(range.second, 3) + " m)");
      }
    }
  };
  auto need_many_poses = [&] {
    if (c.boards.empty()) {
      out.push_back("photos of boards of estimated pose (a board with a surveyed pose is taken "
                    "as surveyed, warp included)");
      return;
    }
    for (const auto& [first_id, v] : c.boards) {
      const double span_x = v.tilt_x_max - v.tilt_x_min, span_y = v.tilt_y_max - v.tilt_y_min;
      if (v.views >= rules.warp_views && span_x >= rules.warp_tilt_span_deg &&
          span_y >= rules.warp_tilt_span_deg) {
        continue;
      }
      out.push_back("board " + std::to_string(first_id) + " in more views, tilted both ways "
                    "about both its axes (" + std::to_string(v.views) + " view(s) spanning " +
                    Significant(span_x, 2) + " deg about its y axis and " +
                    Significant(span_y, 2) + " deg about its x axis; at least " +
                    std::to_string(rules.warp_views) + " views and " +
                    Significant(rules.warp_tilt_span_deg, 2) + " deg each)");
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
      case kNeedManyPoses:
        need_many_poses();
        break;
    }
  }
  return out;
}

std::vector<std::string> CoverageWarnings(const Coverage& c, const InstrumentModel& model,
                                          const CoverageRules& rules) {
  std::vector<std::string> out;
  char line[400];
  for (const ImageCoverage& g : c.images) {
    const int z = g.zoom;
    const double reach = z < static_cast<int>(c.corner_fraction.size()) ? c.corner_fraction[z] : 0;
    if (reach < rules.corner_fraction || !g.corners_covered) {
      std::snprintf(line, sizeof line,
                    "zoom %d: distortion extrapolated: points reach %.0f%% of the half-diagonal%s "
                    "(%.0f%% of the image covered); take photos with the boards in the image "
                    "corners",
                    z, 100 * reach,
                    g.corners_covered ? "" : ", some corner ninths of the image hold no points",
                    100 * g.covered_fraction);
      out.push_back(line);
    }
    if (!model.sigmas.valid || z >= static_cast<int>(model.sigmas.distortion.size())) continue;
    const CameraTool& cam = model.cams[z];
    const double corner_r = 0.5 * std::hypot(cam.width, cam.height) / cam.intrinsics[0];
    for (int k = 0; k < kNumDistortion; ++k) {
      const double x = cam.distortion[k], s = model.sigmas.distortion[z][k];
      if (!(s > 0 && s > std::abs(x))) continue;
      // What one sigma means in the image: the shift it gives at the image
      // corner (radial terms k r^(2n) on a radius r; tangential ones at most
      // 3 p r^2), so that a coefficient that is merely near zero can be told
      // from one that moves pixels.
      double shift = -1;
      if (k == 0) shift = s * std::pow(corner_r, 3);
      if (k == 1) shift = s * std::pow(corner_r, 5);
      if (k == 4) shift = s * std::pow(corner_r, 7);
      if (k == 2 || k == 3) shift = 3 * s * corner_r * corner_r;
      char effect[96] = "";
      if (shift >= 0) {
        std::snprintf(effect, sizeof effect, "; 1 sigma moves the image corner by %.2g px",
                      shift * cam.intrinsics[0]);
      }
      std::snprintf(line, sizeof line,
                    "zoom %d: distortion %s = %.3g +- %.3g is badly determined (relative sigma "
                    "%.1f > 1%s)",
                    z, kDistortionCoefficientNames[k], x, s, x != 0 ? s / std::abs(x) : INFINITY,
                    effect);
      out.push_back(line);
    }
  }
  return out;
}

}  // namespace rtscalib
