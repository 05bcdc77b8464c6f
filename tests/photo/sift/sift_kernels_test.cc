// The SIFT row kernels against their scalar references, bit for bit (photo/sift/sift_kernels.h).
#include "photo/sift/sift_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace cwloc::sift_internal {
namespace {

uint32_t Bits(float x) {
  uint32_t b;
  std::memcpy(&b, &x, sizeof(b));
  return b;
}

// Rows of a level: smooth values in [0, 1] as a Gaussian level holds, with the values that
// take the kernels' special branches mixed in (zero and tiny gradients, the fast sqrt's 1e-8
// threshold on both sides, negative zero, vertical and horizontal edges).
std::vector<float> TestRow(std::mt19937& rng, int w) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> row(static_cast<size_t>(w));
  for (float& v : row) v = unit(rng);
  const float specials[] = {0.0f, -0.0f, 1e-4f, 1e-4f + 1e-8f, std::nextafter(1e-4f, 1.0f),
                            0.5f, 0.5f,  1.0f,  7.0710678e-5f, 7.0710685e-5f};
  for (int i = 0; i < w; i += 3) row[size_t(i)] = specials[size_t(i / 3) % std::size(specials)];
  return row;
}

TEST(SiftKernels, GradientRowEqualsTheScalarReferenceBitForBit) {
  std::mt19937 rng(7);
  for (const int w : {2, 3, 8, 9, 10, 17, 31, 64, 1537}) {
    const std::vector<float> up = TestRow(rng, w), src = TestRow(rng, w), down = TestRow(rng, w);
    for (int border = 0; border < 3; ++border) {
      const float* u = border == 1 ? nullptr : up.data();
      const float* d = border == 2 ? nullptr : down.data();
      const size_t n = static_cast<size_t>(w);
      std::vector<float> mod(n), angle(n), mod_ref(n), angle_ref(n);
      GradientRow(u, src.data(), d, w, mod.data(), angle.data());
      GradientRowScalar(u, src.data(), d, w, mod_ref.data(), angle_ref.data());
      for (int x = 0; x < w; ++x) {
        SCOPED_TRACE("w " + std::to_string(w) + " border " + std::to_string(border) + " x " +
                     std::to_string(x));
        ASSERT_EQ(Bits(mod[size_t(x)]), Bits(mod_ref[size_t(x)]));
        ASSERT_EQ(Bits(angle[size_t(x)]), Bits(angle_ref[size_t(x)]));
      }
    }
  }
}

TEST(SiftKernels, GradientPixelsAtTheFastSqrtThresholdAndEveryDirection) {
  // gx^2 + gy^2 on both sides of 1e-8, and every octant of the angle.
  const float tiny = std::sqrt(1e-8f);
  const float values[] = {
      0.0f,  -0.0f,  tiny, std::nextafter(tiny, 0.0f), std::nextafter(tiny, 1.0f), 0.25f, -0.25f,
      1e-3f, -1e-3f, 0.7f};
  std::vector<float> src;
  for (const float gx : values) {
    // A row whose central difference is 2 gx at its second pixel.
    src = {0.0f, 0.0f, 2 * gx, 0.0f};
    for (const float gy : values) {
      const std::vector<float> up = {0.0f, 0.0f, 0.0f, 0.0f}, down = {0.0f, 2 * gy, 0.0f, 0.0f};
      float mod[4], angle[4], mod_ref[4], angle_ref[4];
      GradientRow(up.data(), src.data(), down.data(), 4, mod, angle);
      GradientRowScalar(up.data(), src.data(), down.data(), 4, mod_ref, angle_ref);
      for (int x = 0; x < 4; ++x) {
        EXPECT_EQ(Bits(mod[x]), Bits(mod_ref[x])) << gx << " " << gy << " x " << x;
        EXPECT_EQ(Bits(angle[x]), Bits(angle_ref[x])) << gx << " " << gy << " x " << x;
      }
    }
  }
}

