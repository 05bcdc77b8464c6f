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

}  // namespace

std::vector<FeatureMatch> MatchForward(const Index& index, const Query& query,
                                       const LocalizerOptions& options, KdForestSearcher& searcher,
                                       ForwardMatchingStats* stats, ClusterMask allowed,
                                       const Deadline& stop) {
  std::vector<uint32_t> order(query.NumFeatures());
  std::iota(order.begin(), order.end(), 0u);
  SplitMix64(options.seed).Shuffle(std::span<uint32_t>(order));

  std::vector<KdNeighbor> neighbors(options.k + 1);
  // A position prior's region: the searches compare only its views (the ratio tests then
  // judge distinctiveness within the region), walking the leaves they would walk anyway.
  const std::vector<uint64_t> region = AllowedViews(index, allowed);
  KdSearchOptions search_options;
  search_options.max_checks = options.checks;
  search_options.allowed_rows = region;
  std::vector<FeatureMatch> matches;
  for (const uint32_t feature : order) {
    if (matches.size() >= options.forward_matches) break;
    if (stop.Passed()) {
      stats->stopped_by_deadline = true;
      break;
    }
    const Stopwatch knn;
    const KdSearchResult result =
        searcher.Search(query.Descriptor(feature), search_options, neighbors);
    stats->seconds_knn += knn.Seconds();
    ++stats->features_searched;
    if (result.corrupt) ThrowCorrupt(index);
    if (result.num_neighbors < options.k + 1) continue;  // a model smaller than k+1 views
    // k-ratio ||q - v1|| / ||q - v_{k+1}|| <= tau.
    if (!PassesRatioTest(neighbors[0].distance, neighbors[options.k].distance, options.ratio))
      continue;
    ++stats->passed_k_ratio;
    const Stopwatch ratio_test;
    ClusterWiseRatioTest(index, feature, neighbors, options.ratio, &matches, stats);
    stats->seconds_ratio_test += ratio_test.Seconds();
  }
  return matches;
}

std::vector<FeatureMatch> MatchGlobalRatio(const Index& index, const Query& query,
                                           const LocalizerOptions& options,
                                           KdForestSearcher& searcher, ForwardMatchingStats* stats,
                                           ClusterMask allowed, const Deadline& stop) {
  std::vector<KdNeighbor> neighbors(2);
  const std::vector<uint64_t> region = AllowedViews(index, allowed);
  KdSearchOptions search_options;
  search_options.max_checks = options.checks;
  search_options.allowed_rows = region;
  std::vector<FeatureMatch> matches;
  const Stopwatch knn;
  for (uint32_t feature = 0; feature < query.NumFeatures(); ++feature) {
    if (stop.Passed()) {
      stats->stopped_by_deadline = true;
      break;
    }
    const KdSearchResult result =
        searcher.Search(query.Descriptor(feature), search_options, neighbors);
    ++stats->features_searched;
    if (result.corrupt) ThrowCorrupt(index);
    if (result.num_neighbors < 2) continue;
    if (!PassesRatioTest(neighbors[0].distance, neighbors[1].distance, options.ratio)) continue;
    ++stats->passed_k_ratio;
    matches.push_back(
        {feature, neighbors[0].index, std::sqrt(static_cast<float>(neighbors[0].distance))});
  }
  stats->seconds_knn = knn.Seconds();
  return matches;
}

}  // namespace cwloc
