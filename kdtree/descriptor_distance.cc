#include "kdtree/descriptor_distance.h"

#if defined(__x86_64__) || defined(_M_X64)
#define CWLOC_X86_64 1
// GCC 12's AVX-512 headers initialize "undefined" vectors from themselves, which -Wuninitialized
// reports at the header's lines when those intrinsics are inlined (GCC PR 105593).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif

#if defined(__aarch64__)
#define CWLOC_AARCH64 1
#include <arm_neon.h>
#include <sys/auxv.h>  // getauxval; HWCAP_ASIMDDP
#endif

namespace cwloc {
namespace {

uint32_t ScalarOne(const uint8_t* a, const uint8_t* b) {
  uint32_t sum = 0;
  for (size_t i = 0; i < kDescriptorDim; ++i) {
    const int32_t d = int32_t(a[i]) - int32_t(b[i]);
    sum += uint32_t(d * d);
  }
  return sum;
}

void ScalarBatch(const uint8_t* query, const uint8_t* base, const uint32_t* rows, size_t n,
                 uint32_t* out) {
  for (size_t i = 0; i < n; ++i) out[i] = ScalarOne(query, base + size_t(rows[i]) * kDescriptorDim);
}

#ifdef CWLOC_X86_64

// The three x86 kernels widen to 16 bits and subtract (|d| <= 255); vpmaddwd squares and adds
// pairs into 32-bit lanes (<= 2 * 255^2 each), which AVX2 and AVX-512BW then add to their
// accumulators; VNNI's vpdpwssd squares, adds pairs and accumulates in one instruction. A whole
// descriptor sums to at most 128 * 255^2 < 2^31, so nothing can overflow.

__attribute__((target("avx2"))) inline uint32_t Avx2Reduce(__m256i acc) {
  __m128i s = _mm_add_epi32(_mm256_castsi256_si128(acc), _mm256_extracti128_si256(acc, 1));
  s = _mm_add_epi32(s, _mm_shuffle_epi32(s, _MM_SHUFFLE(1, 0, 3, 2)));
  s = _mm_add_epi32(s, _mm_shuffle_epi32(s, _MM_SHUFFLE(2, 3, 0, 1)));
  return uint32_t(_mm_cvtsi128_si32(s));
}

__attribute__((target("avx2"))) inline __m256i Avx2Load16(const uint8_t* p) {
  return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

__attribute__((target("avx2"))) uint32_t Avx2One(const uint8_t* a, const uint8_t* b) {
  __m256i acc0 = _mm256_setzero_si256();
  __m256i acc1 = _mm256_setzero_si256();
  for (size_t i = 0; i < kDescriptorDim; i += 32) {
    const __m256i d0 = _mm256_sub_epi16(Avx2Load16(a + i), Avx2Load16(b + i));
    const __m256i d1 = _mm256_sub_epi16(Avx2Load16(a + i + 16), Avx2Load16(b + i + 16));
    acc0 = _mm256_add_epi32(acc0, _mm256_madd_epi16(d0, d0));
    acc1 = _mm256_add_epi32(acc1, _mm256_madd_epi16(d1, d1));
  }
  return Avx2Reduce(_mm256_add_epi32(acc0, acc1));
}

__attribute__((target("avx2"))) void Avx2Batch(const uint8_t* query, const uint8_t* base,
                                               const uint32_t* rows, size_t n, uint32_t* out) {
  __m256i q[8];
  for (int j = 0; j < 8; ++j) q[j] = Avx2Load16(query + 16 * j);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* v = base + size_t(rows[i]) * kDescriptorDim;
    __m256i acc0 = _mm256_setzero_si256();
    __m256i acc1 = _mm256_setzero_si256();
    for (int j = 0; j < 8; j += 2) {
      const __m256i d0 = _mm256_sub_epi16(q[j], Avx2Load16(v + 16 * j));
      const __m256i d1 = _mm256_sub_epi16(q[j + 1], Avx2Load16(v + 16 * j + 16));
      acc0 = _mm256_add_epi32(acc0, _mm256_madd_epi16(d0, d0));
      acc1 = _mm256_add_epi32(acc1, _mm256_madd_epi16(d1, d1));
    }
    out[i] = Avx2Reduce(_mm256_add_epi32(acc0, acc1));
  }
}

#define CWLOC_AVX512 "avx2,avx512f,avx512bw"
#define CWLOC_AVX512_VNNI "avx2,avx512f,avx512bw,avx512vnni"

// Folds 512 -> 256 bits with a lane shuffle (GCC 12's _mm512_reduce_add_epi32 trips
// -Wuninitialized in its own header).
__attribute__((target(CWLOC_AVX512))) inline uint32_t Avx512Reduce(__m512i acc) {
  acc = _mm512_add_epi32(acc, _mm512_shuffle_i64x2(acc, acc, _MM_SHUFFLE(1, 0, 3, 2)));
  return Avx2Reduce(_mm512_castsi512_si256(acc));
}

__attribute__((target(CWLOC_AVX512))) inline __m512i Avx512Load32(const uint8_t* p) {
  return _mm512_cvtepu8_epi16(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)));
}

