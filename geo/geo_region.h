#pragma once

// A region on the globe: a query's position prior (docs/geo.md) and the part of a city that
// `cwloc-index extract --near` keeps. Both select the same cameras.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "geo/georeference.h"
#include "results/priors.h"  // GeoRegion

namespace cwloc {

// "LAT LON [HEIGHT] RADIUS_M"; throws InputError naming `what` and the problem.
GeoRegion ParseGeoRegion(const std::string& text, const std::string& what);

// A region read field by field (a priors file line), range-checked like ParseGeoRegion's.
GeoRegion CheckedGeoRegion(double latitude, double longitude, std::optional<double> height,
                           double radius, const std::string& what);

// Whitespace-separated finite numbers; nullopt when a field is not one.
std::optional<std::vector<double>> ParseFiniteNumbers(const std::string& text);

// The region in one frame's ENU metres, to test many cameras against.
class EnuRegion {
 public:
  EnuRegion(const GeoFrame& frame, const GeoRegion& region);
  bool Contains(const Eigen::Vector3d& enu) const { return Distance(enu) <= radius_; }
  // Metres from the centre; horizontal when the region has no height.
  double Distance(const Eigen::Vector3d& enu) const;

 private:
  Eigen::Vector3d center_;
  bool horizontal_;
  double radius_;
};

}  // namespace cwloc
