#pragma once

// Shared by cwloc-sift-agreement, cwloc-sift-bench and tests/photo/sift: read a photo the way
// COLMAP 3.8 (FreeImage 3.18) does, read COLMAP's features from a database, and measure how
// many keypoints two extractions share.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "photo/grey_image.h"
#include "photo/sift/sift_extractor.h"

namespace cwloc::sift_bench {

// photo/image_decode.h's DecodeGreyImage of the file: COLMAP 3.8's pixels (FreeImage 3.18's
// JPEG flags and grey conversion).
GreyImage DecodeJpegLikeColmap(const std::filesystem::path& path);

// COLMAP's keypoints (scale and orientation from the affine shape) and descriptors of the
// image named `name` in a COLMAP database.
SiftFeatures ReadColmapFeatures(const std::filesystem::path& database, const std::string& name);

// A keypoint of `a` is found in `b` when some keypoint of `b` lies within max_position_px,
// its orientation within max_orientation_deg, and their uint8 descriptors within
// max_descriptor_distance (Euclidean).
struct AgreementCriteria {
  double max_position_px = 0.5;
  double max_orientation_deg = 5.0;
  double max_descriptor_distance = 100.0;
};

struct Agreement {
  size_t num_a = 0, num_b = 0;
  size_t a_found_in_b = 0, b_found_in_a = 0;
  size_t a_same_position_in_b = 0;  // a keypoint of b at the bit-identical position
  // For each keypoint of a with a position+orientation neighbour in b: the smallest
  // descriptor distance among those neighbours (the distribution the threshold comes from).
  std::vector<float> nearest_descriptor_distances;
  double ShareAInB() const { return num_a ? double(a_found_in_b) / num_a : 1.0; }
  double ShareBInA() const { return num_b ? double(b_found_in_a) / num_b : 1.0; }
};

Agreement CompareFeatures(const SiftFeatures& a, const SiftFeatures& b,
                          const AgreementCriteria& criteria = {});

}  // namespace cwloc::sift_bench

namespace cwloc::sift_bench {

// "vlfeat", ... <-> SiftOptions::Implementation, for the tools' --implementation (only the
// ones this build has).
std::vector<std::string> ImplementationNames();
SiftOptions::Implementation ParseImplementation(const std::string& name);

}  // namespace cwloc::sift_bench
