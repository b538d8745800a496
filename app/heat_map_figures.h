// Heat maps over a camera's image, as Vega specs (plot/vega_spec.h): the
// projection uncertainty of a zoom (libcalib/api/uncertainty_map.h) and the
// projection difference of a zoom between two models (`rtscalib compare`,
// libcalib/api/compare.h).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/plot/vega_spec.h"
#include "libcalib/api/compare.h"
#include "libcalib/api/uncertainty_map.h"
#include "libcalib/model/instrument.h"

namespace rtscalib::app {

// Colours of a heat map's values: linear from zero, or logarithmic for
// values over orders of magnitude (a projection uncertainty: hundredths of
// a pixel among the points, tens where the distortion is extrapolated to
// the image corners; on a linear scale the cells among the points look
// alike).
enum class ColourScale { kLinear, kLog };

// A heat map over a width x height image: cols x rows cells (row-major from
// the top-left), NaN: not predictable (grey); `inside` false: outside the
// valid region (faded, struck through); `hull`: the valid region's outline.
nlohmann::json HeatMapSpec(const std::string& title, const std::string& subtitle, int width,
                           int height, int cols, int rows, const std::vector<double>& value,
                           const std::vector<unsigned char>& inside, const std::string& legend,
                           const std::vector<Eigen::Vector2d>& hull,
                           ColourScale colours = ColourScale::kLinear);

// The projection uncertainty of one zoom (`full`: from the fit's full
// covariance, else its diagonal approximation).
Figure UncertaintyFigure(const UncertaintyMap& m, const UncertaintyMapOptions& o,
                         const CameraTool& cam, bool full);

// The projection difference of one zoom between two models (`rtscalib
// compare`, libcalib/api/compare.h) as a heat map.
Figure DifferenceFigure(const ZoomDifference& d);

}  // namespace rtscalib::app
