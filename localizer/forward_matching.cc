#include "localizer/forward_matching.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <span>

#include "format/base/error.h"
#include "format/base/split_mix64.h"
#include "format/base/stopwatch.h"
#include "localizer/cluster_wise_ratio.h"

namespace cwloc {
namespace {

void ThrowCorrupt(const Index& index) {
  throw InputError(
      index.file().path().string() +
      ": the kd-forest holds an out-of-range index; the file is corrupt (run cwloc-index verify)");
}

// Searches in flight in MatchForward: kd-forest SearchBatch's best width on real SIFT, and a
// small batch searches few features past the stop for nothing.
constexpr size_t kForwardBatch = 2;

}  // namespace

std::vector<FeatureMatch> MatchForward(const Index& index, const Query& query,
                                       const LocalizerOptions& options, KdForestSearcher& searcher,
                                       ForwardMatchingStats* stats, ClusterMask allowed,
                                       const Deadline& stop) {
  std::vector<uint32_t> order(query.NumFeatures());
  std::iota(order.begin(), order.end(), 0u);
  SplitMix64(options.seed).Shuffle(std::span<uint32_t>(order));

  // The features are searched kForwardBatch at a time in this order (their cache misses
  // overlap), then judged one by one; the results past the one that completes the matches are
  // dropped, so every output is as if they were searched one at a time.
  const size_t stride = options.k + 1;
  std::vector<KdNeighbor> neighbors(kForwardBatch * stride);
  std::vector<std::span<KdNeighbor>> outs(kForwardBatch);
  for (size_t i = 0; i < kForwardBatch; ++i) outs[i] = {neighbors.data() + i * stride, stride};
  std::vector<KdSearchResult> results(kForwardBatch);
  std::vector<const uint8_t*> descriptors(kForwardBatch);
  // A position prior's region: the searches compare only its views (the ratio tests then
  // judge distinctiveness within the region), walking the leaves they would walk anyway.
  const std::vector<uint64_t> region = AllowedViews(index, allowed);
  KdSearchOptions search_options;
  search_options.max_checks = options.checks;
  search_options.allowed_rows = region;
  std::vector<FeatureMatch> matches;
  for (size_t next = 0; next < order.size() && matches.size() < options.forward_matches;) {
    if (stop.Passed()) {
      stats->stopped_by_deadline = true;
      break;
    }
    const size_t count = std::min<size_t>(kForwardBatch, order.size() - next);
    for (size_t i = 0; i < count; ++i) descriptors[i] = query.Descriptor(order[next + i]);
    const Stopwatch knn;
    searcher.SearchBatch(std::span(descriptors).first(count), search_options,
                         std::span<const std::span<KdNeighbor>>(outs).first(count),
                         std::span(results).first(count), kForwardBatch);
    stats->seconds_knn += knn.Seconds();
    for (size_t i = 0; i < count && matches.size() < options.forward_matches; ++i) {
      const uint32_t feature = order[next + i];
      const KdSearchResult& result = results[i];
      const std::span<const KdNeighbor> found = outs[i];
      ++stats->features_searched;
      if (result.corrupt) ThrowCorrupt(index);
      if (result.num_neighbors < options.k + 1) continue;  // a model smaller than k+1 views
      // k-ratio ||q - v1|| / ||q - v_{k+1}|| <= tau.
      if (!PassesRatioTest(found[0].distance, found[options.k].distance, options.ratio)) continue;
      ++stats->passed_k_ratio;
      const Stopwatch ratio_test;
      ClusterWiseRatioTest(index, feature, found, options.ratio, &matches, stats);
      stats->seconds_ratio_test += ratio_test.Seconds();
    }
    next += count;
  }
  return matches;
}

std::vector<FeatureMatch> MatchGlobalRatio(const Index& index, const Query& query,
                                           const LocalizerOptions& options,
                                           KdForestSearcher& searcher, ForwardMatchingStats* stats,
                                           ClusterMask allowed, const Deadline& stop) {
  const std::vector<uint64_t> region = AllowedViews(index, allowed);
  KdSearchOptions search_options;
  search_options.max_checks = options.checks;
  search_options.allowed_rows = region;
  // Every feature is searched, in batches of kGlobalBatch between two looks at the deadline.
  constexpr size_t kGlobalBatch = 64;
  const size_t n = query.NumFeatures();
  std::vector<const uint8_t*> descriptors(n);
  for (size_t f = 0; f < n; ++f) descriptors[f] = query.Descriptor(uint32_t(f));
  std::vector<KdNeighbor> neighbors(2 * n);
  std::vector<std::span<KdNeighbor>> outs(n);
  for (size_t f = 0; f < n; ++f) outs[f] = {neighbors.data() + 2 * f, 2};
  std::vector<KdSearchResult> results(n);
  std::vector<FeatureMatch> matches;
  const Stopwatch knn;
  size_t searched = 0;
  for (; searched < n; searched += kGlobalBatch) {
    if (stop.Passed()) {
      stats->stopped_by_deadline = true;
      break;
    }
    const size_t count = std::min(kGlobalBatch, n - searched);
    searcher.SearchBatch(std::span(descriptors).subspan(searched, count), search_options,
                         std::span<const std::span<KdNeighbor>>(outs).subspan(searched, count),
                         std::span(results).subspan(searched, count));
  }
  stats->seconds_knn = knn.Seconds();
  for (uint32_t feature = 0; feature < std::min(searched, n); ++feature) {
    const KdSearchResult& result = results[feature];
    const std::span<const KdNeighbor> found = outs[feature];
    ++stats->features_searched;
    if (result.corrupt) ThrowCorrupt(index);
    if (result.num_neighbors < 2) continue;
    if (!PassesRatioTest(found[0].distance, found[1].distance, options.ratio)) continue;
    ++stats->passed_k_ratio;
    matches.push_back({feature, found[0].index, std::sqrt(static_cast<float>(found[0].distance))});
  }
  return matches;
}

}  // namespace cwloc
