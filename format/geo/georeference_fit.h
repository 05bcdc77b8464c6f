#pragma once

// Fitting a georeference to model camera centres with known positions on the globe
// (a georef file, the photos' EXIF GPS): a robust similarity fit (docs/geo.md).

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "format/geo/georeference.h"

namespace cwloc {

// One line of a georef file: IMAGE_NAME LAT LON HEIGHT [SIGMA_M].
struct GeoObservation {
  std::string image_name;
  Geodetic position;
  double sigma_m = 0;  // per-axis standard deviation; <= 0: GeoFitOptions.default_sigma_m
};

// Reads a georef file: `IMAGE_NAME LAT LON HEIGHT [SIGMA_M]` per line, WGS84 degrees and
// ellipsoidal metres; '#' comments and blank lines skipped. Throws InputError naming the file,
// the line and the field (bad number, latitude out of range, sigma <= 0, duplicate name).
std::vector<GeoObservation> ReadGeorefFile(const std::filesystem::path& path);

struct GeoFitOptions {
  // Positions without their own sigma get this one (a phone's GPS, metres per axis).
  double default_sigma_m = 5.0;
  // An observation is an inlier when its residual is within this many sigmas (3D).
  double inlier_sigmas = 3.5;
  int max_iterations = 2000;
  double confidence = 0.9999;
  uint64_t seed = 0;
};

struct GeoFitResult {
  Georeference georeference;        // ENU origin at the geodetic centroid of the inliers
  std::vector<char> inliers;        // per observation
  std::vector<double> residuals_m;  // per observation: |fitted ENU - observed ENU|
  int num_inliers = 0;
  double rms_residual_m = 0;  // over the inliers
};

// model_centers[i] is the camera centre of the image observed at observations[i].
// RANSAC over 3-point samples, then weighted least squares (Umeyama with 1/sigma^2 weights,
// the exact minimum of the weighted squared residuals) on the inliers, iterated to a fixed
// inlier set. Throws InputError for fewer than 3 observations, collinear or coincident
// centres or positions, fewer than 3 inliers, or a non-positive scale.
GeoFitResult FitGeoreference(std::span<const Eigen::Vector3d> model_centers,
                             std::span<const GeoObservation> observations,
                             const GeoFitOptions& options = {});

}  // namespace cwloc
