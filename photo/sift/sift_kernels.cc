#include "photo/sift/sift_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "photo/sift/sift_describe_samples.h"
#include "photo/sift/sift_vectors.h"

#if defined(__x86_64__) && CWLOC_SIFT_VECTORS
#define CWLOC_SIFT_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CWLOC_SIFT_CLONES
#endif

namespace cwloc::sift_internal {
namespace {
#if CWLOC_SIFT_VECTORS

constexpr int kLanes = 8;
typedef Lanes<kLanes>::Floats Floats;
typedef Lanes<kLanes>::Ints Ints;

CWLOC_VECTOR_INLINE Floats Load(const float* p) { return Load<kLanes>(p); }
CWLOC_VECTOR_INLINE Floats Splat(float x) { return Floats{} + x; }

// vl_fast_sqrt_f's test x < 1e-8 compares the float promoted to double: as a float
// comparison, x <= the largest float below 1e-8 (float(1e-8) rounds below 1e-8).
constexpr float kSqrtZeroBelow = 1e-8f;
static_assert(static_cast<double>(kSqrtZeroBelow) < 1e-8);

CWLOC_VECTOR_INLINE Floats FastSqrt(Floats x) {
  const Floats xhalf = Splat(0.5f) * x;
  Ints bits;
  std::memcpy(&bits, &x, sizeof(x));
  bits = 0x5f3759df - (bits >> 1);
  Floats r;
  std::memcpy(&r, &bits, sizeof(r));
  r = r * (Splat(1.5f) - xhalf * r * r);
  r = r * (Splat(1.5f) - xhalf * r * r);
  return Select(x <= kSqrtZeroBelow, Splat(0.0f), x * r);
}

CWLOC_VECTOR_INLINE Floats FastAtan2(Floats y, Floats x) {
  const Floats abs_y = Select(y < 0.0f, -y, y) + VL_EPSILON_F;
  const Ints right = x >= 0.0f;
  const Floats r = Select(right, (x - abs_y) / (x + abs_y), (x + abs_y) / (abs_y - x));
  Floats angle = Select(right, Splat(float(VL_PI / 4)), Splat(float(3 * VL_PI / 4)));
  angle += (Splat(0.1821f) * r * r - 0.9675f) * r;
  return Select(y < 0.0f, -angle, angle);
}

// vl_mod_2pi_f(float(a + 2 pi)) for a fast atan2 angle (|a| < 4 pi): the sum in double, then
// the loops, which never run twice for such a sum.
CWLOC_VECTOR_INLINE Floats AngleFrom(Floats a) {
  return Mod2Pi(Narrow(Widen(a, 0) + 2 * VL_PI, Widen(a, 1) + 2 * VL_PI));
}

#endif  // CWLOC_SIFT_VECTORS

}  // namespace

FastExpn::FastExpn() {
  for (int k = 0; k <= kSize; ++k) table_[size_t(k)] = std::exp(-double(k) * (kMax / kSize));
}

const FastExpn& FastExpn::Get() {
  static const FastExpn expn;
  return expn;
}

void GradientPixel(float gx, float gy, float* mod, float* angle) {
  *mod = vl_fast_sqrt_f(gx * gx + gy * gy);
  *angle = vl_mod_2pi_f(float(vl_fast_atan2_f(gy, gx) + 2 * VL_PI));
}

namespace {

// Pixel x of GradientRow, as VLFeat computes it.
CWLOC_VECTOR_INLINE void GradientAt(const float* up, const float* src, const float* down, int w,
                                    int x, float* mod, float* angle) {
  float gx, gy;
  if (x == 0) {
    gx = src[1] - src[0];
  } else if (x == w - 1) {
    gx = src[x] - src[x - 1];
  } else {
    gx = float(0.5 * (src[x + 1] - src[x - 1]));
  }
  if (up == nullptr) {
    gy = down[x] - src[x];
  } else if (down == nullptr) {
    gy = src[x] - up[x];
  } else {
    gy = float(0.5 * (down[x] - up[x]));
  }
  GradientPixel(gx, gy, &mod[x], &angle[x]);
}

}  // namespace

void GradientRowScalar(const float* up, const float* src, const float* down, int w, float* mod,
                       float* angle) {
  for (int x = 0; x < w; ++x) GradientAt(up, src, down, w, x, mod, angle);
}

CWLOC_SIFT_CLONES
void GradientRow(const float* up, const float* src, const float* down, int w, float* mod,
                 float* angle) {
#if !CWLOC_SIFT_VECTORS
  GradientRowScalar(up, src, down, w, mod, angle);
#else
  // The border columns, and the pixels past the last whole vector, one at a time.
  GradientAt(up, src, down, w, 0, mod, angle);
  int x = 1;
  // 0.5 * d in double, rounded to float, is 0.5f * d: both are the exact product rounded once.
  for (; x + kLanes <= w - 1; x += kLanes) {
    const Floats gx = Splat(0.5f) * (Load(src + x + 1) - Load(src + x - 1));
    const Floats gy = up == nullptr     ? Load(down + x) - Load(src + x)
                      : down == nullptr ? Load(src + x) - Load(up + x)
                                        : Splat(0.5f) * (Load(down + x) - Load(up + x));
    Store(mod + x, FastSqrt(gx * gx + gy * gy));
    Store(angle + x, AngleFrom(FastAtan2(gy, gx)));
  }
  for (; x < w; ++x) GradientAt(up, src, down, w, x, mod, angle);
#endif
}

void ConvolveTapsScalar(const float* const* rows, const float* kernel, int taps, int w,
                        float* out) {
  for (int x = 0; x < w; ++x) {
    float sum = rows[0][x] * kernel[0];
    for (int k = 1; k < taps; ++k) sum += rows[k][x] * kernel[k];
    out[x] = sum;
  }
}

CWLOC_SIFT_CLONES
void ConvolveTaps(const float* const* rows, const float* kernel, int taps, int w, float* out) {
#if !CWLOC_SIFT_VECTORS
  ConvolveTapsScalar(rows, kernel, taps, w, out);
#else
  int x = 0;
  // Each lane adds in tap order, so a lane's sum is a chain of dependent adds; several vectors
  // at a time keep enough chains in flight to hide the add latency.
  constexpr int kChains = 8;
  for (; x + kChains * kLanes <= w; x += kChains * kLanes) {
    Floats sum[kChains];
#pragma GCC unroll 8
    for (int c = 0; c < kChains; ++c) sum[c] = Load(rows[0] + x + c * kLanes) * kernel[0];
    for (int k = 1; k < taps; ++k) {
#pragma GCC unroll 8
      for (int c = 0; c < kChains; ++c) sum[c] += Load(rows[k] + x + c * kLanes) * kernel[k];
    }
#pragma GCC unroll 8
    for (int c = 0; c < kChains; ++c) Store(out + x + c * kLanes, sum[c]);
  }
  for (; x + kLanes <= w; x += kLanes) {
    Floats a = Load(rows[0] + x) * kernel[0];
    for (int k = 1; k < taps; ++k) a += Load(rows[k] + x) * kernel[k];
    Store(out + x, a);
  }
  for (; x < w; ++x) {
    float sum = rows[0][x] * kernel[0];
    for (int k = 1; k < taps; ++k) sum += rows[k][x] * kernel[k];
    out[x] = sum;
  }
#endif
}

void ConvolveTapsRowsScalar(const float* const* rows, const float* kernel, int taps, int w,
                            int num_out, float* const* out) {
  for (int j = 0; j < num_out; ++j) ConvolveTapsScalar(rows + j, kernel, taps, w, out[j]);
}

CWLOC_SIFT_CLONES
void ConvolveTapsRows(const float* const* rows, const float* kernel, int taps, int w, int num_out,
                      float* const* out) {
#if !CWLOC_SIFT_VECTORS
  ConvolveTapsRowsScalar(rows, kernel, taps, w, num_out, out);
#else
  constexpr int kRows = kConvolveRowsAtOnce;
  if (num_out != kRows || taps <= kRows) {
    for (int j = 0; j < num_out; ++j) ConvolveTaps(rows + j, kernel, taps, w, out[j]);
    return;
  }
  // Input row r is tap r - j of output j. Every output still adds its taps in order: the first
  // kRows input rows start the outputs one by one, the last kRows - 1 finish them.
  constexpr int kChains = 2;
  int x = 0;
  for (; x + kChains * kLanes <= w; x += kChains * kLanes) {
    Floats sum[kRows][kChains];
#pragma GCC unroll 4
    for (int r = 0; r < kRows; ++r) {
#pragma GCC unroll 2
      for (int c = 0; c < kChains; ++c) {
        const Floats v = Load(rows[r] + x + c * kLanes);
#pragma GCC unroll 4
        for (int j = 0; j < r; ++j) sum[j][c] += v * kernel[r - j];
        sum[r][c] = v * kernel[0];
      }
    }
    for (int r = kRows; r < taps; ++r) {
#pragma GCC unroll 2
      for (int c = 0; c < kChains; ++c) {
        const Floats v = Load(rows[r] + x + c * kLanes);
#pragma GCC unroll 4
        for (int j = 0; j < kRows; ++j) sum[j][c] += v * kernel[r - j];
      }
    }
#pragma GCC unroll 4
    for (int t = 1; t < kRows; ++t) {
      const int r = taps - 1 + t;
#pragma GCC unroll 2
      for (int c = 0; c < kChains; ++c) {
        const Floats v = Load(rows[r] + x + c * kLanes);
#pragma GCC unroll 4
        for (int j = t; j < kRows; ++j) sum[j][c] += v * kernel[r - j];
      }
    }
#pragma GCC unroll 4
    for (int j = 0; j < kRows; ++j) {
#pragma GCC unroll 2
      for (int c = 0; c < kChains; ++c) Store(out[j] + x + c * kLanes, sum[j][c]);
    }
  }
  for (; x < w; ++x) {
    for (int j = 0; j < kRows; ++j) {
      float sum = rows[j][x] * kernel[0];
      for (int k = 1; k < taps; ++k) sum += rows[j + k][x] * kernel[k];
      out[j][x] = sum;
    }
  }
#endif
}

void DescribeSamplesScalar(const DescriptorRow& row, const float* mod, const float* angle,
                           int count, DescriptorSamples* out) {
  const FastExpn& expn = FastExpn::Get();
  for (int p = 0; p < count; ++p) {
    const float dx = float(row.first_x + p - row.x);
    const float dy = row.dy;
    const float nx = float((row.ct0 * dx + row.st0 * dy) / row.sbp);
    const float ny = float((-row.st0 * dx + row.ct0 * dy) / row.sbp);
    out->inside[p] = nx > -kReach && nx < kReach && ny > -kReach && ny < kReach;
    if (!out->inside[p]) continue;
    const float theta = vl_mod_2pi_f(float(angle[p] - row.angle0));
    const float nt = float(8 * theta / (2 * VL_PI));
    const float win = float(expn((nx * nx + ny * ny) / (2.0 * kWindowSigma * kWindowSigma)));
    const int binx = int(vl_floor_f(float(nx - 0.5)));
    const int biny = int(vl_floor_f(float(ny - 0.5)));
    const int bint = int(vl_floor_f(nt));
    const float rbinx = float(nx - (binx + 0.5));
    const float rbiny = float(ny - (biny + 0.5));
    const float rbint = nt - bint;
    out->binx[p] = binx;
    out->biny[p] = biny;
    out->bint[p] = bint;
    for (int i = 0; i < 4; ++i) {
      const int dbinx = i >> 1, dbiny = i & 1;
      out->cell_weight[i][p] =
          win * mod[p] * vl_abs_f(1 - dbinx - rbinx) * vl_abs_f(1 - dbiny - rbiny);
    }
    for (int dbint = 0; dbint < 2; ++dbint)
      out->angle_weight[dbint][p] = vl_abs_f(1 - dbint - rbint);
  }
}

CWLOC_SIFT_CLONES
void DescribeSamplesEightLanes(const DescriptorRow& row, const float* mod, const float* angle,
                               int count, DescriptorSamples* out) {
#if !CWLOC_SIFT_VECTORS
  DescribeSamplesScalar(row, mod, angle, count, out);
#else
  DescribeSamplesIn<8>(row, mod, angle, count, 0, true, out);
#endif
}

void DescribeSamples(const DescriptorRow& row, const float* mod, const float* angle, int count,
                     DescriptorSamples* out) {
#if CWLOC_SIFT_AVX512
  static const bool avx512 =
      __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw");
  if (avx512) return DescribeSamplesAvx512(row, mod, angle, count, out);
#endif
  DescribeSamplesEightLanes(row, mod, angle, count, out);
}

void DescriptorHistogram::Clear() { std::memset(cell, 0, sizeof(cell)); }

void DescriptorHistogram::CopyInnerTo(float* descriptor) const {
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) std::memcpy(descriptor + 32 * y + 8 * x, cell[y + 1][x + 1], 32);
  }
}