// Gaussian rows whose DoG values straddle the threshold, with ties: plateaus (equal
// neighbours never make an extremum) and values exactly at the threshold.
TEST(SiftKernels, FindExtremumCandidatesEqualsTheScalarReference) {
  std::mt19937 rng(17);
  std::normal_distribution<float> step(0.0f, 0.01f);
  std::uniform_real_distribution<float> unit(0.2f, 0.8f);
  const float threshold = 0.0053f;
  for (const int w : {3, 9, 10, 16, 17, 100, 3072, 3079}) {
    std::vector<float> data[4][3];
    for (int r = 0; r < 3; ++r) {
      for (int t = 0; t < 4; ++t) data[t][r].resize(size_t(w));
      for (int x = 0; x < w; ++x) {
        float g = unit(rng);
        for (int t = 0; t < 4; ++t) {
          data[t][r][size_t(x)] = g;
          g += (x % 11 == 5) ? 0.0f : step(rng);  // a flat DoG column now and then
        }
      }
    }
    data[2][1][size_t(w / 2)] = data[1][1][size_t(w / 2)] + threshold;
    const float* rows[4][3];
    for (int t = 0; t < 4; ++t) {
      for (int r = 0; r < 3; ++r) rows[t][r] = data[t][r].data();
    }
    std::vector<int32_t> found(static_cast<size_t>(w)), expected(static_cast<size_t>(w));
    found.resize(size_t(FindExtremumCandidates(rows, w, threshold, found.data())));
    expected.resize(size_t(FindExtremumCandidatesScalar(rows, w, threshold, expected.data())));
    EXPECT_EQ(found, expected) << "w " << w;
    if (w >= 100) {
      EXPECT_GT(expected.size(), 5u) << "w " << w;
    }
  }
}

TEST(SiftKernels, ConvolveTapsEqualsTheScalarReferenceBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const int taps : {3, 9, 13, 17, 25}) {
    std::vector<float> kernel(static_cast<size_t>(taps));
    for (float& k : kernel) k = unit(rng) / float(taps);
    for (const int w : {1, 7, 8, 15, 16, 17, 33, 47, 64, 71, 130, 3072, 3079}) {
      std::vector<std::vector<float>> data;
      std::vector<const float*> rows;
      for (int k = 0; k < taps; ++k) data.push_back(TestRow(rng, w));
      for (const auto& row : data) rows.push_back(row.data());
      std::vector<float> out(static_cast<size_t>(w)), ref(static_cast<size_t>(w));
      ConvolveTaps(rows.data(), kernel.data(), taps, w, out.data());
      ConvolveTapsScalar(rows.data(), kernel.data(), taps, w, ref.data());
      for (int x = 0; x < w; ++x) {
        ASSERT_EQ(Bits(out[size_t(x)]), Bits(ref[size_t(x)]))
            << "taps " << taps << " w " << w << " x " << x;
      }
    }
  }
}

TEST(SiftKernels, ConvolveTapsRowsEqualsTheScalarReferenceBitForBit) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const int taps : {3, 4, 5, 11, 27}) {
    std::vector<float> kernel(static_cast<size_t>(taps));
    for (float& k : kernel) k = unit(rng) / float(taps);
    for (const int w : {1, 15, 16, 17, 33, 3079}) {
      for (int num_out = 1; num_out <= kConvolveRowsAtOnce; ++num_out) {
        std::vector<std::vector<float>> data;
        std::vector<const float*> rows;
        for (int k = 0; k < taps + num_out - 1; ++k) data.push_back(TestRow(rng, w));
        for (const auto& row : data) rows.push_back(row.data());
        std::vector<std::vector<float>> out, ref;
        std::vector<float*> out_rows, ref_rows;
        for (int j = 0; j < num_out; ++j) {
          out.emplace_back(static_cast<size_t>(w), -1.0f);
          ref.emplace_back(static_cast<size_t>(w), -2.0f);
        }
        for (int j = 0; j < num_out; ++j) {
          out_rows.push_back(out[size_t(j)].data());
          ref_rows.push_back(ref[size_t(j)].data());
        }
        ConvolveTapsRows(rows.data(), kernel.data(), taps, w, num_out, out_rows.data());
        ConvolveTapsRowsScalar(rows.data(), kernel.data(), taps, w, num_out, ref_rows.data());
        for (int j = 0; j < num_out; ++j) {
          for (int x = 0; x < w; ++x) {
            ASSERT_EQ(Bits(out[size_t(j)][size_t(x)]), Bits(ref[size_t(j)][size_t(x)]))
                << "taps " << taps << " w " << w << " out " << j << " x " << x;
          }
        }
        // Output j is ConvolveTaps on the rows shifted by j.
        std::vector<float> single(static_cast<size_t>(w));
        ConvolveTapsScalar(rows.data() + num_out - 1, kernel.data(), taps, w, single.data());
        ASSERT_EQ(single, ref[size_t(num_out - 1)]);
      }
    }
  }
}

