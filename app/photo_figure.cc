#include "app/photo_figure.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "app/report_html.h"
#include "libcalib/text/number_text.h"

namespace rtscalib::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The part `box` of a photo (pixels at full resolution, then at most the
// panel's size: a photo's pixels beyond what is shown only make report.html
// heavier), as a data URI; *crop: the image part it shows.
std::string PhotoDataUri(const cv::Mat& photo, const ImageBox& box, ImageBox* crop) {
  const int x0 = std::clamp(static_cast<int>(std::floor(box.u0 + 0.5)), 0, photo.cols - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(box.v0 + 0.5)), 0, photo.rows - 1);
  const int x1 = std::clamp(static_cast<int>(std::ceil(box.u1 + 0.5)), x0 + 1, photo.cols);
  const int y1 = std::clamp(static_cast<int>(std::ceil(box.v1 + 0.5)), y0 + 1, photo.rows);
  *crop = {x0 - 0.5, x1 - 0.5, y0 - 0.5, y1 - 0.5};
  cv::Mat img = photo(cv::Rect(x0, y0, x1 - x0, y1 - y0));
  const double s = static_cast<double>(kImagePanel) / std::max(img.cols, img.rows);
  if (s < 1) cv::resize(img, img, cv::Size(), s, s, cv::INTER_AREA);
  std::vector<unsigned char> jpg;
  if (!cv::imencode(".jpg", img, jpg, {cv::IMWRITE_JPEG_QUALITY, 85})) return "";
  return "data:image/jpeg;base64," + Base64(jpg);
}

}  // namespace

