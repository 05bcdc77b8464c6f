#pragma once

// Our SIFT's detection (sift_cwloc.cc): VLFeat's DoG extrema of one level, refined and
// tested as vl_sift_detect does, from the Gaussian levels around it.

#include <vector>

#include "base/parallel_for.h"
#include "photo/sift/sift_scale_space.h"

namespace cwloc::sift_internal {

// VLFeat's keypoint fields (float position and scale, integer level).
struct Key {
  int o, ix, iy, is;
  float x, y, s, sigma;
};

// Refinement moves a candidate by at most this many rows and reads one more either side.
constexpr int kDetectionReach = 6;

// Candidates on rows `rows` (within 1 .. h - 2) and their refined keypoints, of DoG level s, in
// VLFeat's order (rows, then columns); appends to `keys`. gauss holds the Gaussian levels
// s-1 .. s+2, each on rows `rows` widened by kDetectionReach: DoG level t is G(t + 1) - G(t),
// computed where it is read (the same float subtraction VLFeat stores), so no DoG is held.
void DetectLevel(const Plane* gauss[4], int s, int o, const Geometry& g, double tp, double te,
                 Rows rows, WorkerPool& pool, std::vector<Key>* keys);

}  // namespace cwloc::sift_internal
