// The pictures of a run (PNG, drawn with OpenCV), in the order report.html
// shows them:
//   error maps      rms error per pointing over phi (x) and theta (y, zenith at
//                   the top), one panel per face, one figure per tool (EDM, camera
//                   rows and image points per zoom); the faces of one tool share
//                   one colour scale; critical regions are hatched
//   ladder          error per observation group across the runs in the output
//                   folder's history and across this run's stepwise rungs
//   image arrows    image-space residuals per zoom (observed minus predicted
//                   pixel) at the observed points, averaged per image cell, with
//                   a scale bar
//   histograms      residual coordinates per group against the Gaussian of the
//                   fitted sigma
// Only formats what the pipeline and the diagnosis computed.
#pragma once

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "app/pipeline.h"
#include "libcalib/api/compare.h"

namespace rtscalib::app {

struct Figure {
  std::string name;     // file name, e.g. "error_map_edm.png"
  std::string section;  // "maps", "ladder", "image", "histograms"
  std::string title;
  std::string caption;
  cv::Mat image;  // BGR, 8 bit
  std::vector<unsigned char> png;  // the image encoded once, when written (EncodePng)
};

// `history` = report.json's "history" array (earlier runs, oldest first).
std::vector<Figure> MakeFigures(const PipelineResult& result, const nlohmann::json& history);

// The projection difference of one zoom between two models (`rtscalib
// compare`, libcalib/api/compare.h) as a heat map.
Figure DifferenceFigure(const ZoomDifference& d);

// PNG bytes of a figure (for writing and for embedding).
std::vector<unsigned char> EncodePng(const cv::Mat& image);

}  // namespace rtscalib::app
