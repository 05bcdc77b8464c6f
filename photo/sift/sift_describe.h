#pragma once

// Our SIFT's description (sift_cwloc.cc): VLFeat's gradient, orientations and descriptor of a
// keypoint, from the gradient of its level's rows around it.

extern "C" {
#include <vl/mathop.h>
}

#include <algorithm>
#include <cmath>

#include "base/parallel_for.h"
#include "photo/sift/sift_detect.h"
#include "photo/sift/sift_scale_space.h"

namespace cwloc::sift_internal {

constexpr int kNumBinsPerSide = 4;  // VLFeat's NBP
constexpr double kMagnif = 3.0;

// VLFeat's update_gradient for one level: per pixel (modulus, angle in [0, 2 pi)), central
// differences inside, one-sided at the borders; the modulus by VLFeat's fast sqrt and the
// angle by its fast atan2.
struct GradientPlanes {
  Plane mod, angle;
};

// Rows `rows` of the gradient (held by grad) from `level` (holding them widened by one).
void Gradient(const Plane& level, Rows rows, GradientPlanes* grad, WorkerPool& pool);

// The window radii (pixels of the keypoint's octave) of VLFeat's orientation histogram and
// descriptor.
// VLFeat's floor(3 * sigmaw), sigmaw = 1.5 sigma rounded first.
inline int OrientationRadius(double sigma) {
  return std::max(int(std::floor(3.0 * (1.5 * sigma))), 1);
}
inline double DescriptorBinSize(double sigma) { return kMagnif * sigma + VL_EPSILON_D; }
inline int DescriptorRadius(double sigma) {
  return int(
      std::floor(std::sqrt(2.0) * DescriptorBinSize(sigma) * (kNumBinsPerSide + 1) / 2.0 + 0.5));
}

// The keypoint's row in its octave, and how many rows either side its orientations and
// descriptors read.
inline int KeyRow(const Key& k) { return int(k.y / std::pow(2.0, k.o) + 0.5); }
inline int KeyReach(const Key& k) {
  const double sigma = k.sigma / std::pow(2.0, k.o);
  return std::max(OrientationRadius(sigma), DescriptorRadius(sigma));
}

// VLFeat's vl_sift_calc_keypoint_orientations on the gradient of the keypoint's level, which
// holds the rows KeyReach(k) either side of KeyRow(k).
int Orientations(const Key& k, const GradientPlanes& grad, double angles[4]);

// VLFeat's vl_sift_calc_keypoint_descriptor: the per-pixel terms from DescribeSamples, added
// in VLFeat's order; pixels whose rotated position lies outside every spatial bin (they would
// add nothing) are skipped before any other work.
void Descriptor(const Key& k, double angle0, const GradientPlanes& grad, float* descr);

}  // namespace cwloc::sift_internal
