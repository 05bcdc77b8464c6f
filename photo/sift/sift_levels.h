#pragma once

// What every implementation shares: COLMAP 3.8's per-DoG-level bookkeeping, the cap on the
// number of features, and the descriptor post-processing (normalization, uint8, UBC order).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "photo/sift/sift_extractor.h"

namespace cwloc::sift_internal {

// The keypoints of one run of consecutive detections with the same DoG level index, as
// COLMAP groups VLFeat's output: `num_detections` keypoints before orientations, and
// `keypoints` with one entry per kept orientation.
struct SiftLevel {
  size_t num_detections = 0;
  std::vector<SiftKeypoint> keypoints;
  std::vector<float> descriptors;  // keypoints.size() x 128, VLFeat order, VLFeat-normalized
};

// COLMAP's rule: walking from the coarsest level to the finest, add each level's detections;
// the first level at which the sum exceeds `max_num_features` is the finest level kept (and
// all coarser ones). Returns the index of the first level to keep (0 = all).
size_t FirstLevelToKeep(const std::vector<size_t>& level_num_detections, int max_num_features);

// One VLFeat-order float descriptor to COLMAP's uint8 UBC-order descriptor: normalize
// (L1-root or L2, in float), round(512 * v) clamped to [0, 255], then reorder.
void FinishDescriptor(const float* vlfeat_descriptor, SiftOptions::Normalization normalization,
                      uint8_t* out);

// Concatenates levels [first, end) into features, finishing every descriptor.
SiftFeatures AssembleFeatures(const std::vector<SiftLevel>& levels, size_t first,
                              const SiftOptions& options);

}  // namespace cwloc::sift_internal
