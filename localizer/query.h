#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "format/camera/camera_models.h"

namespace cwloc {

// The query's camera. With focal_known == false only the image size is trusted: the
// principal point is taken at the image centre, distortion is ignored, and P4Pf estimates
// the focal length.
struct QueryCamera {
  CameraModelId model_id = CameraModelId::kSimplePinhole;
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<double> params;
  bool focal_known = true;

  // The principal point assumed when the focal length is unknown.
  std::array<double, 2> ImageCenter() const { return {width / 2.0, height / 2.0}; }
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

  uint32_t NumFeatures() const { return static_cast<uint32_t>(keypoints.size() / 2); }
  const uint8_t* Descriptor(uint32_t i) const { return descriptors.data() + size_t{i} * 128; }
  std::string Source() const { return source.empty() ? "query '" + name + "'" : source; }
};

}  // namespace cwloc