Figure PhotoFigure(const std::string& shot, const std::vector<ObservationResidual>& rows,
                   const std::string& image, int width, int height) {
  const cv::Mat photo = image.empty() ? cv::Mat() : cv::imread(image, cv::IMREAD_COLOR);
  if (!photo.empty()) {
    width = photo.cols;
    height = photo.rows;
  }
  std::vector<double> sizes;
  double ss = 0;
  int zoom = rows.empty() ? 0 : rows.front().zoom, fitted = 0;
  for (const ObservationResidual& o : rows) {
    if (!Fitted(o)) continue;
    sizes.push_back(o.size);
    ss += o.size * o.size;
    ++fitted;
  }
  const double rms = fitted ? std::sqrt(ss / fitted) : 0;
  // The reference arrow: a round residual near the largest (95th
  // percentile) drawn 40 image pixels long per the panel's 640.
  const double reference_px = NiceAbove(Percentile(sizes, 0.95));
  // Zoomed to the corners (a fifth of their extent around them, at least a
  // third of the image, the image's aspect), so that arrows of a fraction of
  // a pixel are seen where they are.
  double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  for (const ObservationResidual& o : rows) {
    u0 = std::min(u0, o.u);
    u1 = std::max(u1, o.u);
    v0 = std::min(v0, o.v);
    v1 = std::max(v1, o.v);
  }
  const double aspect = double(height) / width;
  double half_u = std::max({0.6 * (u1 - u0), 0.6 * (v1 - v0) / aspect, width / 6.0});
  half_u = std::min(half_u, width / 2.0);
  const double half_v = half_u * aspect;
  const double cu = std::clamp(0.5 * (u0 + u1), half_u - 0.5, width - 0.5 - half_u);
  const double cv = std::clamp(0.5 * (v0 + v1), half_v - 0.5, height - 0.5 - half_v);
  const ImageBox box = rows.empty() ? ImageBox{-0.5, width - 0.5, -0.5, height - 0.5}
                                    : ImageBox{cu - half_u, cu + half_u, cv - half_v, cv + half_v};
  // The reference arrow is 40 display pixels long.
  const double drawn = 40.0 * std::max(box.u1 - box.u0, box.v1 - box.v0) / kImagePanel;
  const double gain = drawn / reference_px;
  json corners = json::array();
  for (const ObservationResidual& o : rows) {
    json c = {{"target", o.target},
              {"corner", o.corner},
              {"u", o.u},
              {"v", o.v},
              {"status", ResidualStatusName(o.status)},
              {"line", o.line}};
    if (o.valid) {
      c.update({{"du", o.delta.x()},
                {"dv", o.delta.y()},
                {"r", o.size},
                {"nr", o.normalised},
                {"tip_u", o.u + gain * o.delta.x()},
                {"tip_v", o.v + gain * o.delta.y()},
                {"angle", std::atan2(o.delta.x(), -o.delta.y()) * kDegPerRad}});
    }
    corners.push_back(c);
  }
  json spec = Chart("Photo " + shot + " (zoom " + std::to_string(zoom) + "): corners and residuals",
                    std::to_string(fitted) + " fitted corners, rms " + Significant(rms, 3) +
                        " px; arrows from each observed corner along observed - predicted, " +
                        Significant(reference_px, 3) + " px residual = the red reference arrow" +
                        (photo.empty() ? "; photo not found, corners only" : ""));
  int w = 0, h = 0;
  ImageScales(&spec, box, &w, &h);
  ImageBox crop{};
  const std::string uri = photo.empty() ? "" : PhotoDataUri(photo, box, &crop);
  spec["data"].push_back({{"name", "corners"}, {"values", corners}});
  spec["data"].push_back(
      {{"name", "arrows"},
       {"source", "corners"},
       {"transform", {{{"type", "filter"}, {"expr", "datum.status == 'fitted'"}}}}});
  json& marks = spec["marks"];
  if (!uri.empty()) {
    // The photo is a data row, not a constant of the mark: Vega compiles a
    // mark's constants into the code of its encoder, and its expression
    // parser then scans the tens of kilobytes of the data URI character by
    // character, a large part of the figure's time in node's interpreter.
    spec["data"].push_back({{"name", "photo"}, {"values", {{{"url", uri}}}}});
    json image = Mark("image", "photo",
                      {{"url", {{"field", "url"}}},
                       {"x", {{"scale", "u"}, {"value", crop.u0}}},
                       {"y", {{"scale", "v"}, {"value", crop.v0}}},
                       {"x2", {{"scale", "u"}, {"value", crop.u1}}},
                       {"y2", {{"scale", "v"}, {"value", crop.v1}}},
                       {"aspect", {{"value", false}}},
                       {"opacity", {{"value", 0.85}}}});
    image["clip"] = true;  // the panel shows a part of the photo
    marks.push_back(image);
  }
  const json tip = Tip({{"shot", "'" + shot + "'"},
                        {"target", "datum.target"},
                        {"corner", "datum.corner"},
                        {"u, v [px]", "format(datum.u, '.2f') + ', ' + format(datum.v, '.2f')"},
                        {"du, dv [px]", "format(datum.du, '.3f') + ', ' + format(datum.dv, '.3f')"},
                        {"|r| / sigma", "format(datum.nr, '.2f')"},
                        {"status", "datum.status"},
                        {"pixels.csv line", "datum.line"}});
  marks.push_back(
      Mark("symbol", "corners",
           {{"x", Field("u", "u")},
            {"y", Field("v", "v")},
            {"shape", {{"value", "circle"}}},
            {"size", {{"value", 18}}},
            {"stroke", {{"signal", "datum.status == 'fitted' ? '#00e5ff' : '#ff00ff'"}}},
            {"strokeWidth", {{"value", 1.2}}},
            {"tooltip", tip}}));
  Arrows(&marks, "arrows", "#ff3b30", tip);
  ScaleBar(&marks, 40.0, Significant(reference_px, 3) + " px", w);
  Figure f;
  // A file name and an HTML id: shot ids are free text (shots.csv).
  f.name = "photo_";
  for (char ch : shot)
    f.name += std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '.' ? ch : '_';
  f.section = "photos";
  f.title = "Photo " + shot + ", zoom " + std::to_string(zoom);
  f.caption =
      "The photo with its detected corners (cyan: fitted, magenta: left out, see the tooltip) "
      "and each fitted corner's residual (observed minus predicted at the final model, the "
      "board at its estimated pose), scaled by the red reference arrow. Arrows that turn "
      "together across the board point at the board pose or the camera model, a single long "
      "one at a bad detection.";
  f.spec = spec;
  f.summary = {{"shot", shot},           {"zoom", zoom},  {"fitted_rows", fitted},
               {"rows", rows.size()},    {"rms_px", rms}, {"arrow_scale_px", reference_px},
               {"photo", !photo.empty()}};
  return f;
}

std::map<std::string, std::string> PhotoFiles(const PhotoSessionSummary& photos) {
  std::map<std::string, std::string> out;
  const fs::path base = fs::path(photos.shots_path).parent_path();
  for (const PhotoSessionSummary::Photo& p : photos.photos) {
    const fs::path img(p.image);
    out[p.shot] = (img.is_absolute() ? img : base / img).string();
  }
  return out;
}

}  // namespace rtscalib::app
