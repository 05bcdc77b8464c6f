#pragma once

// Test helpers for geo/: WGS84 written out from its definition (independent of
// GeographicLib), random rotations and numbers from the tests' shared PRNG. Several draws in
// one expression go in braces, which fix their order (parentheses do not), so every platform
// generates the same data.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "geo/georeference.h"
#include "tests/test_util.h"

namespace cwloc::test {

constexpr double kWgs84A = 6378137.0;
constexpr double kWgs84F = 1 / 298.257223563;
constexpr double kWgs84E2 = kWgs84F * (2 - kWgs84F);

inline double Radians(double degrees) { return degrees * std::numbers::pi / 180; }
inline double Degrees(double radians) { return radians * 180 / std::numbers::pi; }

// Earth-centred earth-fixed metres of a WGS84 position.
inline Eigen::Vector3d Ecef(const Geodetic& g) {
  const double lat = Radians(g.latitude_deg), lon = Radians(g.longitude_deg);
  const double n = kWgs84A / std::sqrt(1 - kWgs84E2 * std::sin(lat) * std::sin(lat));
  return {(n + g.height_m) * std::cos(lat) * std::cos(lon),
          (n + g.height_m) * std::cos(lat) * std::sin(lon),
          (n * (1 - kWgs84E2) + g.height_m) * std::sin(lat)};
}

// The rotation ENU-at-(lat, lon) from ECEF: rows east, north, up.
inline Eigen::Matrix3d EnuFromEcef(double latitude_deg, double longitude_deg) {
  const double lat = Radians(latitude_deg), lon = Radians(longitude_deg);
  Eigen::Matrix3d r;
  r << -std::sin(lon), std::cos(lon), 0,                                              //
      -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat),  //
      std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat);
  return r;
}

inline double Uniform(double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(Rng());
}

inline double Normal(double sigma) { return std::normal_distribution<double>(0, sigma)(Rng()); }

inline Eigen::Quaterniond RandomRotation() {
  Eigen::Quaterniond q{Normal(1), Normal(1), Normal(1), Normal(1)};
  return q.normalized();
}

inline Eigen::Vector3d RandomUnitVector() {
  return Eigen::Vector3d{Normal(1), Normal(1), Normal(1)}.normalized();
}

// Angle in radians between two rotations.
inline double AngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

}  // namespace cwloc::test
