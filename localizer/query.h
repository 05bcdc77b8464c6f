#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "camera/camera_models.h"
#include "geo/geo_region.h"

namespace cwloc {

// What the pose stage may trust about the query camera; COLMAP's registrator draws the same
// line with prior_focal_length.
enum class Calibration {
  kKnown,       // every parameter is trusted and held fixed
  kFocalPrior,  // params hold a focal guess (EXIF, --focal): it seeds the estimate
  kUnknown,     // only the image size: P4Pf estimates the focal
};

inline constexpr std::array<std::string_view, 3> kCalibrationNames = {"known", "focal-prior",
                                                                      "unknown"};

inline std::string_view CalibrationName(Calibration calibration) {
  return kCalibrationNames[static_cast<size_t>(calibration)];
}

// Where the query camera came from, reported in the JSON.
enum class IntrinsicsSource {
  kCameraOption,     // --camera
  kQueryList,        // a query-list line's "MODEL W H PARAMS"
  kImageSizeOption,  // --image-size
  kFocalOption,      // --focal
  kExif,             // the photo's EXIF focal length
  kDatabase,         // the COLMAP database's camera
  kNone,             // nothing but the photo's size
};

inline constexpr std::array<std::string_view, 7> kIntrinsicsSourceNames = {
    "camera-option", "query-list", "image-size-option", "focal-option", "exif", "database", "none"};

inline std::string_view IntrinsicsSourceName(IntrinsicsSource source) {
  return kIntrinsicsSourceNames[static_cast<size_t>(source)];
}

// The query's camera. Unless the calibration is known, the principal point is taken at the
// image centre and the focal length (with a radial distortion term) is estimated.
struct QueryCamera {
  CameraModelId model_id = CameraModelId::kSimplePinhole;
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<double> params;
  Calibration calibration = Calibration::kKnown;
  IntrinsicsSource source = IntrinsicsSource::kCameraOption;

  bool FocalKnown() const { return calibration == Calibration::kKnown; }

  // The principal point assumed when the focal length is unknown.
  std::array<double, 2> ImageCenter() const { return {width / 2.0, height / 2.0}; }
};

// The camera of a focal prior for a width x height image: SIMPLE_RADIAL (f, w/2, h/2, 0).
inline QueryCamera FocalPriorCamera(double focal_length_px, uint32_t width, uint32_t height,
                                    IntrinsicsSource source) {
  return {CameraModelId::kSimpleRadial,
          width,
          height,
          {focal_length_px, width / 2.0, height / 2.0, 0.0},
          Calibration::kFocalPrior,
          source};
}

// A width x height image's camera when only its size is known: SIMPLE_PINHOLE (0, w/2, h/2).
inline QueryCamera UnknownFocalCamera(uint32_t width, uint32_t height, IntrinsicsSource source) {
  return {CameraModelId::kSimplePinhole, width, height, {0.0, width / 2.0, height / 2.0},
          Calibration::kUnknown,         source};
}

// A photo's EXIF GPS position (its altitude, above mean sea level, is not kept).
struct GpsFix {
  double latitude_deg = 0;
  double longitude_deg = 0;
};

// How a photo query became features (absent for feature files and database queries).
struct PhotoInfo {
  uint32_t extraction_width = 0;  // the image SIFT ran on, after --max-image-size
  uint32_t extraction_height = 0;
  int first_octave = -1;          // SIFT's, as --first-octave set it
  uint32_t max_features = 0;      // SIFT's cap, as --max-features set it
  double extraction_seconds = 0;  // decoding, EXIF, resizing and SIFT
  std::optional<GpsFix> exif_gps;
};

// Where a query's prior came from, reported in the JSON.
enum class PriorSource { kOption, kFile, kExif };
inline constexpr std::array<std::string_view, 3> kPriorSourceNames = {"option", "priors-file",
                                                                      "exif"};

// A GPS fix: the query was taken in this region. Localization then considers only clusters
// with a camera in it.
struct PositionPrior : GeoRegion {
  PriorSource source = PriorSource::kOption;
};

// A query image's own features: keypoints in COLMAP's pixel convention and N x 128 uint8
// SIFT descriptors in COLMAP's normalization.
struct Query {
  std::string name;
  // Where the query was read from (a feature file, a database image), for error messages.
  std::string source;
  QueryCamera camera;
  std::vector<float> keypoints;      // x0, y0, x1, y1, ...
  std::vector<uint8_t> descriptors;  // N x 128
  std::optional<PhotoInfo> photo;
  // Priors; both need a georeferenced index (docs/geo.md).
  std::optional<PositionPrior> position_prior;
  // The direction gravity pulls in the camera frame (x right, y down, z forward), as a phone's
  // accelerometer gives it at rest (negated: an accelerometer measures the upward reaction).
  std::optional<std::array<double, 3>> gravity;

  uint32_t NumFeatures() const { return static_cast<uint32_t>(keypoints.size() / 2); }
  const uint8_t* Descriptor(uint32_t i) const { return descriptors.data() + size_t{i} * 128; }
  std::string Source() const { return source.empty() ? "query '" + name + "'" : source; }
};

}  // namespace cwloc
