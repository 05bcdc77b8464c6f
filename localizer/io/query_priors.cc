#include "localizer/io/query_priors.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "format/base/bounded_file.h"
#include "format/base/error.h"

namespace cwloc {
namespace {

// Whitespace-separated numbers; nullopt when a field is not a finite number.
std::optional<std::vector<double>> ParseNumbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> values;
  std::string field;
  while (in >> field) {
    char* end = nullptr;
    const double value = std::strtod(field.c_str(), &end);
    if (end != field.c_str() + field.size() || !std::isfinite(value)) return std::nullopt;
    values.push_back(value);
  }
  return values;
}

PositionPrior CheckedPositionPrior(double latitude, double longitude, std::optional<double> height,
                                   double radius, const std::string& what) {
  if (std::abs(latitude) > 90)
    throw InputError(what + ": latitude " + std::to_string(latitude) + " is outside [-90, 90]");
  if (longitude < -180 || longitude >= 360)
    throw InputError(what + ": longitude " + std::to_string(longitude) + " is outside [-180, 360)");
  if (!(radius > 0)) throw InputError(what + ": the radius must be a positive number of metres");
  return {latitude, longitude, height, radius, PriorSource::kOption};
}

std::array<double, 3> CheckedGravity(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 3 || std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) < 1e-9)
    throw InputError(what + ": expected a non-zero vector 'GX GY GZ' (camera frame)");
  return {v[0], v[1], v[2]};
}

}  // namespace

PositionPrior ParsePositionPrior(const std::string& text, const std::string& what) {
  const auto values = ParseNumbers(text);
  if (!values || values->size() < 3 || values->size() > 4)
    throw InputError(what + " '" + text + "': expected 'LAT LON [HEIGHT] RADIUS_M'");
  const std::vector<double>& v = *values;
  const std::optional<double> height = v.size() == 4 ? std::optional(v[2]) : std::nullopt;
  return CheckedPositionPrior(v[0], v[1], height, v.back(), what);
}

std::array<double, 3> ParseGravityPrior(const std::string& text, const std::string& what) {
  const auto values = ParseNumbers(text);
  if (!values) throw InputError(what + " '" + text + "': expected 'GX GY GZ'");
  return CheckedGravity(*values, what);
}

std::unordered_map<std::string, QueryPriors> ReadPriorsFile(const std::filesystem::path& path) {
  CheckInputFile(path, kPriorsFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the priors file");
  std::unordered_map<std::string, QueryPriors> priors;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string where = path.string() + ":" + std::to_string(number);
    std::istringstream fields(line);
    std::string name, kind;
    if (!(fields >> name) || name[0] == '#') continue;
    if (!(fields >> kind)) throw InputError(where + ": expected 'NAME position|gravity ...'");
    std::string rest;
    std::getline(fields, rest);
    QueryPriors& query = priors[name];
    if (kind == "position") {
      // HEIGHT may be '-': the fix has no usable height.
      std::istringstream parts(rest);
      std::vector<std::string> tokens;
      for (std::string token; parts >> token;) tokens.push_back(token);
      if (tokens.size() != 4)
        throw InputError(where + ": expected 'NAME position LAT LON HEIGHT|- RADIUS_M'");
      const bool no_height = tokens[2] == "-";
      if (no_height) tokens[2] = "0";
      const auto v = ParseNumbers(tokens[0] + " " + tokens[1] + " " + tokens[2] + " " + tokens[3]);
      if (!v) throw InputError(where + ": a position field is not a number");
      if (query.position) throw InputError(where + ": a second position for '" + name + "'");
      query.position = CheckedPositionPrior(
          (*v)[0], (*v)[1], no_height ? std::nullopt : std::optional((*v)[2]), (*v)[3], where);
      query.position->source = PriorSource::kPriorsFile;
    } else if (kind == "gravity") {
      const auto v = ParseNumbers(rest);
      if (!v) throw InputError(where + ": a gravity field is not a number");
      if (query.gravity) throw InputError(where + ": a second gravity for '" + name + "'");
      query.gravity = CheckedGravity(*v, where);
    } else {
      throw InputError(where + ": unknown prior '" + kind + "', expected position or gravity");
    }
  }
  return priors;
}

std::optional<PositionPrior> ExifPositionPrior(const Query& query, double radius_m) {
  if (!query.photo || !query.photo->exif_gps) return std::nullopt;
  const GpsFix& fix = *query.photo->exif_gps;
  return PositionPrior{fix.latitude_deg, fix.longitude_deg, std::nullopt, radius_m,
                       PriorSource::kExif};
}

}  // namespace cwloc
