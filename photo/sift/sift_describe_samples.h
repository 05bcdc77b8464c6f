#pragma once

// DescribeSamples's vector kernel for N lanes, compiled for 8 in sift_kernels.cc and for 16
// (then 8 for the row's last pixels) in sift_kernels_avx512.cc.

#include <algorithm>

#include "photo/sift/sift_kernels.h"
#include "photo/sift/sift_vectors.h"

#if CWLOC_SIFT_VECTORS
namespace cwloc::sift_internal {
namespace {

// DescribeSamples for pixels first .. count - 1, N at a time; with_tail: the last
// (count - first) % N too, padded to a whole vector. Returns the first pixel it left.
template <int N>
CWLOC_VECTOR_INLINE int DescribeSamplesIn(const DescriptorRow& row, const float* mod,
                                          const float* angle, int count, int first, bool with_tail,
                                          DescriptorSamples* out) {
  typedef typename Lanes<N>::Floats FloatsN;
  typedef typename Lanes<N>::Ints IntsN;
  typedef typename Lanes<N>::HalfInts HalfIntsN;
  typedef typename Lanes<N>::Doubles DoublesN;
  typedef typename Lanes<N>::Longs LongsN;
  constexpr int kHalf = N / 2;
  const double* table = FastExpn::Get().table();
  DoublesN lane;
  for (int i = 0; i < kHalf; ++i) lane[i] = i;
  const FloatsN zero = {}, one = zero + 1.0f, half_pixel = zero + 0.5f;
  // Lanes p .. p + N - 1 from mods[0 .. N - 1] and angles[0 .. N - 1].
  static_assert(DescriptorSamples::kMax % N == 0);
  auto block = [&](int p, const float* mods, const float* angles) __attribute__((always_inline)) {
    // float(first_x + p + lane - x), each lane's int sum in double.
    const DoublesN x_low = (double(row.first_x + p) + lane) - row.x;
    const DoublesN x_high = (double(row.first_x + p + kHalf) + lane) - row.x;
    const FloatsN dx = Narrow(x_low, x_high);
    const double dy = row.dy;
    DoublesN n[2][2];  // [x or y][half]
    for (int half = 0; half < 2; ++half) {
      const DoublesN dxd = Widen(dx, half);
      n[0][half] = (row.ct0 * dxd + row.st0 * dy) / row.sbp;
      n[1][half] = (-row.st0 * dxd + row.ct0 * dy) / row.sbp;
    }
    const FloatsN nx = Narrow(n[0][0], n[0][1]), ny = Narrow(n[1][0], n[1][1]);
    const IntsN inside = (nx > -kReach) & (nx < kReach) & (ny > -kReach) & (ny < kReach);
    Store(out->inside + p, inside);
    const FloatsN a = Load<N>(angles);
    const FloatsN theta = Mod2Pi(Narrow(Widen(a, 0) - row.angle0, Widen(a, 1) - row.angle0));
    const FloatsN theta8 = 8.0f * theta;
    const FloatsN nt = Narrow(Widen(theta8, 0) / (2 * VL_PI), Widen(theta8, 1) / (2 * VL_PI));
    // fast_expn of (nx^2 + ny^2) / 8, the sum in float.
    const FloatsN r2 = nx * nx + ny * ny;
    DoublesN win_half[2];
    for (int half = 0; half < 2; ++half) {
      const DoublesN e = Widen(r2, half) / (2.0 * kWindowSigma * kWindowSigma);
      const DoublesN scaled = e * (FastExpn::kSize / FastExpn::kMax);
      // Outside the table (e > 25, or a sample outside the window) the value is unused.
      // int32 lanes: AVX2 converts doubles to int32 in one instruction, not to int64.
      const HalfIntsN index = __builtin_convertvector(
          DoublesN(LongsN(scaled) & ~LongsN(e >= FastExpn::kMax)), HalfIntsN);
      DoublesN lo, hi;
      for (int i = 0; i < kHalf; ++i) {
        lo[i] = table[index[i]];
        hi[i] = table[index[i] + 1];
      }
      const DoublesN value = lo + (scaled - __builtin_convertvector(index, DoublesN)) * (hi - lo);
      win_half[half] = DoublesN(LongsN(value) & ~LongsN(e > FastExpn::kMax));
    }
    const FloatsN win = Narrow(win_half[0], win_half[1]);
    // VLFeat's float(n - 0.5) and float(n - (bin + 0.5)) subtract in double and round to
    // float; in float they give the same value: the double difference is exact unless |n| <
    // 2^-27, and then it lies within 2^-27 of -c (c = 0.5 or bin + 0.5), nearer than any point
    // halfway between two floats there (2^-26 or more), so rounding it twice cannot differ.
    const IntsN binx = Floor(nx - half_pixel);
    const IntsN biny = Floor(ny - half_pixel);
    const IntsN bint = Floor(nt);
    Store(out->binx + p, binx);
    Store(out->biny + p, biny);
    Store(out->bint + p, bint);
    const FloatsN rbinx = nx - (__builtin_convertvector(binx, FloatsN) + half_pixel);
    const FloatsN rbiny = ny - (__builtin_convertvector(biny, FloatsN) + half_pixel);
    const FloatsN rbint = nt - __builtin_convertvector(bint, FloatsN);
    const FloatsN wm = win * Load<N>(mods);
    const FloatsN ax[2] = {Abs(one - rbinx), Abs(zero - rbinx)};
    const FloatsN ay[2] = {Abs(one - rbiny), Abs(zero - rbiny)};
    const FloatsN at[2] = {Abs(one - rbint), Abs(zero - rbint)};
    for (int i = 0; i < 4; ++i) Store(out->cell_weight[i] + p, wm * ax[i >> 1] * ay[i & 1]);
    for (int dbint = 0; dbint < 2; ++dbint) Store(out->angle_weight[dbint] + p, at[dbint]);
  };
  int p = first;
  for (; p + N <= count; p += N) block(p, mod + p, angle + p);
  if (with_tail && p < count) {  // padded to a whole vector whose extra lanes are unused
    float mods[N] = {}, angles[N] = {};
    std::copy(mod + p, mod + count, mods);
    std::copy(angle + p, angle + count, angles);
    block(p, mods, angles);
    p = count;
  }
  return p;
}

}  // namespace
}  // namespace cwloc::sift_internal
#endif  // CWLOC_SIFT_VECTORS
