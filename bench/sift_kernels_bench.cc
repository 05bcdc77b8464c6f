// Google Benchmark of our SIFT's row kernels (photo/sift/sift_kernels.h), each against its
// scalar reference, on the sizes a 1536 x 1024 photo gives: rows of the doubled octave (3072
// pixels), the widest smoothing (27 taps) and a descriptor window row.
// Run: build/bin/cwloc-sift-kernels-bench [--benchmark_filter=Convolve]

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "photo/sift/sift_kernels.h"

namespace cwloc::sift_internal {
namespace {

constexpr int kWidth = 3072;

std::vector<float> SmoothRow(std::mt19937& rng, int w) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<float> row(static_cast<size_t>(w));
  float v = unit(rng);
  for (float& x : row) x = v = 0.9f * v + 0.1f * unit(rng);
  return row;
}

// One pass of the widest smoothing of the doubled octave along columns (taps from distinct
// rows) or along a row (taps from one padded row).
void BM_ConvolveTaps(benchmark::State& state, bool vector, bool along_row) {
  constexpr int kTaps = 27;
  std::mt19937 rng(1);
  std::vector<std::vector<float>> images;
  std::vector<const float*> rows(kTaps);
  if (along_row) {
    images.push_back(SmoothRow(rng, kWidth + kTaps));
    for (int k = 0; k < kTaps; ++k) rows[size_t(k)] = images[0].data() + k;
  } else {
    for (int k = 0; k < kTaps; ++k) {
      images.push_back(SmoothRow(rng, kWidth));
      rows[size_t(k)] = images.back().data();
    }
  }
  std::vector<float> kernel(kTaps), out(kWidth);
  for (int k = 0; k < kTaps; ++k)
    kernel[size_t(k)] = std::exp(-0.5f * float((k - 13) * (k - 13)) / 9.5f);
  for (auto _ : state) {
    (vector ? ConvolveTaps : ConvolveTapsScalar)(rows.data(), kernel.data(), kTaps, kWidth,
                                                 out.data());
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kWidth);
}

// The column pass for kConvolveRowsAtOnce output rows at once; items are output pixels.
void BM_ConvolveTapsRows(benchmark::State& state) {
  constexpr int kTaps = 27, kOut = kConvolveRowsAtOnce;
  std::mt19937 rng(1);
  std::vector<std::vector<float>> images;
  std::vector<const float*> rows;
  for (int k = 0; k < kTaps + kOut - 1; ++k) {
    images.push_back(SmoothRow(rng, kWidth));
    rows.push_back(images.back().data());
  }
  std::vector<float> kernel(kTaps);
  for (int k = 0; k < kTaps; ++k)
    kernel[size_t(k)] = std::exp(-0.5f * float((k - 13) * (k - 13)) / 9.5f);
  std::vector<std::vector<float>> out(kOut, std::vector<float>(kWidth));
  float* out_rows[kOut];
  for (int j = 0; j < kOut; ++j) out_rows[j] = out[size_t(j)].data();
  for (auto _ : state) {
    ConvolveTapsRows(rows.data(), kernel.data(), kTaps, kWidth, kOut, out_rows);
    benchmark::DoNotOptimize(out_rows[0]);
  }
  state.SetItemsProcessed(state.iterations() * kWidth * kOut);
}

void BM_GradientRow(benchmark::State& state, bool vector) {
  std::mt19937 rng(2);
  const std::vector<float> up = SmoothRow(rng, kWidth), src = SmoothRow(rng, kWidth),
                           down = SmoothRow(rng, kWidth);
  std::vector<float> mod(kWidth), angle(kWidth);
  for (auto _ : state) {
    (vector ? GradientRow : GradientRowScalar)(up.data(), src.data(), down.data(), kWidth,
                                               mod.data(), angle.data());
    benchmark::DoNotOptimize(mod.data());
  }
  state.SetItemsProcessed(state.iterations() * kWidth);
}

void BM_FindExtremumCandidates(benchmark::State& state, bool vector) {
  std::mt19937 rng(3);
  std::vector<std::vector<float>> rows;
  const float* gauss[4][3];
  for (int t = 0; t < 4; ++t) {
    for (int r = 0; r < 3; ++r) {
      rows.push_back(SmoothRow(rng, kWidth));
      gauss[t][r] = rows.back().data();
    }
  }
  std::vector<int32_t> out(kWidth);
  for (auto _ : state) {
    benchmark::DoNotOptimize((vector ? FindExtremumCandidates : FindExtremumCandidatesScalar)(
        gauss, kWidth, 0.0053f, out.data()));
  }
  state.SetItemsProcessed(state.iterations() * kWidth);
}

// A row through the middle of a descriptor window of a keypoint of scale 2.5 (octave pixels),
// the typical kept keypoint, kMax pixels at a time.
struct DescriptorRowInput {
  DescriptorRow row;
  std::vector<float> mod, angle;
};
DescriptorRowInput TypicalDescriptorRow() {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  constexpr int kCount = DescriptorSamples::kMax;
  const double angle0 = 0.7;
  DescriptorRowInput in{
      {100 - kCount / 2, 100.3, 1.6f, std::cos(angle0), std::sin(angle0), 3 * 2.5, angle0},
      std::vector<float>(kCount),
      std::vector<float>(kCount)};
  for (int p = 0; p < kCount; ++p) {
    in.mod[size_t(p)] = unit(rng);
    in.angle[size_t(p)] = float(2 * M_PI) * unit(rng);
  }
  return in;
}

void BM_DescribeSamples(benchmark::State& state, decltype(&DescribeSamples) describe) {
  const DescriptorRowInput in = TypicalDescriptorRow();
  DescriptorSamples samples;
  for (auto _ : state) {
    describe(in.row, in.mod.data(), in.angle.data(), DescriptorSamples::kMax, &samples);
    benchmark::DoNotOptimize(&samples);
  }
  state.SetItemsProcessed(state.iterations() * DescriptorSamples::kMax);
}

// The same row's samples added to a histogram.
void BM_AccumulateSamples(benchmark::State& state, bool vector) {
  const DescriptorRowInput in = TypicalDescriptorRow();
  constexpr int kCount = DescriptorSamples::kMax;
  DescriptorSamples samples;
  DescribeSamplesScalar(in.row, in.mod.data(), in.angle.data(), kCount, &samples);
  DescriptorHistogram hist;
  hist.Clear();
  for (auto _ : state) {
    (vector ? AccumulateSamples : AccumulateSamplesScalar)(samples, kCount, &hist);
    benchmark::DoNotOptimize(&hist);
  }
  state.SetItemsProcessed(state.iterations() * kCount);
}

BENCHMARK_CAPTURE(BM_ConvolveTaps, column_scalar, false, false);
BENCHMARK_CAPTURE(BM_ConvolveTaps, column_vector, true, false);
BENCHMARK_CAPTURE(BM_ConvolveTaps, row_scalar, false, true);
BENCHMARK_CAPTURE(BM_ConvolveTaps, row_vector, true, true);
BENCHMARK(BM_ConvolveTapsRows);
BENCHMARK_CAPTURE(BM_GradientRow, scalar, false);
BENCHMARK_CAPTURE(BM_GradientRow, vector, true);
BENCHMARK_CAPTURE(BM_FindExtremumCandidates, scalar, false);
BENCHMARK_CAPTURE(BM_FindExtremumCandidates, vector, true);
BENCHMARK_CAPTURE(BM_AccumulateSamples, scalar, false);
BENCHMARK_CAPTURE(BM_AccumulateSamples, vector, true);
BENCHMARK_CAPTURE(BM_DescribeSamples, scalar, &DescribeSamplesScalar);
BENCHMARK_CAPTURE(BM_DescribeSamples, eight_lanes, &DescribeSamplesEightLanes);
BENCHMARK_CAPTURE(BM_DescribeSamples, vector, &DescribeSamples);

}  // namespace
}  // namespace cwloc::sift_internal

BENCHMARK_MAIN();