void AccumulateSamplesScalar(const DescriptorSamples& samples, int count,
                             DescriptorHistogram* hist) {
  for (int p = 0; p < count; ++p) {
    if (!samples.inside[p]) continue;
    const int binx = samples.binx[p], biny = samples.biny[p], bint = samples.bint[p];
    const int t0 = bint % 8, t1 = (bint + 1) % 8;
    for (int dbinx = 0; dbinx < 2; ++dbinx) {
      for (int dbiny = 0; dbiny < 2; ++dbiny) {
        float* cell = hist->cell[biny + dbiny + 3][binx + dbinx + 3];
        const float w = samples.cell_weight[2 * dbinx + dbiny][p];
        cell[t0] += w * samples.angle_weight[0][p];
        cell[t1] += w * samples.angle_weight[1][p];
      }
    }
  }
}

CWLOC_SIFT_CLONES
void AccumulateSamples(const DescriptorSamples& samples, int count, DescriptorHistogram* hist) {
#if !CWLOC_SIFT_VECTORS
  AccumulateSamplesScalar(samples, count, hist);
#else
  // A cell's 8 angle bins are one vector; a sample adds w * wt0 to bin t0, w * wt1 to bin t1
  // and w * 0 = +0 to the others, which leaves them as they are (the bins are >= +0).
  const Ints lanes = {0, 1, 2, 3, 4, 5, 6, 7};
  int cached_x = -1, cached_y = -1;
  float* cells[4] = {};
  Floats sums[4] = {};
  for (int p = 0; p < count; ++p) {
    if (!samples.inside[p]) continue;
    const int x = samples.binx[p] + 3, y = samples.biny[p] + 3;
    if (x != cached_x || y != cached_y) {
      for (int i = 0; i < 4 && cached_x >= 0; ++i) Store(cells[i], sums[i]);
      cached_x = x;
      cached_y = y;
      for (int i = 0; i < 4; ++i) {
        cells[i] = hist->cell[y + (i & 1)][x + (i >> 1)];
        sums[i] = Load(cells[i]);
      }
    }
    const int t0 = samples.bint[p] & 7;  // bint is in 0 .. 8
    const Floats angle_weights =
        Select(lanes == t0, Splat(samples.angle_weight[0][p]),
               Select(lanes == ((t0 + 1) & 7), Splat(samples.angle_weight[1][p]), Splat(0.0f)));
    for (int i = 0; i < 4; ++i) sums[i] += Splat(samples.cell_weight[i][p]) * angle_weights;
  }
  for (int i = 0; i < 4 && cached_x >= 0; ++i) Store(cells[i], sums[i]);
#endif
}

