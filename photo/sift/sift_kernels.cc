#include "photo/sift/sift_kernels.h"

extern "C" {
#include <vl/mathop.h>
}

#include <cstdint>
#include <cstring>

// The helpers pass 32-byte vectors by value; they are always inlined into the kernels, and
// into the AVX2 clones with them, so no call crosses the ABI GCC warns about.
#pragma GCC diagnostic ignored "-Wpsabi"
#define CWLOC_VECTOR_INLINE inline __attribute__((always_inline))

namespace cwloc::sift_internal {
namespace {

constexpr int kLanes = 8;
typedef float Floats __attribute__((vector_size(kLanes * sizeof(float))));
typedef int32_t Ints __attribute__((vector_size(kLanes * sizeof(int32_t))));
typedef float Floats4 __attribute__((vector_size(4 * sizeof(float))));
typedef double Doubles4 __attribute__((vector_size(4 * sizeof(double))));

CWLOC_VECTOR_INLINE Floats Load(const float* p) {
  Floats v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
CWLOC_VECTOR_INLINE void Store(float* p, Floats v) { std::memcpy(p, &v, sizeof(v)); }
CWLOC_VECTOR_INLINE Floats Splat(float x) { return Floats{} + x; }
CWLOC_VECTOR_INLINE Floats Select(Ints mask, Floats a, Floats b) {
  Ints ai, bi;
  std::memcpy(&ai, &a, sizeof(a));
  std::memcpy(&bi, &b, sizeof(b));
  const Ints r = (ai & mask) | (bi & ~mask);
  Floats out;
  std::memcpy(&out, &r, sizeof(out));
  return out;
}

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
  Floats sum;
  for (int half = 0; half < 2; ++half) {
    Floats4 part;
    std::memcpy(&part, reinterpret_cast<const float*>(&a) + 4 * half, sizeof(part));
    const Doubles4 wide = __builtin_convertvector(part, Doubles4) + 2 * VL_PI;
    const Floats4 narrow = __builtin_convertvector(wide, Floats4);
    std::memcpy(reinterpret_cast<float*>(&sum) + 4 * half, &narrow, sizeof(narrow));
  }
  constexpr float kTwoPi = float(2 * VL_PI);
  for (int i = 0; i < 2; ++i) sum = Select(sum > kTwoPi, sum - kTwoPi, sum);
  for (int i = 0; i < 2; ++i) sum = Select(sum < 0.0f, sum + kTwoPi, sum);
  return sum;
}

}  // namespace

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

#if defined(__x86_64__)
__attribute__((target_clones("avx2", "default")))
#endif
void GradientRow(const float* up, const float* src, const float* down, int w, float* mod,
                 float* angle) {
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
}

void ConvolveTapsScalar(const float* const* rows, const float* kernel, int taps, int w,
                        float* out) {
  for (int x = 0; x < w; ++x) {
    float sum = rows[0][x] * kernel[0];
    for (int k = 1; k < taps; ++k) sum += rows[k][x] * kernel[k];
    out[x] = sum;
  }
}

#if defined(__x86_64__)
__attribute__((target_clones("avx2", "default")))
#endif
void ConvolveTaps(const float* const* rows, const float* kernel, int taps, int w, float* out) {
  int x = 0;
  // Two vectors at a time keep more multiplies in flight; each lane still adds in tap order.
  for (; x + 2 * kLanes <= w; x += 2 * kLanes) {
    Floats a = Load(rows[0] + x) * kernel[0];
    Floats b = Load(rows[0] + x + kLanes) * kernel[0];
    for (int k = 1; k < taps; ++k) {
      a += Load(rows[k] + x) * kernel[k];
      b += Load(rows[k] + x + kLanes) * kernel[k];
    }
    Store(out + x, a);
    Store(out + x + kLanes, b);
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
}

}  // namespace cwloc::sift_internal
