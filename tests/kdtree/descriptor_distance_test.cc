#include "kdtree/descriptor_distance.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace cwloc {
namespace {

uint32_t Reference(const uint8_t* a, const uint8_t* b) {
  uint64_t sum = 0;
  for (size_t i = 0; i < kDescriptorDim; ++i) {
    const int64_t d = int64_t(a[i]) - int64_t(b[i]);
    sum += uint64_t(d * d);
  }
  return uint32_t(sum);
}

std::vector<const DistanceFunctions*> SupportedKernels() {
  std::vector<const DistanceFunctions*> out;
  for (DistanceKernel k : kAllDistanceKernels) {
    if (const DistanceFunctions* f = DistanceFunctionsFor(k)) out.push_back(f);
  }
  return out;
}

// The tests below run every kernel this list names. CWLOC_TEST_DISTANCE_KERNELS (e.g. "scalar
// neon" under QEMU_CPU=cortex-a53) makes sure that they are the ones expected.
TEST(DescriptorDistance, ScalarAlwaysAvailableAndBestIsSupported) {
  ASSERT_NE(DistanceFunctionsFor(DistanceKernel::kScalar), nullptr);
  const DistanceFunctions& best = BestDistanceFunctions();
  EXPECT_EQ(DistanceFunctionsFor(best.kernel), &best);
  std::string names;
  for (const DistanceFunctions* f : SupportedKernels()) {
    if (!names.empty()) names += ' ';
    names += f->name;
  }
  std::cout << "kernels on this CPU: " << names << " (best: " << best.name << ")\n";
  if (const char* expected = std::getenv("CWLOC_TEST_DISTANCE_KERNELS")) {
    EXPECT_EQ(names, expected);
  }
#if defined(__aarch64__)
  EXPECT_NE(DistanceFunctionsFor(DistanceKernel::kNeon), nullptr);  // part of ARMv8-A
  EXPECT_NE(best.kernel, DistanceKernel::kScalar);
#endif
}

TEST(DescriptorDistance, AllKernelsExactOnRandomAndExtremeData) {
  auto& rng = test::Rng();
  // Rows: all 0, all 255, alternating 0/255 both ways, then random (full range and SIFT-like).
  constexpr size_t kRows = 300;
  std::vector<uint8_t> data(kRows * kDescriptorDim);
  for (size_t r = 0; r < kRows; ++r) {
    for (size_t d = 0; d < kDescriptorDim; ++d) {
      uint8_t v;
      switch (r) {
        case 0:
          v = 0;
          break;
        case 1:
          v = 255;
          break;
        case 2:
          v = d % 2 ? 255 : 0;
          break;
        case 3:
          v = d % 2 ? 0 : 255;
          break;
        default:
          v = uint8_t(r % 2 ? rng() % 256 : rng() % 64);
      }
      data[r * kDescriptorDim + d] = v;
    }
  }
  const uint8_t* zeros = data.data();
  const uint8_t* ones = data.data() + kDescriptorDim;
  EXPECT_EQ(Reference(zeros, ones), 128u * 255u * 255u);
  std::vector<uint32_t> rows(kRows);
  for (uint32_t i = 0; i < kRows; ++i) rows[i] = i;
  for (const DistanceFunctions* f : SupportedKernels()) {
    SCOPED_TRACE(std::string(f->name));
    EXPECT_EQ(f->one(zeros, ones), 128u * 255u * 255u);
    EXPECT_EQ(f->one(ones, zeros), 128u * 255u * 255u);
    EXPECT_EQ(f->one(ones, ones), 0u);
    for (size_t q = 0; q < kRows; q += 7) {
      const uint8_t* query = data.data() + q * kDescriptorDim;
      std::vector<uint32_t> batch(kRows);
      f->batch(query, data.data(), rows.data(), kRows, batch.data());
      for (size_t r = 0; r < kRows; ++r) {
        const uint32_t expected = Reference(query, data.data() + r * kDescriptorDim);
        ASSERT_EQ(f->one(query, data.data() + r * kDescriptorDim), expected) << q << " " << r;
        ASSERT_EQ(batch[r], expected) << q << " " << r;
      }
    }
    // Unaligned pointers are allowed (rows come from a mapped file at any offset).
    std::vector<uint8_t> shifted(3 * kDescriptorDim + 1);
    for (auto& b : shifted) b = uint8_t(rng());
    EXPECT_EQ(f->one(shifted.data() + 1, shifted.data() + kDescriptorDim + 2),
              Reference(shifted.data() + 1, shifted.data() + kDescriptorDim + 2));
    f->batch(ones, data.data(), rows.data(), 0, nullptr);  // empty batch: no access
  }
}

// Batches as a kd leaf makes them: any rows, in any order, repeated, of any count.
TEST(DescriptorDistance, BatchesOfArbitraryRows) {
  auto& rng = test::Rng();
  constexpr size_t kRows = 97;
  std::vector<uint8_t> data(kRows * kDescriptorDim);
  for (auto& b : data) b = uint8_t(rng());
  std::fill_n(data.begin() + 5 * kDescriptorDim, kDescriptorDim, uint8_t{255});
  std::fill_n(data.begin() + 6 * kDescriptorDim, kDescriptorDim, uint8_t{0});
  for (const DistanceFunctions* f : SupportedKernels()) {
    SCOPED_TRACE(std::string(f->name));
    for (size_t n = 1; n <= 40; ++n) {
      std::vector<uint32_t> rows(n);
      for (auto& r : rows) r = uint32_t(rng() % kRows);
      rows[rng() % n] = rng() % 2 ? 5 : 6;  // an extreme row in every batch
      const uint8_t* query = data.data() + (rng() % kRows) * kDescriptorDim;
      std::vector<uint32_t> out(n + 1, 12345);
      f->batch(query, data.data(), rows.data(), n, out.data());
      for (size_t i = 0; i < n; ++i) {
        ASSERT_EQ(out[i], Reference(query, data.data() + size_t(rows[i]) * kDescriptorDim))
            << "n " << n << " i " << i << " row " << rows[i];
      }
      EXPECT_EQ(out[n], 12345u);  // nothing written past n
    }
  }
}

}  // namespace
}  // namespace cwloc
