#include "geo/geo_region.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "base/error.h"

namespace cwloc {

std::optional<std::vector<double>> ParseFiniteNumbers(const std::string& text) {
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

GeoRegion CheckedGeoRegion(double latitude, double longitude, std::optional<double> height,
                           double radius, const std::string& what) {
  if (std::abs(latitude) > 90)
    throw InputError(what + ": latitude " + std::to_string(latitude) + " is outside [-90, 90]");
  if (longitude < -180 || longitude >= 360)
    throw InputError(what + ": longitude " + std::to_string(longitude) + " is outside [-180, 360)");
  if (!(radius > 0)) throw InputError(what + ": the radius must be a positive number of metres");
  return {latitude, longitude, height, radius};
}

GeoRegion ParseGeoRegion(const std::string& text, const std::string& what) {
  const auto values = ParseFiniteNumbers(text);
  if (!values || values->size() < 3 || values->size() > 4)
    throw InputError(what + " '" + text + "': expected 'LAT LON [HEIGHT] RADIUS_M'");
  const std::vector<double>& v = *values;
  const std::optional<double> height = v.size() == 4 ? std::optional(v[2]) : std::nullopt;
  return CheckedGeoRegion(v[0], v[1], height, v.back(), what);
}

EnuRegion::EnuRegion(const GeoFrame& frame, const GeoRegion& region)
    : center_(frame.GeodeticToEnu(
          {region.latitude_deg, region.longitude_deg, region.height_m.value_or(0.0)})),
      horizontal_(!region.height_m),
      radius_(region.radius_m) {}

double EnuRegion::Distance(const Eigen::Vector3d& enu) const {
  Eigen::Vector3d offset = enu - center_;
  // Without a height, the ENU "up" offset of a distant fix is mostly the earth's curvature.
  if (horizontal_) offset.z() = 0;
  return offset.norm();
}

}  // namespace cwloc