// The AVX-512 kernels differ only in how they add the squares of 32 differences to 16 lanes.
// AVX-512BW: vpmaddwd, then vpaddd.
struct Avx512Squares {
  __attribute__((target(CWLOC_AVX512))) __m512i operator()(__m512i acc, __m512i d) const {
    return _mm512_add_epi32(acc, _mm512_madd_epi16(d, d));
  }
};

// VNNI: vpdpwssd multiplies, adds pairs and accumulates in one instruction.
struct Avx512VnniSquares {
  __attribute__((target(CWLOC_AVX512_VNNI))) __m512i operator()(__m512i acc, __m512i d) const {
    return _mm512_dpwssd_epi32(acc, d, d);
  }
};

// Inlined into each kernel, so the VNNI kernels get their target's instructions (the VNNI
// Squares inlines only there).
template <typename Squares>
__attribute__((target(CWLOC_AVX512), always_inline)) inline void Avx512BatchWith(
    const uint8_t* query, const uint8_t* base, const uint32_t* rows, size_t n, uint32_t* out) {
  __m512i q[4];
  for (int j = 0; j < 4; ++j) q[j] = Avx512Load32(query + 32 * j);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* v = base + size_t(rows[i]) * kDescriptorDim;
    __m512i acc0 = Squares()(_mm512_setzero_si512(), _mm512_sub_epi16(q[0], Avx512Load32(v)));
    __m512i acc1 = Squares()(_mm512_setzero_si512(), _mm512_sub_epi16(q[1], Avx512Load32(v + 32)));
    acc0 = Squares()(acc0, _mm512_sub_epi16(q[2], Avx512Load32(v + 64)));
    acc1 = Squares()(acc1, _mm512_sub_epi16(q[3], Avx512Load32(v + 96)));
    out[i] = Avx512Reduce(_mm512_add_epi32(acc0, acc1));
  }
}

__attribute__((target(CWLOC_AVX512))) void Avx512Batch(const uint8_t* query, const uint8_t* base,
                                                       const uint32_t* rows, size_t n,
                                                       uint32_t* out) {
  Avx512BatchWith<Avx512Squares>(query, base, rows, n, out);
}

__attribute__((target(CWLOC_AVX512))) uint32_t Avx512One(const uint8_t* a, const uint8_t* b) {
  const uint32_t row = 0;
  uint32_t out;
  Avx512BatchWith<Avx512Squares>(a, b, &row, 1, &out);
  return out;
}

__attribute__((target(CWLOC_AVX512_VNNI))) void Avx512VnniBatch(const uint8_t* query,
                                                                const uint8_t* base,
                                                                const uint32_t* rows, size_t n,
                                                                uint32_t* out) {
  Avx512BatchWith<Avx512VnniSquares>(query, base, rows, n, out);
}

__attribute__((target(CWLOC_AVX512_VNNI))) uint32_t Avx512VnniOne(const uint8_t* a,
                                                                  const uint8_t* b) {
  const uint32_t row = 0;
  uint32_t out;
  Avx512BatchWith<Avx512VnniSquares>(a, b, &row, 1, &out);
  return out;
}

#endif  // CWLOC_X86_64

#ifdef CWLOC_AARCH64

// Both aarch64 kernels square |a - b| (vabdq_u8: 8 bits, no widening needed first) and differ
// only in how they add 16 of those squares to 32-bit lanes. Neither can overflow: a lane sums
// at most 32 squares.

#define CWLOC_DOTPROD "arch=armv8.2-a+dotprod"

// Advanced SIMD: widen the squares to 16 bits (vmull_u8, <= 255^2), add pairs into the lanes.
struct NeonSquares {
  uint32x4_t operator()(uint32x4_t acc, uint8x16_t a, uint8x16_t b) const {
    const uint8x16_t d = vabdq_u8(a, b);
    acc = vpadalq_u16(acc, vmull_u8(vget_low_u8(d), vget_low_u8(d)));
    return vpadalq_u16(acc, vmull_high_u8(d, d));
  }
};

// The dot product: one udot squares and sums four bytes per lane.
struct DotProdSquares {
  __attribute__((target(CWLOC_DOTPROD))) uint32x4_t operator()(uint32x4_t acc, uint8x16_t a,
                                                               uint8x16_t b) const {
    const uint8x16_t d = vabdq_u8(a, b);
    return vdotq_u32(acc, d, d);
  }
};