int FindExtremumCandidatesScalar(const float* const gauss[4][3], int w, float threshold,
                                 int32_t* out) {
  int count = 0;
  for (int x = 1; x < w - 1; ++x) {
    const float v = gauss[2][1][x] - gauss[1][1][x];
    if (!(std::abs(v) >= threshold)) continue;
    bool above = true, below = true;
    for (int l = 0; l < 3; ++l) {
      for (int r = 0; r < 3; ++r) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (l == 1 && r == 1 && dx == 0) continue;
          const float n = gauss[l + 1][r][x + dx] - gauss[l][r][x + dx];
          above = above && v > n;
          below = below && v < n;
        }
      }
    }
    if (above || below) out[count++] = x;
  }
  return count;
}

CWLOC_SIFT_CLONES
int FindExtremumCandidates(const float* const gauss[4][3], int w, float threshold, int32_t* out) {
#if !CWLOC_SIFT_VECTORS
  return FindExtremumCandidatesScalar(gauss, w, threshold, out);
#else
  int count = 0;
  int x = 1;
  auto any = [](Ints mask) {
    uint64_t words[sizeof(mask) / sizeof(uint64_t)];
    std::memcpy(words, &mask, sizeof(mask));
    uint64_t bits = 0;
    for (const uint64_t word : words) bits |= word;
    return bits != 0;
  };
  for (; x + kLanes <= w - 1; x += kLanes) {
    const Floats v = Load(gauss[2][1] + x) - Load(gauss[1][1] + x);
    const Ints strong = Abs(v) >= threshold;
    if (!any(strong)) continue;
    // The largest and smallest of the 26 neighbours: v above (below) all of them is v above
    // (below) the largest (smallest), exactly, for the finite values DoG levels hold.
    Floats hi = Splat(-std::numeric_limits<float>::infinity());
    Floats lo = Splat(std::numeric_limits<float>::infinity());
    for (int l = 0; l < 3; ++l) {
      for (int r = 0; r < 3; ++r) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (l == 1 && r == 1 && dx == 0) continue;
          const Floats n = Load(gauss[l + 1][r] + x + dx) - Load(gauss[l][r] + x + dx);
          hi = n > hi ? n : hi;  // maxps and minps on x86
          lo = n < lo ? n : lo;
        }
      }
    }
    const Ints hit = strong & ((v > hi) | (v < lo));
    if (!any(hit)) continue;
    for (int l = 0; l < kLanes; ++l) {
      if (hit[l]) out[count++] = x + l;
    }
  }
  for (; x < w - 1; ++x) {
    const float* const rows[4][3] = {
        {gauss[0][0] + x - 1, gauss[0][1] + x - 1, gauss[0][2] + x - 1},
        {gauss[1][0] + x - 1, gauss[1][1] + x - 1, gauss[1][2] + x - 1},
        {gauss[2][0] + x - 1, gauss[2][1] + x - 1, gauss[2][2] + x - 1},
        {gauss[3][0] + x - 1, gauss[3][1] + x - 1, gauss[3][2] + x - 1}};
    int32_t found;
    if (FindExtremumCandidatesScalar(rows, 3, threshold, &found) == 1) out[count++] = x;
  }
  return count;
#endif
}

}  // namespace cwloc::sift_internal
