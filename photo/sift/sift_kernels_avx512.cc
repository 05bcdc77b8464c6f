// DescribeSamples 16 lanes at a time: photo/sift/CMakeLists.txt compiles this file for AVX-512
// and sift_kernels.cc calls it only where the CPU has it. The kernel converts between float and
// double so often that it is bound by instructions, not arithmetic, so twice the lanes per
// instruction is 1.2x (cwloc-sift-kernels-bench) even on Zen 4, whose 512-bit arithmetic is no
// faster than its 256-bit arithmetic.

#include "photo/sift/sift_describe_samples.h"

namespace cwloc::sift_internal {

void DescribeSamplesAvx512(const DescriptorRow& row, const float* mod, const float* angle,
                           int count, DescriptorSamples* out) {
#if CWLOC_SIFT_VECTORS
  // A window row is some 30-50 pixels: its last count % 16 in 8 lanes pad fewer lanes.
  const int p = DescribeSamplesIn<16>(row, mod, angle, count, 0, false, out);
  DescribeSamplesIn<8>(row, mod, angle, count, p, true, out);
#else
  DescribeSamplesScalar(row, mod, angle, count, out);
#endif
}

}  // namespace cwloc::sift_internal