// DescribeSamples computes VLFeat's float(n - 0.5) and float(n - (bin + 0.5)), which subtract
// in double, by float subtractions (sift_kernels.cc says why they agree): every 61st float
// below 2.5 in magnitude, and every float near the values where rounding twice could differ.
TEST(SiftKernels, BinOffsetsInFloatEqualVlfeatsDoubleOnes) {
  auto check = [](float n) {
    ASSERT_EQ(Bits(float(double(n) - 0.5)), Bits(n - 0.5f)) << n;
    for (int bin = -3; bin <= 1; ++bin) {
      ASSERT_EQ(Bits(float(double(n) - (bin + 0.5))), Bits(n - (float(bin) + 0.5f)))
          << n << " bin " << bin;
    }
  };
  const uint32_t limit = Bits(2.5f);
  for (uint32_t bits = 0; bits < limit; bits += 61) {
    float n;
    std::memcpy(&n, &bits, sizeof(n));
    check(n);
    check(-n);
  }
  for (const float centre : {0.0f, 1e-30f, 1.0f / (1 << 27), 1.0f / (1 << 26), 1.0f / (1 << 25),
                             0.5f, 1.0f, 1.5f, 2.0f}) {
    for (const float sign : {1.0f, -1.0f}) {
      float n = sign * centre;
      for (int i = 0; i < 20000; ++i) n = std::nextafter(n, 10.0f);
      for (int i = 0; i < 40000; ++i, n = std::nextafter(n, -10.0f)) check(n);
    }
  }
}

// DescribeSamples (16 lanes on a CPU with AVX-512) and the 8-lane kernel it runs elsewhere.
class DescribeSamplesKernel
    : public ::testing::TestWithParam<std::pair<const char*, decltype(&DescribeSamples)>> {};
INSTANTIATE_TEST_SUITE_P(
    SiftKernels, DescribeSamplesKernel,
    ::testing::Values(std::make_pair("picked", &DescribeSamples),
                      std::make_pair("eight_lanes", &DescribeSamplesEightLanes)),
    [](const auto& param_info) { return std::string(param_info.param.first); });

