#pragma once

// The vector types and helpers of our SIFT's row kernels (sift_kernels.h): GCC's generic vectors
// of N lanes, so the same code is SSE2/AVX2/AVX-512 on x86-64 and NEON on aarch64. All of it
// has internal linkage: sift_kernels.cc and sift_kernels_avx512.cc compile it for different
// instruction sets, and the linker must not let one file's copy stand in for the other's.

extern "C" {
#include <vl/mathop.h>
}

#include <cstdint>
#include <cstring>

// The helpers pass 32- or 64-byte vectors by value; they are always inlined into the kernels,
// and into the AVX2 clones with them, so no call crosses the ABI GCC warns about. Clang makes that
// warning an error outside AVX code, so a clang build (the sanitizer jobs) runs the scalar
// references instead: the same output, slower.
#if defined(__clang__)
#define CWLOC_SIFT_VECTORS 0
#else
#define CWLOC_SIFT_VECTORS 1
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
#define CWLOC_VECTOR_INLINE inline __attribute__((always_inline))

namespace cwloc::sift_internal {
namespace {

constexpr float kReach = 2.5f;        // |n| >= 2.5 puts all of a sample's bins outside [-2, 2)
constexpr double kWindowSigma = 2.0;  // VLFeat's window size, NBP / 2

#if CWLOC_SIFT_VECTORS

// Vectors of N lanes: N floats or int32s, and the halves of N / 2 doubles or int64s that
// double-precision steps widen them into. The kernels use 8 lanes (two SSE or NEON registers,
// one AVX2); DescribeSamples also has a 16-lane build for AVX-512.
template <int N>
struct Lanes {
  typedef float Floats __attribute__((vector_size(N * sizeof(float))));
  typedef int32_t Ints __attribute__((vector_size(N * sizeof(int32_t))));
  typedef float HalfFloats __attribute__((vector_size(N / 2 * sizeof(float))));
  typedef int32_t HalfInts __attribute__((vector_size(N / 2 * sizeof(int32_t))));
  typedef double Doubles __attribute__((vector_size(N / 2 * sizeof(double))));
  typedef int64_t Longs __attribute__((vector_size(N / 2 * sizeof(int64_t))));
};
template <class Vector>
constexpr int kLanesOf = int(sizeof(Vector) / sizeof(float));  // of a float or int32 vector

template <int N>
CWLOC_VECTOR_INLINE typename Lanes<N>::Floats Load(const float* p) {
  typename Lanes<N>::Floats v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
template <class T, class Vector>
CWLOC_VECTOR_INLINE void Store(T* p, Vector v) {
  static_assert(sizeof(T) == sizeof(float));
  std::memcpy(p, &v, sizeof(v));
}
// Lanes 0 .. N / 2 - 1 (half 0) or N / 2 .. N - 1 (half 1) as doubles, and back. Shuffles, not
// copies through memory: two half-width stores read back as one load stall store forwarding.
template <class Vector>
CWLOC_VECTOR_INLINE auto Half(Vector v, int half) {
  if constexpr (kLanesOf<Vector> == 8) {
    return half == 0 ? __builtin_shufflevector(v, v, 0, 1, 2, 3)
                     : __builtin_shufflevector(v, v, 4, 5, 6, 7);
  } else {
    static_assert(kLanesOf<Vector> == 16);
    return half == 0 ? __builtin_shufflevector(v, v, 0, 1, 2, 3, 4, 5, 6, 7)
                     : __builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15);
  }
}
template <class Vector>
CWLOC_VECTOR_INLINE auto Widen(Vector v, int half) {
  return __builtin_convertvector(Half(v, half), typename Lanes<kLanesOf<Vector>>::Doubles);
}
template <class Doubles>
CWLOC_VECTOR_INLINE auto Narrow(Doubles low, Doubles high) {
  constexpr int n = int(sizeof(Doubles) / sizeof(double)) * 2;
  typedef typename Lanes<n>::HalfFloats HalfFloats;
  const HalfFloats a = __builtin_convertvector(low, HalfFloats),
                   b = __builtin_convertvector(high, HalfFloats);
  if constexpr (n == 8) {
    return __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7);
  } else {
    static_assert(n == 16);
    return __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  }
}
// vl_floor_f: truncation, one less for a negative non-integer.
template <class FloatVector>
CWLOC_VECTOR_INLINE auto Floor(FloatVector v) {
  typedef decltype(v < v) IntVector;  // a comparison gives the int32 vector of as many lanes
  const IntVector t = __builtin_convertvector(v, IntVector);
  return t + ((v < 0.0f) & (__builtin_convertvector(t, FloatVector) != v));
}
template <class IntVector, class FloatVector>
CWLOC_VECTOR_INLINE FloatVector Select(IntVector mask, FloatVector a, FloatVector b) {
  IntVector ai, bi;
  std::memcpy(&ai, &a, sizeof(a));
  std::memcpy(&bi, &b, sizeof(b));
  const IntVector r = (ai & mask) | (bi & ~mask);
  FloatVector out;
  std::memcpy(&out, &r, sizeof(out));
  return out;
}
template <class FloatVector>
CWLOC_VECTOR_INLINE FloatVector Abs(FloatVector v) {
  return Select(v < 0.0f, -v, v);
}

// vl_mod_2pi_f for |x| < 6 pi, where its loops never run more than twice.
template <class FloatVector>
CWLOC_VECTOR_INLINE FloatVector Mod2Pi(FloatVector x) {
  constexpr float kTwoPi = float(2 * VL_PI);
  for (int i = 0; i < 2; ++i) x = Select(x > kTwoPi, x - kTwoPi, x);
  for (int i = 0; i < 2; ++i) x = Select(x < 0.0f, x + kTwoPi, x);
  return x;
}

#endif  // CWLOC_SIFT_VECTORS

}  // namespace
}  // namespace cwloc::sift_internal
