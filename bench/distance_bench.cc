// Google Benchmark of the uint8 squared-L2 kernels: one distance with both rows in L1, and a
// kd-leaf-like batch of 8 random rows of a matrix far larger than the caches (with and without
// prefetching the rows first, as the kd search does).

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "base/prefetch.h"
#include "kdtree/descriptor_distance.h"

namespace cwloc {
namespace {

std::vector<uint8_t> RandomBytes(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<uint8_t> out(n);
  for (auto& b : out) b = uint8_t(rng() % 128);  // SIFT values rarely exceed 128
  return out;
}

void BM_One(benchmark::State& state, DistanceKernel kernel) {
  const DistanceFunctions* f = DistanceFunctionsFor(kernel);
  if (!f) {
    state.SkipWithError("kernel not supported on this CPU");
    return;
  }
  const std::vector<uint8_t> data = RandomBytes(64 * kDescriptorDim, 1);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f->one(data.data(), data.data() + (1 + (i++ & 31)) * kDescriptorDim));
  }
  state.SetItemsProcessed(state.iterations());
}

// 8 random rows of a 1 GB matrix (one leaf bucket), rows prefetched or not.
void BM_BatchFromRam(benchmark::State& state, DistanceKernel kernel) {
  const DistanceFunctions* f = DistanceFunctionsFor(kernel);
  if (!f) {
    state.SkipWithError("kernel not supported on this CPU");
    return;
  }
  const bool prefetch = state.range(0) != 0;
  constexpr size_t kRows = size_t(1) << 23;
  static const std::vector<uint8_t> data = RandomBytes(kRows * kDescriptorDim, 2);
  const std::vector<uint8_t> query = RandomBytes(kDescriptorDim, 3);
  std::mt19937_64 rng(4);
  uint32_t rows[8], out[8];
  for (auto _ : state) {
    for (uint32_t& r : rows) {
      r = uint32_t(rng() % kRows);
      if (prefetch) {
        Prefetch(data.data() + size_t(r) * kDescriptorDim);
        Prefetch(data.data() + size_t(r) * kDescriptorDim + 64);
      }
    }
    f->batch(query.data(), data.data(), rows, 8, out);
    benchmark::DoNotOptimize(out);
  }
  state.SetItemsProcessed(state.iterations() * 8);
}

#define CWLOC_KERNEL_BENCH(kernel)                           \
  BENCHMARK_CAPTURE(BM_One, kernel, DistanceKernel::kernel); \
  BENCHMARK_CAPTURE(BM_BatchFromRam, kernel, DistanceKernel::kernel)->Arg(0)->Arg(1);

CWLOC_KERNEL_BENCH(kScalar)
CWLOC_KERNEL_BENCH(kAvx2)
CWLOC_KERNEL_BENCH(kAvx512)
CWLOC_KERNEL_BENCH(kAvx512Vnni)
CWLOC_KERNEL_BENCH(kNeon)
CWLOC_KERNEL_BENCH(kNeonDotProd)

}  // namespace
}  // namespace cwloc

BENCHMARK_MAIN();
