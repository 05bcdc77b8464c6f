#pragma once

// The generated city on the globe (docs/synth.md, "On the globe"): with --geo, the city centre
// lies at a WGS84 position, the written model is in an arbitrary SfM-like frame (a seeded
// similarity of the world frame), and the mapping images get noisy GPS positions (georef.txt)
// and the queries their true positions and noisy priors (queries_geo.txt, query_priors.txt).
// Everything here draws from its own SplitMix64 streams, so the rest of the output does not
// change with these knobs.

#include <Eigen/Core>
#include <optional>
#include <string>

#include "colmap/reconstruction.h"
#include "geo/georeference.h"
#include "tools/synth/city_scene.h"

namespace cwloc::synth {

// The defaults of the --geo knobs (cwloc-synth --help and docs/synth.md print these).
inline constexpr double kDefaultGpsNoise = 3;              // metres, sigma per axis
inline constexpr double kDefaultGpsOutliers = 0;           // share of mapping images
inline constexpr double kDefaultPriorPositionError = 0;    // metres, horizontal
inline constexpr double kDefaultPriorRadius = 50;          // metres
inline constexpr double kDefaultPriorGravityErrorDeg = 0;  // degrees

// The model frame's random similarity: the city's larger horizontal side spans this many model
// units, and each translation component is within +-kModelTranslationRange units.
inline constexpr double kModelMinSpan = 2;
inline constexpr double kModelMaxSpan = 10;
inline constexpr double kModelTranslationRange = 5;

// GPS outliers are displaced this far horizontally (uniform), and up to this far vertically.
inline constexpr double kGpsOutlierMinOffset = 100;   // metres
inline constexpr double kGpsOutlierMaxOffset = 1000;  // metres
inline constexpr double kGpsOutlierMaxVertical = 50;  // metres

struct GeoOptions {
  // --geo: the WGS84 position (ellipsoidal height) of the city centre at ground level. Unset:
  // no globe, the model is written in world coordinates and no geo file is written.
  std::optional<Geodetic> origin;
  double gps_noise = kDefaultGpsNoise;        // metres, Gaussian sigma per ENU axis
  double gps_outliers = kDefaultGpsOutliers;  // share of mapping images that are wildly wrong
  double prior_position_error = kDefaultPriorPositionError;       // metres, exact, horizontal
  double prior_radius = kDefaultPriorRadius;                      // metres, written as is
  double prior_gravity_error_deg = kDefaultPriorGravityErrorDeg;  // degrees, exact
};

// The frame the model is written in: model = scale * rotation * (world - enu_origin) +
// translation, where enu_origin is the world point at the city centre on the ground, so that
// world - enu_origin are the ENU coordinates at GeoOptions::origin (world's axes are east,
// north, up). Without --geo the frame is the identity and is never applied, so the output is
// the world frame bit for bit.
struct ModelFrame {
  bool identity = true;
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d enu_origin = Eigen::Vector3d::Zero();  // in world coordinates

  Eigen::Vector3d ModelFromWorld(const Eigen::Vector3d& world) const;
  Eigen::Vector3d EnuFromWorld(const Eigen::Vector3d& world) const { return world - enu_origin; }
  // COLMAP's pose of an image in the model frame (world-to-camera, quaternion w >= 0).
  colmap::Rigid3d CamFromModel(const CityScene& scene, const SceneImage& image) const;
  // The similarity model -> ENU at `origin` (what a georeference fit should find).
  Georeference EnuFromModel(const Geodetic& origin) const;
};

// The identity without --geo; otherwise the seeded random similarity: rotation uniform on
// SO(3), scale so that the city's larger side spans [kModelMinSpan, kModelMaxSpan] units,
// translation components in +-kModelTranslationRange units.
ModelFrame MakeModelFrame(const CityScene& scene, const GeoOptions& geo);

// The number of mapping images whose GPS position is an outlier: round(gps_outliers x images).
size_t NumGpsOutliers(const GeoOptions& geo, size_t mapping_images);

// The files --geo adds (docs/synth.md has their exact formats), and the scale_to_metres.txt
// that replaces the identity one.
struct GeoFiles {
  std::string georef;           // georef.txt: NAME LAT LON HEIGHT per registered mapping image
  std::string georef_outliers;  // georef_outliers.txt: the outliers' names, one per line
  std::string queries_geo;      // queries_geo.txt: NAME LAT LON HEIGHT, the true query centres
  std::string query_priors;     // query_priors.txt: position and gravity priors per query
  std::string scale_to_metres;  // the similarity model -> ENU metres at the --geo origin
};

// Requires geo.origin (std::logic_error otherwise: a bug, exit code 3).
GeoFiles MakeGeoFiles(const CityScene& scene, const GeoOptions& geo, const ModelFrame& frame);

}  // namespace cwloc::synth
