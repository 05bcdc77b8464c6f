#pragma once

// Fitting a georeference to model camera centres with known positions on the globe
// (a georef file, the photos' EXIF GPS): a robust similarity fit (docs/geo.md).

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "geo/georeference.h"

namespace cwloc {

// One line of a georef file: IMAGE_NAME LAT LON HEIGHT [SIGMA_M].
struct GeoObservation {
  std::string image_name;
  Geodetic position;
  double sigma_m = 0;  // per-axis standard deviation; <= 0: GeoFitOptions.default_sigma_m
};

// Reads a georef file: `IMAGE_NAME LAT LON HEIGHT [SIGMA_M]` per line, WGS84 degrees and
// ellipsoidal metres, fields separated by blanks (so no blanks in names); lines starting with
// '#' and blank lines skipped; LON in [-180, 360). Throws InputError "<file>:<line>: ..." naming
// the field (missing or extra field, bad number, latitude or longitude out of range,
// sigma <= 0, duplicate name), "<file>: no observations ..." for a file without any.
std::vector<GeoObservation> ReadGeorefFile(const std::filesystem::path& path);

struct GeoFitOptions {
  // Positions without their own sigma get this one (a phone's GPS, metres per axis).
  double default_sigma_m = 5.0;
  // An observation is an inlier when its residual is within this many sigmas (3D).
  double inlier_sigmas = 3.5;
  // RANSAC stops after this many samples, or earlier once an all-inlier sample has been drawn
  // with this confidence at the best inlier ratio so far.
  int max_iterations = 2000;
  double confidence = 0.9999;
  uint64_t seed = 0;  // SplitMix64's: the same seed gives the same fit on every platform
};

struct GeoFitResult {
  Georeference georeference;        // ENU origin at the geodetic centroid of the inliers
  std::vector<char> inliers;        // per observation: used by the final least squares
  std::vector<double> residuals_m;  // per observation: |fitted ENU - observed ENU|, metres
  int num_inliers = 0;
  double rms_residual_m = 0;  // sqrt(mean of residual^2) over the inliers
};

// model_centers[i] is the camera centre of the image observed at observations[i].
// RANSAC over 3-point samples, then weighted least squares (Umeyama with 1/sigma^2 weights,
// the exact minimum of the weighted squared residuals) on the inliers, iterated to a fixed
// inlier set (at most 10 rounds). Throws InputError "georeference fit: ..." for fewer than 3
// observations, a non-finite centre, an invalid position or sigma, an option out of range,
// coincident or collinear centres or positions (of all observations or of the inliers), fewer
// than 3 inliers, or a non-finite or non-positive scale; std::invalid_argument when the spans'
// sizes differ.
GeoFitResult FitGeoreference(std::span<const Eigen::Vector3d> model_centers,
                             std::span<const GeoObservation> observations,
                             const GeoFitOptions& options = {});

}  // namespace cwloc
