#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "camera/camera_models.h"
#include "results/camera.h"
#include "results/localization_result.h"
#include "results/priors.h"

namespace cwloc {

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

// A camera as a result reports it: the model by its COLMAP name.
inline CameraUsed CameraUsedOf(const QueryCamera& camera) {
  CameraUsed used;
  used.model = std::string(CameraModelName(camera.model_id));
  used.width = camera.width;
  used.height = camera.height;
  used.params = camera.params;
  used.calibration = camera.calibration;
  used.intrinsics_source = camera.source;
  return used;
}

// The model of a camera a result reports (CameraUsedOf's name).
inline CameraModelId ModelIdOf(const Camera& camera) {
  const std::optional<CameraModelInfo> model = FindCameraModel(camera.model);
  if (!model) throw std::logic_error("a result's camera model '" + camera.model + "' is unknown");
  return model->id;
}

// A photo's EXIF GPS position (its altitude, above mean sea level, is not kept).
struct GpsFix {
  double latitude_deg = 0;
  double longitude_deg = 0;
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
  // A photo query: how it became features, in what time, and where its EXIF GPS put it.
  std::optional<PhotoInfo> photo;
  double extraction_seconds = 0;  // decoding, EXIF, resizing and SIFT
  std::optional<GpsFix> exif_gps;
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
