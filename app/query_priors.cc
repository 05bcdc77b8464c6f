#include "app/query_priors.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "base/bounded_file.h"
#include "base/error.h"

namespace cwloc {
namespace {

std::array<double, 3> CheckedGravity(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 3 || std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) < 1e-9)
    throw InputError(what + ": expected a non-zero vector 'GX GY GZ' (camera frame)");
  return {v[0], v[1], v[2]};
}

}  // namespace

PositionPrior ParsePositionPrior(const std::string& text, const std::string& what) {
  return {ParseGeoRegion(text, what), PriorSource::kOption};
}

std::array<double, 3> ParseGravityPrior(const std::string& text, const std::string& what) {
  const auto values = ParseFiniteNumbers(text);
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
      const auto v =
          ParseFiniteNumbers(tokens[0] + " " + tokens[1] + " " + tokens[2] + " " + tokens[3]);
      if (!v) throw InputError(where + ": a position field is not a number");
      if (query.position) throw InputError(where + ": a second position for '" + name + "'");
      query.position = {
          CheckedGeoRegion((*v)[0], (*v)[1], no_height ? std::nullopt : std::optional((*v)[2]),
                           (*v)[3], where),
          PriorSource::kFile};
    } else if (kind == "gravity") {
      const auto v = ParseFiniteNumbers(rest);
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
  if (!query.exif_gps) return std::nullopt;
  const GpsFix& fix = *query.exif_gps;
  return PositionPrior{{fix.latitude_deg, fix.longitude_deg, std::nullopt, radius_m},
                       PriorSource::kExif};
}

}  // namespace cwloc
