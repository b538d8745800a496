// The figure of residuals against the variables the diagnosis tests
// (app/residual_figures.h): which panels it draws and what its legend lists.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "app/residual_figures.h"

namespace rtscalib::app {
namespace {

using nlohmann::json;

// Pixel rows of a camera on its own: no angles (ObservationResidual::hz is
// NaN), a pixel residual that grows with the image radius.
std::vector<ObservationResidual> CameraOnItsOwn() {
  std::vector<ObservationResidual> rows;
  for (int i = 0; i < 200; ++i) {
    ObservationResidual o;
    o.group = ObsGroup::kPixel;
    o.index = i;
    o.valid = true;
    o.phi = 0;
    o.theta = M_PI / 2;
    o.image_radius = 2.0 * i;
    o.target_distance = 0.2 + 0.001 * i;
    o.image_delta = Eigen::Vector2d(1e-3 * i, -0.05);
    o.hz = o.zenith = std::nan("");
    rows.push_back(o);
  }
  return rows;
}

// The panels drawn, each "variable_component" (the name of its data).
std::set<std::string> PanelsWithData(const Figure& f) {
  std::set<std::string> out;
  for (const json& g : f.spec.at("marks")) {
    if (g.contains("data")) out.insert(g.at("data").at(0).at("name").get<std::string>());
  }
  return out;
}

const json& GroupScale(const Figure& f) {
  for (const json& s : f.spec.at("scales")) {
    if (s.at("name") == "group") return s;
  }
  throw std::runtime_error("no group scale");
}

TEST(VariablesFigure, ACameraOnItsOwnIsDrawnInPixelsAndItsLegendListsImagePointsAlone) {
  const Figure f = VariablesFigure(CameraOnItsOwn());
  // phi and theta do not vary; no angles: u and v in pixels against the
  // camera-to-point distance and the image radius.
  EXPECT_EQ(PanelsWithData(f), (std::set<std::string>{"target_distance_du", "target_distance_dv",
                                                      "image_radius_du", "image_radius_dv"}));
  const json& scale = GroupScale(f);
  EXPECT_EQ(scale.at("domain"), json::array({"image points"}));
  EXPECT_EQ(scale.at("range"), json::array({"#2ca02c"}));
  // The last bin of u against the image radius holds the rows of the
  // largest radii: the mean of 1e-3 i over them, in pixels.
  double last_x = -1, last_mean = 0;
  for (const json& g : f.spec.at("marks")) {
    if (!g.contains("data")) continue;
    const json& d = g.at("data").at(0);
    if (d.at("name") != "image_radius_du") continue;
    for (const json& v : d.at("values")) {
      if (v.at("x").get<double>() > last_x) {
        last_x = v.at("x").get<double>();
        last_mean = v.at("mean").get<double>();
      }
    }
  }
  ASSERT_GT(last_x, 0);
  EXPECT_NEAR(last_mean, 1e-3 * last_x / 2.0, 1e-9);
}

TEST(VariablesFigure, AnInstrumentsImagePointsAreDrawnInAnglesNotInPixels) {
  std::vector<ObservationResidual> rows = CameraOnItsOwn();
  for (ObservationResidual& o : rows) {
    o.hz = 1e-5;
    o.zenith = -1e-5;
  }
  ObservationResidual edm;
  edm.group = ObsGroup::kEdm;
  edm.valid = true;
  const Figure f = VariablesFigure(rows);
  EXPECT_EQ(PanelsWithData(f),
            (std::set<std::string>{"target_distance_hz", "target_distance_zenith",
                                   "image_radius_hz", "image_radius_zenith"}));
  EXPECT_EQ(GroupScale(f).at("domain"), json::array({"image points"}));
  rows.push_back(edm);
  EXPECT_EQ(GroupScale(VariablesFigure(rows)).at("domain"),
            json::array({"EDM points", "image points"}));
}

}  // namespace
}  // namespace rtscalib::app
