#include "libcalib/io/shots.h"

#include <filesystem>
#include <limits>
#include <map>

#include "libcalib/io/csv.h"
#include "libcalib/text/errors.h"
#include "libcalib/text/number_text.h"

namespace rtscalib {

ShotsFile ReadShots(const std::string& path, AngleUnit unit) {
  const CsvTable t = CsvTable::Read(path, {{"face", "zoom", "phi", "theta", "image"},
                                           {"shot", "placement", "focus_distance"},
                                           /*covariates=*/true});
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  ShotsFile out;
  out.path = path;
  out.angle_unit = unit;
  out.notes = t.notes();
  out.has_placements = t.Has("placement");
  out.covariates = t.covariates();
  std::map<std::string, int> line_of_shot;
  for (int row = 0; row < t.NumRows(); ++row) {
    PhotoShot s;
    s.line = t.Line(row);
    const std::optional<long long> face = ParseInteger(t.Text(row, "face"));
    if (!face || (*face != 1 && *face != 2)) t.Fail(row, "face", "1 or 2");
    s.face = static_cast<int>(*face);
    const std::optional<long long> zoom = ParseInteger(t.Text(row, "zoom"));
    if (!zoom || *zoom < 0 || *zoom > std::numeric_limits<int>::max()) {
      t.Fail(row, "zoom", "a zoom level (integer >= 0)");
    }
    s.zoom = static_cast<int>(*zoom);
    s.has_reading = t.OptionalReading(row, unit, &s.phi, &s.theta);
    s.placement = t.Text(row, "placement");
    if (!t.Empty(row, "focus_distance")) {
      s.focus_distance = t.Number(row, "focus_distance");
      if (!(s.focus_distance > 0)) {
        t.Fail(row, "focus_distance", "the focus distance in metres (> 0), or empty");
      }
    }
    for (size_t k = 0; k < out.covariates.size(); ++k) {
      s.covariates.push_back(t.Covariate(row, static_cast<int>(k)));
    }
    s.image = t.Text(row, "image");
    if (s.image.empty()) t.Fail(row, "image", "an image file (relative to the CSV's folder)");
    const std::filesystem::path image(s.image);
    s.image_path = (image.is_absolute() ? image : folder / image).lexically_normal().string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(s.image_path, ec)) {
      throw InputError::Cell(path, s.line, "image", "an existing image file", s.image_path);
    }
    s.shot = t.Text(row, "shot");
    if (s.shot.empty()) s.shot = image.stem().string();
    if (s.shot.empty()) t.Fail(row, "image", "an image file name with a stem (the shot id)");
    const auto [it, inserted] = line_of_shot.emplace(s.shot, s.line);
    if (!inserted) {
      throw InputError::Cell(path, s.line, t.Has("shot") ? "shot" : "image",
                             "a shot id not used before (line " + std::to_string(it->second) +
                                 " has it; without a `shot` column the id is the image's stem)",
                             s.shot);
    }
    out.shots.push_back(std::move(s));
  }
  return out;
}

}  // namespace rtscalib
