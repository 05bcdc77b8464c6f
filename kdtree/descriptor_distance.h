#pragma once

// Squared L2 distance between 128-byte uint8 SIFT descriptors, exact in uint32 (the largest
// value, 128 * 255^2, fits easily). The kernel is chosen once at run time from what the CPU
// supports, so one x86-64 or aarch64 binary runs everywhere; other architectures use the
// portable code. Every kernel gives the scalar kernel's results exactly.

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace cwloc {

inline constexpr size_t kDescriptorDim = 128;

enum class DistanceKernel : uint8_t {
  kScalar,       // portable C++, any CPU
  kAvx2,         // x86-64 with AVX2
  kAvx512,       // x86-64 with AVX-512BW
  kAvx512Vnni,   // AVX-512BW plus VNNI (vpdpwssd fuses the multiply-add and the sum)
  kNeon,         // aarch64 Advanced SIMD (every ARMv8-A CPU)
  kNeonDotProd,  // aarch64 with the ARMv8.2 dot product (udot squares and sums bytes)
};

// Every kernel, of every architecture (DistanceFunctionsFor says which this CPU has).
inline constexpr DistanceKernel kAllDistanceKernels[] = {
    DistanceKernel::kScalar,     DistanceKernel::kAvx2, DistanceKernel::kAvx512,
    DistanceKernel::kAvx512Vnni, DistanceKernel::kNeon, DistanceKernel::kNeonDotProd};

struct DistanceFunctions {
  DistanceKernel kernel;
  std::string_view name;
  // ||a - b||^2 of two 128-byte descriptors.
  uint32_t (*one)(const uint8_t* a, const uint8_t* b);
  // out[i] = ||query - base[rows[i] * 128 ..]||^2 for i < n. One indirect call per kd leaf
  // instead of one per descriptor; the query stays in registers.
  void (*batch)(const uint8_t* query, const uint8_t* base, const uint32_t* rows, size_t n,
                uint32_t* out);
};

// The fastest kernel this CPU supports (decided once, thread-safe).
const DistanceFunctions& BestDistanceFunctions();

// A specific kernel, or nullptr when this CPU (or this build's architecture) lacks it.
const DistanceFunctions* DistanceFunctionsFor(DistanceKernel kernel);

// Convenience: the best kernel's single distance.
inline uint32_t SquaredL2(const uint8_t* a, const uint8_t* b) {
  return BestDistanceFunctions().one(a, b);
}

}  // namespace cwloc
