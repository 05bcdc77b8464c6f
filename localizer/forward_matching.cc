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
                                       ForwardMatchingStats* stats, ClusterMask allowed) {
  std::vector<uint32_t> order(query.NumFeatures());
  std::iota(order.begin(), order.end(), 0u);
  SplitMix64(options.seed).Shuffle(std::span<uint32_t>(order));

  std::vector<KdNeighbor> neighbors(options.k + 1);
  const KdSearchOptions search_options{options.checks};
  std::vector<FeatureMatch> matches;
  // N_F counts every match that passed both tests, kept or not: a position prior then costs no
  // extra searches, and only its region's matches vote.
  size_t passed = 0;
  for (const uint32_t feature : order) {
    if (passed >= options.forward_matches) break;
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
    const size_t before = matches.size();
    ClusterWiseRatioTest(index, feature, neighbors, options.ratio, &matches, stats);
    passed += matches.size() - before;
    if (!allowed.empty()) {
      matches.erase(
          std::remove_if(matches.begin() + static_cast<std::ptrdiff_t>(before), matches.end(),
                         [&](const FeatureMatch& match) {
                           return !ClusterAllowed(allowed, ClusterOfView(index, match.view));
                         }),
          matches.end());
    }
    stats->seconds_ratio_test += ratio_test.Seconds();
  }
  return matches;
}

std::vector<FeatureMatch> MatchGlobalRatio(const Index& index, const Query& query,
                                           const LocalizerOptions& options,
                                           KdForestSearcher& searcher, ForwardMatchingStats* stats,
                                           ClusterMask allowed) {
  std::vector<KdNeighbor> neighbors(2);
  const KdSearchOptions search_options{options.checks};
  std::vector<FeatureMatch> matches;
  const Stopwatch knn;
  for (uint32_t feature = 0; feature < query.NumFeatures(); ++feature) {
    const KdSearchResult result =
        searcher.Search(query.Descriptor(feature), search_options, neighbors);
    ++stats->features_searched;
    if (result.corrupt) ThrowCorrupt(index);
    if (result.num_neighbors < 2) continue;
    if (!PassesRatioTest(neighbors[0].distance, neighbors[1].distance, options.ratio)) continue;
    ++stats->passed_k_ratio;
    if (!ClusterAllowed(allowed, ClusterOfView(index, neighbors[0].index))) continue;
    matches.push_back(
        {feature, neighbors[0].index, std::sqrt(static_cast<float>(neighbors[0].distance))});
  }
  stats->seconds_knn = knn.Seconds();
  return matches;
}

}  // namespace cwloc
