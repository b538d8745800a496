#include "libcalib/io/covariance_io.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "libcalib/fit/parameter_layout.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"
#include "libcalib/io/yaml_reader.h"

namespace rtscalib {
namespace {

constexpr const char* kCovarianceFormat = "rtscalib-covariance";
constexpr int kCovarianceVersion = 1;

// YAML double-quoted text (block names and units hold brackets and commas).
std::string Quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string CovariancePathFor(const std::string& model_yaml) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path resolved = fs::canonical(model_yaml, ec);
  if (ec) resolved = fs::path(model_yaml);
  return (resolved.parent_path() / "covariance.yaml").string();
}

void WriteCovarianceYaml(const std::string& path, const InstrumentModel& model) {
  const std::vector<LayoutBlock> layout = ParameterLayout(model);
  const int n = LayoutSize(layout);
  const Eigen::MatrixXd& p = model.sigmas.covariance;
  if (p.rows() != n || p.cols() != n) {
    throw std::invalid_argument("covariance.yaml: the model's covariance is " +
                                std::to_string(p.rows()) + "x" + std::to_string(p.cols()) +
                                ", its parameter vector has " + std::to_string(n));
  }
  std::ofstream f(path);
  f << "# The fit's full parameter covariance of the model.yaml beside this file\n"
       "# (docs/library.md): rows and columns in `blocks` order, tangent coordinates\n"
       "# of libcalib/fit/parameter_layout.h; `at` = the block's values in model.yaml.\n";
  f << "format: " << kCovarianceFormat << "\nversion: " << kCovarianceVersion
    << "\nparameters: " << n << "\nblocks:\n";
  for (const LayoutBlock& b : layout) {
    f << "  - {name: " << Quoted(b.name) << ", offset: " << b.offset << ", size: " << b.size
      << ", unit: " << Quoted(b.unit) << ", at: [";
    const double* x = b.const_data(model);
    for (int i = 0; i < b.ambient; ++i) f << (i ? ", " : "") << FormatDouble(x[i]);
    f << "]}\n";
  }
  f << "covariance:\n";
  for (int r = 0; r < n; ++r) {
    f << "  - [";
    for (int c = 0; c < n; ++c) f << (c ? ", " : "") << FormatDouble(p(r, c));
    f << "]\n";
  }
  f.close();
  if (!f) throw std::runtime_error("could not write " + path);
}

void ReadCovarianceYaml(const std::string& path, InstrumentModel* model) {
  const YamlDocument doc = YamlDocument::Load(path);
  const YamlNode root = doc.Root();
  root.RequireFormat(kCovarianceFormat, kCovarianceVersion);
  const std::vector<LayoutBlock> layout = ParameterLayout(*model);
  const int n = LayoutSize(layout);
  const YamlNode count = root.Require("parameters");
  if (count.AsInt() != n) {
    count.Fail(std::to_string(n) + " (the parameters of the model.yaml beside it)");
  }
  const YamlNode blocks = root.Require("blocks");
  const std::vector<YamlNode> items = blocks.Items();
  if (items.size() != layout.size()) {
    blocks.Fail(std::to_string(layout.size()) + " blocks (the model.yaml beside it)");
  }
  for (size_t k = 0; k < layout.size(); ++k) {
    const LayoutBlock& b = layout[k];
    const YamlNode& item = items[k];
    const YamlNode name = item.Require("name");
    if (name.AsString() != b.name)
      name.Fail("'" + b.name + "' (the model's block " + std::to_string(k) + ")");
    const YamlNode offset = item.Require("offset");
    if (offset.AsInt() != b.offset) offset.Fail(std::to_string(b.offset));
    const YamlNode size = item.Require("size");
    if (size.AsInt() != b.size) size.Fail(std::to_string(b.size));
    std::string unit;
    item.Read("unit", &unit);
    const YamlNode at = item.Require("at");
    const std::vector<double> values = at.AsDoubles(b.ambient);
    const double* x = b.const_data(*model);
    for (int i = 0; i < b.ambient; ++i) {
      if (values[i] != x[i]) {
        at.Fail("the values of '" + b.name +
                "' in the model.yaml beside it (this covariance belongs to another model: " +
                "value " + std::to_string(i) + " is " + FormatDouble(x[i]) + " there)");
      }
    }
  }
  const YamlNode rows = root.Require("covariance");
  const std::vector<YamlNode> row_items = rows.Items();
  if (static_cast<int>(row_items.size()) != n) rows.Fail(std::to_string(n) + " rows");
  Eigen::MatrixXd p(n, n);
  for (int r = 0; r < n; ++r) {
    const std::vector<double> row = row_items[r].AsDoubles(n);
    for (int c = 0; c < n; ++c) p(r, c) = row[c];
  }
  for (int r = 0; r < n; ++r) {
    if (!(p(r, r) >= 0)) row_items[r].Fail("a variance >= 0 on the diagonal");
    for (int c = 0; c < r; ++c) {
      if (p(r, c) != p(c, r)) {
        row_items[r].Fail("a symmetric matrix (entry " + std::to_string(c) + " equal to row " +
                          std::to_string(c) + "'s entry " + std::to_string(r) + ")");
      }
    }
  }
  doc.CheckAllKeysUsed();
  model->sigmas.covariance = std::move(p);
}

}  // namespace rtscalib
