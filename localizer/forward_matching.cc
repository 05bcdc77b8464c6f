#include "localizer/forward_matching.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <span>

#include "base/error.h"
#include "base/split_mix64.h"
#include "base/stopwatch.h"
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

// What a coded index's (feature, point) correspondence counts towards N_F. At 2, N_F = 200
// gives 100 correspondences: on the paper's city as accurate as the full index's 200 view
// matches (about 40 correspondences) and as fast; at 1 forward matching searches 1.3-3.2x the
// features, at 4 the guided pose hypothesis fails on repetitive cities (docs/algorithm.md).
constexpr size_t kCodedMatchWeight = 2;

// The 3D points among one feature's matches.
size_t DistinctPoints(const Index& index, std::span<const FeatureMatch> matches) {
  size_t count = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    const uint32_t point = index.view_points()[matches[i].view];
    bool seen = false;
    for (size_t j = 0; j < i && !seen; ++j) seen = index.view_points()[matches[j].view] == point;
    count += !seen;
  }
  return count;
}

uint32_t FirstViewOfPoint(const Index& index, uint32_t point) {
  const std::span<const uint32_t> track = index.TrackOf(point);
  return track.empty() ? UINT32_MAX : track.front();
}

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
  const std::vector<uint64_t> region = AllowedRows(index, allowed);
  KdSearchOptions search_options;
  search_options.max_checks = options.checks;
  search_options.allowed_rows = region;
  std::vector<FeatureMatch> matches;
  // N_F counts view matches. A coded index's point neighbour is a candidate in every cluster
  // that sees it, so its matches there (votes) say little more than one; there each distinct
  // 2D-3D correspondence counts kCodedMatchWeight.
  size_t correspondences = 0;
  for (size_t next = 0; next < order.size() && correspondences < options.forward_matches;) {
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
    for (size_t i = 0; i < count && correspondences < options.forward_matches; ++i) {
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
      const size_t before = matches.size();
      ClusterWiseRatioTest(index, feature, found, options.ratio, &matches, stats, allowed);
      correspondences +=
          index.coded()
              ? kCodedMatchWeight * DistinctPoints(index, std::span(matches).subspan(before))
              : matches.size() - before;
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
  const std::vector<uint64_t> region = AllowedRows(index, allowed);
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
    // A coded index's row is a point: its first view stands for it.
    const uint32_t view = index.coded() ? FirstViewOfPoint(index, found[0].index) : found[0].index;
    if (view == UINT32_MAX) continue;
    matches.push_back({feature, view, std::sqrt(static_cast<float>(found[0].distance))});
  }
  return matches;
}

}  // namespace cwloc