// Inlined into each kernel, so the dot product kernels get their target's instructions.
template <typename Squares>
__attribute__((always_inline)) inline void NeonBatchWith(const uint8_t* query, const uint8_t* base,
                                                         const uint32_t* rows, size_t n,
                                                         uint32_t* out) {
  uint8x16_t q[8];
  for (int j = 0; j < 8; ++j) q[j] = vld1q_u8(query + 16 * j);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* v = base + size_t(rows[i]) * kDescriptorDim;
    uint32x4_t acc0 = vdupq_n_u32(0);
    uint32x4_t acc1 = vdupq_n_u32(0);
    for (int j = 0; j < 8; j += 2) {
      acc0 = Squares()(acc0, q[j], vld1q_u8(v + 16 * j));
      acc1 = Squares()(acc1, q[j + 1], vld1q_u8(v + 16 * j + 16));
    }
    out[i] = vaddvq_u32(vaddq_u32(acc0, acc1));
  }
}

void NeonBatch(const uint8_t* query, const uint8_t* base, const uint32_t* rows, size_t n,
               uint32_t* out) {
  NeonBatchWith<NeonSquares>(query, base, rows, n, out);
}

uint32_t NeonOne(const uint8_t* a, const uint8_t* b) {
  const uint32_t row = 0;
  uint32_t out;
  NeonBatchWith<NeonSquares>(a, b, &row, 1, &out);
  return out;
}

__attribute__((target(CWLOC_DOTPROD))) void NeonDotProdBatch(const uint8_t* query,
                                                             const uint8_t* base,
                                                             const uint32_t* rows, size_t n,
                                                             uint32_t* out) {
  NeonBatchWith<DotProdSquares>(query, base, rows, n, out);
}

__attribute__((target(CWLOC_DOTPROD))) uint32_t NeonDotProdOne(const uint8_t* a, const uint8_t* b) {
  const uint32_t row = 0;
  uint32_t out;
  NeonBatchWith<DotProdSquares>(a, b, &row, 1, &out);
  return out;
}

#endif  // CWLOC_AARCH64

constexpr DistanceFunctions kScalarFunctions{DistanceKernel::kScalar, "scalar", ScalarOne,
                                             ScalarBatch};
#ifdef CWLOC_X86_64
constexpr DistanceFunctions kAvx2Functions{DistanceKernel::kAvx2, "avx2", Avx2One, Avx2Batch};
constexpr DistanceFunctions kAvx512Functions{DistanceKernel::kAvx512, "avx512bw", Avx512One,
                                             Avx512Batch};
constexpr DistanceFunctions kAvx512VnniFunctions{DistanceKernel::kAvx512Vnni, "avx512vnni",
                                                 Avx512VnniOne, Avx512VnniBatch};
#endif
#ifdef CWLOC_AARCH64
constexpr DistanceFunctions kNeonFunctions{DistanceKernel::kNeon, "neon", NeonOne, NeonBatch};
constexpr DistanceFunctions kNeonDotProdFunctions{DistanceKernel::kNeonDotProd, "neon-dotprod",
                                                  NeonDotProdOne, NeonDotProdBatch};
#endif

}  // namespace

const DistanceFunctions* DistanceFunctionsFor(DistanceKernel kernel) {
  switch (kernel) {
    case DistanceKernel::kScalar:
      return &kScalarFunctions;
#ifdef CWLOC_X86_64
    // __builtin_cpu_supports also checks that the OS saves the wide registers (XGETBV).
    case DistanceKernel::kAvx2:
      return __builtin_cpu_supports("avx2") ? &kAvx2Functions : nullptr;
    case DistanceKernel::kAvx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw")
                 ? &kAvx512Functions
                 : nullptr;
    case DistanceKernel::kAvx512Vnni:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                     __builtin_cpu_supports("avx512vnni")
                 ? &kAvx512VnniFunctions
                 : nullptr;
#endif
#ifdef CWLOC_AARCH64
    // Advanced SIMD is part of ARMv8-A; the dot product is optional from ARMv8.2 on, and the
    // kernel reports it in the auxiliary vector.
    case DistanceKernel::kNeon:
      return &kNeonFunctions;
    case DistanceKernel::kNeonDotProd:
      return getauxval(AT_HWCAP) & HWCAP_ASIMDDP ? &kNeonDotProdFunctions : nullptr;
#endif
    default:
      return nullptr;  // another architecture's kernel
  }
}

const DistanceFunctions& BestDistanceFunctions() {
  static const DistanceFunctions* best = [] {
    // Fastest first; each architecture finds only its own.
    for (DistanceKernel k :
         {DistanceKernel::kAvx512Vnni, DistanceKernel::kAvx512, DistanceKernel::kAvx2,
          DistanceKernel::kNeonDotProd, DistanceKernel::kNeon}) {
      if (const DistanceFunctions* f = DistanceFunctionsFor(k)) return f;
    }
    return &kScalarFunctions;
  }();
  return *best;
}

}  // namespace cwloc
