#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "base/deadline.h"
#include "base/split_mix64.h"

namespace cwloc {

// A templated LO-RANSAC in the style of PoseLib's robust/ransac_impl.h (Lebeda, Matas and
// Chum, "Fixing the Locally Optimized RANSAC", BMVC 2012): minimal samples give hypotheses,
// hypotheses are ranked by their MSAC score (Torr and Zisserman, "MLESAC", CVIU 2000), and
// every new best hypothesis is locally optimised (Estimator::Refine) for as long as that
// improves its score. The number of iterations adapts to the best inlier ratio w found so
// far: k = log(1 - confidence) / log(1 - w^sample_size).
//
// Header-only and problem-agnostic, so that every layer above base/ uses this one
// sampler: the pose stage (robust/pose_estimators.h) and the georeference fit
// (geo/georeference_fit.cc, plain RANSAC with max_refinements = 0).

// The sampler's settings.
struct RansacOptions {
  uint32_t min_iterations = 100;    // sampled hypotheses at least (unless data < sample size)
  uint32_t max_iterations = 10000;  // and at most
  double confidence = 0.9999;       // probability of drawing one all-inlier sample
  uint32_t max_refinements = 4;     // local optimisation rounds per new best hypothesis
};

// What one run is given besides the settings: its seed and its deadline.
struct RansacRun {
  uint64_t seed = 0;  // same seed, same data: same result on every platform
  // A latency budget: no new sample once it has passed (after the first), whatever the
  // iteration counts of the options ask for.
  Deadline deadline;
};

struct RansacStats {
  uint32_t iterations = 0;                                 // minimal samples drawn
  uint32_t num_inliers = 0;                                // of the best model
  double inlier_ratio = 0.0;                               // num_inliers / number of data points
  uint32_t refinements = 0;                                // local optimisation rounds run
  double score = std::numeric_limits<double>::infinity();  // MSAC score of the best model
  bool stopped_by_deadline = false;                        // RansacRun::deadline ended the sampling
};

// What Ransac needs from a problem.
//   kSampleSize                  size of a minimal sample
//   NumData()                    number of data points (correspondences)
//   GenerateModels(sample, &ms)  appends the models a minimal sample gives to ms, which Ransac
//                                empties first; none for a degenerate sample
//   Score(model, &n, bound)      MSAC score sum_i min(r_i^2, threshold^2) (lower is better);
//                                n = number of inliers (r_i below the threshold). Once the
//                                partial sum reaches `bound` the model has lost (Ransac keeps
//                                only a score below it): Score may stop and return that sum.
//   Refine(&model)               local optimisation on the model's inliers (e.g. non-linear
//                                least squares); Ransac keeps the result only if it scores better
template <typename E>
concept RansacEstimator = requires(const E& e, const typename E::Model& model,
                                   typename E::Model* model_out, std::span<const uint32_t> sample,
                                   std::vector<typename E::Model>* models, uint32_t* num_inliers,
                                   double bound) {
  { E::kSampleSize } -> std::convertible_to<size_t>;
  { e.NumData() } -> std::convertible_to<size_t>;
  e.GenerateModels(sample, models);
  { e.Score(model, num_inliers, bound) } -> std::convertible_to<double>;
  e.Refine(model_out);
};

// Iterations needed to draw an all-inlier sample with the given confidence.
inline uint32_t RansacRequiredIterations(double inlier_ratio, size_t sample_size, double confidence,
                                         uint32_t max_iterations) {
  if (inlier_ratio <= 0.0) return max_iterations;
  if (inlier_ratio >= 1.0) return 0;
  const double all_inliers = std::pow(inlier_ratio, static_cast<double>(sample_size));
  const double log_miss = std::log1p(-all_inliers);
  if (!(log_miss < 0.0)) return max_iterations;  // w^s below double precision
  const double k = std::ceil(std::log1p(-std::clamp(confidence, 0.0, 1.0 - 1e-16)) / log_miss);
  return k >= max_iterations ? max_iterations : static_cast<uint32_t>(k);
}

// Runs LO-RANSAC. On return *best_model holds the best model found if stats.num_inliers > 0
// or at least one model was scored (stats.score finite); otherwise it is untouched.
template <RansacEstimator Estimator>
RansacStats Ransac(const Estimator& estimator, const RansacOptions& options, const RansacRun& run,
                   typename Estimator::Model* best_model) {
  using Model = typename Estimator::Model;
  constexpr size_t kSampleSize = Estimator::kSampleSize;
  RansacStats stats;
  const size_t num_data = estimator.NumData();
  if (num_data < kSampleSize || num_data > std::numeric_limits<uint32_t>::max()) return stats;
  const uint32_t n = static_cast<uint32_t>(num_data);

  SplitMix64 rng(run.seed);
  std::array<uint32_t, kSampleSize> sample;
  std::vector<Model> models;
  uint32_t required = options.max_iterations;
  const uint32_t min_iterations = std::min(options.min_iterations, options.max_iterations);

  while (stats.iterations < options.max_iterations &&
         (stats.iterations < min_iterations || stats.iterations < required)) {
    if (stats.iterations > 0 && run.deadline.Passed()) {
      stats.stopped_by_deadline = true;
      break;
    }
    ++stats.iterations;
    // Distinct indices by rejection: the sample is tiny compared to the data.
    for (size_t i = 0; i < kSampleSize; ++i) {
      uint32_t index;
      do {
        index = rng.Uniform(n);
      } while (std::find(sample.begin(), sample.begin() + i, index) != sample.begin() + i);
      sample[i] = index;
    }
    models.clear();
    estimator.GenerateModels(std::span<const uint32_t>(sample), &models);

    int best_index = -1;
    double best_score = stats.score;
    uint32_t best_inliers = 0;
    for (size_t m = 0; m < models.size(); ++m) {
      uint32_t inliers = 0;
      const double score = estimator.Score(models[m], &inliers, best_score);
      if (score < best_score) {
        best_score = score;
        best_inliers = inliers;
        best_index = static_cast<int>(m);
      }
    }
    if (best_index < 0) continue;

    // Local optimisation of the new best hypothesis while it keeps improving.
    Model model = models[best_index];
    for (uint32_t round = 0; round < options.max_refinements; ++round) {
      Model refined = model;
      estimator.Refine(&refined);
      ++stats.refinements;
      uint32_t inliers = 0;
      const double score = estimator.Score(refined, &inliers, best_score);
      if (!(score < best_score)) break;
      model = refined;
      best_score = score;
      best_inliers = inliers;
    }
    *best_model = model;
    stats.score = best_score;
    stats.num_inliers = best_inliers;
    required = RansacRequiredIterations(static_cast<double>(best_inliers) / n, kSampleSize,
                                        options.confidence, options.max_iterations);
  }
  stats.inlier_ratio = static_cast<double>(stats.num_inliers) / n;
  return stats;
}

}  // namespace cwloc
