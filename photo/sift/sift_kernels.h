#pragma once

// Row kernels of our SIFT (sift_cwloc.cc): each computes, for every pixel of a row, exactly
// what VLFeat computes for it, in the same float operations and order, several pixels at a
// time. Vectors are GCC's generic ones, so the same code is SSE2/AVX2 on x86-64 (an AVX2 clone
// is picked at run time) and NEON on aarch64; no fused multiply-adds anywhere
// (-ffp-contract=off), so every lane rounds as the scalar code does. The scalar references are
// here too, and tests/photo/sift/sift_kernels_test.cc holds the kernels to them bit for bit.

namespace cwloc::sift_internal {

// VLFeat's gradient of one pixel from its central (or, at a border, one-sided) differences:
// modulus by vl_fast_sqrt_f, angle by vl_fast_atan2_f moved into [0, 2 pi) by vl_mod_2pi_f.
void GradientPixel(float gx, float gy, float* mod, float* angle);

// VLFeat's update_gradient for row `src` of a w-pixel-wide level (w >= 2): `up` and `down`
// are the rows above and below, nullptr at the top and bottom borders.
void GradientRow(const float* up, const float* src, const float* down, int w, float* mod,
                 float* angle);

// The scalar GradientRow, pixel by pixel: the reference the kernel is tested against.
void GradientRowScalar(const float* up, const float* src, const float* down, int w, float* mod,
                       float* angle);

// One pass of VLFeat's separable Gaussian (vl_imconvcol_vf's order): out[x] is the sum over
// taps k = 0, 1, ... of rows[k][x] * kernel[k], added from the first tap to the last.
// Along a column, rows[k] are the image rows the taps read; along a row, rows[k] = padded + k.
void ConvolveTaps(const float* const* rows, const float* kernel, int taps, int w, float* out);
void ConvolveTapsScalar(const float* const* rows, const float* kernel, int taps, int w, float* out);

}  // namespace cwloc::sift_internal