TEST_P(DescribeSamplesKernel, EqualsTheScalarReferenceBitForBit) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<float> angle_of(0.0f, float(2 * 3.14159265358979));
  constexpr int kCount = DescriptorSamples::kMax;
  int inside = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // A keypoint of scale 1 to 6 at a sub-pixel position, one of its window rows, any angle.
    const double sigma = 1 + 5 * unit(rng), x = 40 + unit(rng), angle0 = 2 * 3.14159265 * unit(rng);
    const double sbp = 3 * sigma + 2.220446049250313e-16;
    const int half_width = int(sbp * 3.6);
    DescriptorRow row{int(x + 0.5) - half_width,
                      x,
                      float(int((trial % (2 * half_width + 1)) - half_width) - 0.37 * unit(rng)),
                      std::cos(angle0),
                      std::sin(angle0),
                      sbp,
                      angle0};
    std::vector<float> mod(kCount), angle(kCount);
    for (int p = 0; p < kCount; ++p) {
      mod[size_t(p)] = float(unit(rng));
      angle[size_t(p)] = p % 7 == 0 ? float(angle0) : angle_of(rng);  // theta 0 and near 2 pi
    }
    const int count = 1 + trial % kCount;
    DescriptorSamples fast, ref;
    GetParam().second(row, mod.data(), angle.data(), count, &fast);
    DescribeSamplesScalar(row, mod.data(), angle.data(), count, &ref);
    for (int p = 0; p < count; ++p) {
      SCOPED_TRACE("trial " + std::to_string(trial) + " pixel " + std::to_string(p));
      ASSERT_EQ(fast.inside[p] != 0, ref.inside[p] != 0);
      if (!ref.inside[p]) continue;
      ++inside;
      ASSERT_EQ(fast.binx[p], ref.binx[p]);
      ASSERT_EQ(fast.biny[p], ref.biny[p]);
      ASSERT_EQ(fast.bint[p], ref.bint[p]);
      for (int i = 0; i < 4; ++i) {
        ASSERT_EQ(Bits(fast.cell_weight[i][p]), Bits(ref.cell_weight[i][p]));
      }
      for (int i = 0; i < 2; ++i) {
        ASSERT_EQ(Bits(fast.angle_weight[i][p]), Bits(ref.angle_weight[i][p]));
      }
    }
  }
  EXPECT_GT(inside, 10000);  // the rows cross the window
}

// Samples as a descriptor row gives them: runs of equal spatial bins (the kernel keeps them in
// registers), every bin of the padded grid, angle bin 8 (VLFeat's nt can round up to 8), and
// some samples outside.
TEST(SiftKernels, AccumulateSamplesEqualsTheScalarReferenceBitForBit) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  DescriptorHistogram fast, ref;
  fast.Clear();
  ref.Clear();
  int added = 0;
  for (int call = 0; call < 300; ++call) {
    DescriptorSamples samples;
    const int count = 1 + call % DescriptorSamples::kMax;
    int binx = int(rng() % 5) - 3, biny = int(rng() % 5) - 3;
    for (int p = 0; p < count; ++p) {
      if (rng() % 6 == 0) binx = int(rng() % 5) - 3;
      if (rng() % 9 == 0) biny = int(rng() % 5) - 3;
      samples.inside[p] = rng() % 10 != 0;
      samples.binx[p] = binx;
      samples.biny[p] = biny;
      samples.bint[p] = int(rng() % 9);
      for (auto& w : samples.cell_weight) w[p] = unit(rng);
      for (auto& w : samples.angle_weight) w[p] = p % 11 == 0 ? 0.0f : unit(rng);
      added += samples.inside[p] != 0;
    }
    AccumulateSamples(samples, count, &fast);
    AccumulateSamplesScalar(samples, count, &ref);
  }
  EXPECT_GT(added, 8000);
  int nonzero = 0;
  for (int y = 0; y < DescriptorHistogram::kSide; ++y) {
    for (int x = 0; x < DescriptorHistogram::kSide; ++x) {
      for (int t = 0; t < 8; ++t) {
        SCOPED_TRACE("bin " + std::to_string(y) + " " + std::to_string(x) + " " +
                     std::to_string(t));
        ASSERT_EQ(Bits(fast.cell[y][x][t]), Bits(ref.cell[y][x][t]));
        nonzero += ref.cell[y][x][t] != 0;
      }
    }
  }
  // Spatial bins -3 .. 1 plus 0 or 1 reach every bin of the padded grid.
  EXPECT_EQ(nonzero, DescriptorHistogram::kSide * DescriptorHistogram::kSide * 8);
  float inner[128];
  ref.CopyInnerTo(inner);
  // VLFeat's bins -2 .. 1 are the grid's 1 .. 4.
  EXPECT_EQ(Bits(inner[0]), Bits(ref.cell[1][1][0]));
  EXPECT_EQ(Bits(inner[127]), Bits(ref.cell[4][4][7]));
  EXPECT_EQ(Bits(inner[32 * 1 + 8 * 2 + 3]), Bits(ref.cell[2][3][3]));
}

}  // namespace
}  // namespace cwloc::sift_internal
