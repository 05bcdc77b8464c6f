#pragma once

// Row kernels of our SIFT (sift_cwloc.cc): each computes, for every pixel of a row, exactly
// what VLFeat computes for it, in the same float operations and order, several pixels at a
// time. Vectors are GCC's generic ones, so the same code is SSE2/AVX2 on x86-64 (an AVX2 clone
// is picked at run time) and NEON on aarch64; no fused multiply-adds anywhere
// (-ffp-contract=off), so every lane rounds as the scalar code does. The scalar references are
// here too, and tests/photo/sift/sift_kernels_test.cc holds the kernels to them bit for bit.

#include <array>
#include <cstddef>
#include <cstdint>

namespace cwloc::sift_internal {

// exp(-x) for x >= 0 by table lookup and linear interpolation, as VLFeat's fast_expn (256
// entries up to 25).
class FastExpn {
 public:
  static constexpr int kSize = 256;
  static constexpr double kMax = 25.0;
  static const FastExpn& Get();

  double operator()(double x) const {
    if (x > kMax) return 0.0;
    x *= kSize / kMax;
    const int i = int(x);  // vl_floor_d of x >= 0
    const double r = x - i;
    const double a = table_[size_t(i)], b = table_[size_t(i) + 1];
    return a + r * (b - a);
  }
  const double* table() const { return table_.data(); }

 private:
  FastExpn();
  std::array<double, kSize + 1> table_;
};

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

// The DoG scan's candidates on one row: the x in [1, w - 1), ascending, into `out` (returns
// how many), whose DoG value v passes |v| >= threshold and is above all 26 neighbours or below
// all of them. gauss[t][r] is Gaussian level t (0..3) on row r (0..2); DoG level l on row r is
// gauss[l + 1][r] - gauss[l][r] in float, and v is level 1, row 1. VLFeat's extremum test
// implies this one, so the candidates hold every extremum VLFeat finds; most pixels fail it.
int FindExtremumCandidates(const float* const gauss[4][3], int w, float threshold, int32_t* out);
int FindExtremumCandidatesScalar(const float* const gauss[4][3], int w, float threshold,
                                 int32_t* out);

// One pass of VLFeat's separable Gaussian (vl_imconvcol_vf's order): out[x] is the sum over
// taps k = 0, 1, ... of rows[k][x] * kernel[k], added from the first tap to the last.
// Along a column, rows[k] are the image rows the taps read; along a row, rows[k] = padded + k.
void ConvolveTaps(const float* const* rows, const float* kernel, int taps, int w, float* out);
void ConvolveTapsScalar(const float* const* rows, const float* kernel, int taps, int w, float* out);

// `num_out` ConvolveTaps along columns for consecutive output rows at once: out[j] reads rows
// rows[j] .. rows[j + taps - 1] (so `rows` holds taps + num_out - 1 rows). Each loaded input
// vector feeds every output it is a tap of, so the column pass reads its rows a quarter as often.
constexpr int kConvolveRowsAtOnce = 4;
void ConvolveTapsRows(const float* const* rows, const float* kernel, int taps, int w, int num_out,
                      float* const* out);
void ConvolveTapsRowsScalar(const float* const* rows, const float* kernel, int taps, int w,
                            int num_out, float* const* out);

// The part of VLFeat's descriptor loop (vl_sift_calc_keypoint_descriptor) that depends on one
// window pixel alone: where its rotated position falls among the 4 x 4 x 8 bins and the weights
// it adds to its 8 trilinear neighbours. AccumulateSamples adds them, pixel after pixel, in
// VLFeat's order. One call covers up to kMax consecutive pixels of one window row.
struct DescriptorRow {
  int first_x;  // xi + dxi of the first pixel (octave coordinates)
  double x;     // the keypoint's x in the octave
  float dy;     // float(yi + dyi - y)
  double ct0, st0, sbp, angle0;
};
struct DescriptorSamples {
  static constexpr int kMax = 64;
  int32_t inside[kMax];  // nonzero: |nx|, |ny| < 2.5; the other fields only then
  int32_t binx[kMax], biny[kMax], bint[kMax];
  // VLFeat's weight of the neighbour (binx + dbinx, biny + dbiny, bint + dbint) is
  // cell_weight[2 * dbinx + dbiny][p] * angle_weight[dbint][p], that float product (VLFeat's
  // win * mod * wx * wy * wt, multiplied left to right).
  float cell_weight[4][kMax];
  float angle_weight[2][kMax];
};
void DescribeSamples(const DescriptorRow& row, const float* mod, const float* angle, int count,
                     DescriptorSamples* out);
void DescribeSamplesScalar(const DescriptorRow& row, const float* mod, const float* angle,
                           int count, DescriptorSamples* out);
// The kernels DescribeSamples picks from: 8 lanes (AVX2, SSE2 or NEON), or 16 where the CPU has
// AVX-512 (x86-64 builds with GCC; sift_kernels_avx512.cc). The tests hold both to the
// reference.
void DescribeSamplesEightLanes(const DescriptorRow& row, const float* mod, const float* angle,
                               int count, DescriptorSamples* out);
void DescribeSamplesAvx512(const DescriptorRow& row, const float* mod, const float* angle,
                           int count, DescriptorSamples* out);

// The histogram VLFeat's descriptor adds into, with a border of one spatial bin on every side
// that takes the additions VLFeat skips (bins outside the 4 x 4), so no sample needs a test.
struct DescriptorHistogram {
  static constexpr int kSide = 6;           // spatial bins -3 .. 2
  alignas(32) float cell[kSide][kSide][8];  // [biny + 3][binx + 3][angle bin]
  void Clear();
  // The 4 x 4 x 8 bins in VLFeat's order (y bin, x bin, angle bin).
  void CopyInnerTo(float* descriptor) const;
};

// Adds the inside samples' weights to their 8 neighbours, sample after sample, as VLFeat's
// loop does: every bin receives its additions in the same order. The kernel keeps the four
// spatial bins of the current samples in registers while consecutive samples share them.
void AccumulateSamples(const DescriptorSamples& samples, int count, DescriptorHistogram* hist);
void AccumulateSamplesScalar(const DescriptorSamples& samples, int count,
                             DescriptorHistogram* hist);

}  // namespace cwloc::sift_internal
