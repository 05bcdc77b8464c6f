#include "photo/sift/sift_levels.h"

#include <array>
#include <cmath>
#include <cstring>

namespace cwloc::sift_internal {

size_t FirstLevelToKeep(const std::vector<size_t>& level_num_detections, int max_num_features) {
  size_t num_detections = 0;
  for (size_t i = level_num_detections.size(); i-- > 0;) {
    num_detections += level_num_detections[i];
    if (num_detections > static_cast<size_t>(max_num_features)) return i;
  }
  return 0;
}

void FinishDescriptor(const float* vlfeat_descriptor, SiftOptions::Normalization normalization,
                      uint8_t* out) {
  std::array<float, kSiftDescriptorDim> v;
  std::memcpy(v.data(), vlfeat_descriptor, sizeof(v));
  if (normalization == SiftOptions::Normalization::kL1Root) {
    // COLMAP's L1RootNormalizeFeatureDescriptors (VLFeat's values are >= 0).
    float norm = 0;
    for (float x : v) norm += std::abs(x);
    for (float& x : v) x = std::sqrt(x / norm);
  } else {
    float norm2 = 0;
    for (float x : v) norm2 += x * x;
    const float norm = std::sqrt(norm2);
    for (float& x : v) x /= norm;
  }
  // VLFeat's order is (y cell, x cell, angle) with angles counter-clockwise in the image
  // (y down); UBC's (COLMAP's) runs the 8 angles the other way: bin k goes to (8 - k) % 8.
  for (int cell = 0; cell < 16; ++cell) {
    for (int k = 0; k < 8; ++k) {
      // COLMAP's FeatureDescriptorsToUnsignedByte: round, then clamp into [0, 255].
      const float scaled = std::round(512.0f * v[size_t(8 * cell + k)]);
      const float clamped = std::min(255.0f, std::max(0.0f, scaled));
      out[8 * cell + (8 - k) % 8] = static_cast<uint8_t>(clamped);
    }
  }
}

SiftFeatures AssembleFeatures(const std::vector<SiftLevel>& levels, size_t first,
                              const SiftOptions& options) {
  size_t total = 0;
  for (size_t i = first; i < levels.size(); ++i) total += levels[i].keypoints.size();
  SiftFeatures features;
  features.keypoints.reserve(total);
  features.descriptors.resize(total * kSiftDescriptorDim);
  size_t k = 0;
  for (size_t i = first; i < levels.size(); ++i) {
    const SiftLevel& level = levels[i];
    for (size_t j = 0; j < level.keypoints.size(); ++j, ++k) {
      features.keypoints.push_back(level.keypoints[j]);
      FinishDescriptor(level.descriptors.data() + j * kSiftDescriptorDim, options.normalization,
                       features.descriptors.data() + k * kSiftDescriptorDim);
    }
  }
  return features;
}

}  // namespace cwloc::sift_internal
