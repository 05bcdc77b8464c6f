#include "localizer/back_matching.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "format/base/stopwatch.h"
#include "format/kdtree/kd_forest_builder.h"

namespace cwloc {
namespace {

// Views matched between two reads of the clock (a guided match takes ~0.2 us).
constexpr uint32_t kViewsPerDeadlineCheck = 32;

}  // namespace

BackMatchingResult MatchBack(const Index& index, const ClusterMembers& clusters, const Query& query,
                             std::span<const FeatureMatch> forward_matches,
                             const LocalizerOptions& options, ClusterMask allowed, PoseGuide* guide,
                             const Deadline& stop) {
  BackMatchingResult result;
  result.cluster_votes.assign(clusters.num_clusters(), 0);
  std::vector<uint32_t>& votes = result.cluster_votes;
  std::vector<uint32_t> voted;  // clusters with votes, to find the best without scanning all
  auto vote = [&](uint32_t cluster) {
    if (cluster >= votes.size() || !ClusterAllowed(allowed, cluster)) return;
    if (votes[cluster]++ == 0) voted.push_back(cluster);
  };
  for (const FeatureMatch& match : forward_matches) vote(ClusterOfView(index, match.view));
  if (voted.empty() || query.NumFeatures() < 2) return result;

  // Without a guide, views are searched in a kd-forest over all the query's features.
  Stopwatch stopwatch;
  std::optional<KdForest> query_forest;
  std::optional<KdForestSearcher> searcher;
  const std::span<const uint8_t> query_descriptors(query.descriptors.data(),
                                                   size_t{query.NumFeatures()} * 128);
  if (guide == nullptr) {
    if (stop.Passed()) {
      result.stopped_by_deadline = true;  // the forest alone would cost milliseconds
      return result;
    }
    KdForestBuildOptions tree_options;
    tree_options.num_trees = 4;
    tree_options.num_threads = 1;
    tree_options.seed = options.seed;
    query_forest = BuildKdForest(query_descriptors, tree_options);
    searcher.emplace(query_forest->View(query_descriptors));
  }
  result.seconds_query_tree = stopwatch.Seconds();

  stopwatch.Restart();
  KdSearchOptions search_options;
  search_options.max_checks = options.query_tree_checks;
  std::vector<bool> visited(clusters.num_clusters(), false);
  std::vector<KdNeighbor> neighbors(2);
  std::vector<uint32_t> track_clusters;
  while (result.matches.size() < options.back_matches &&
         result.visited.size() < options.max_back_clusters && !result.stopped_by_deadline) {
    uint32_t best = UINT32_MAX;
    for (uint32_t cluster : voted) {
      if (!visited[cluster] && (best == UINT32_MAX || votes[cluster] > votes[best] ||
                                (votes[cluster] == votes[best] && cluster < best))) {
        best = cluster;
      }
    }
    if (best == UINT32_MAX) break;
    visited[best] = true;
    const size_t first_match = result.matches.size();
    for (uint32_t i = clusters.offsets[best];
         i < clusters.offsets[best + 1] && !result.stopped_by_deadline; ++i) {
      const IndexImage& image = index.images()[clusters.images[i]];
      for (uint32_t view = image.first_view; view < image.first_view + image.num_views; ++view) {
        if (view >= index.num_views()) break;  // a corrupt range; verify names it
        if ((view - image.first_view) % kViewsPerDeadlineCheck == 0 && stop.Passed()) {
          result.stopped_by_deadline = true;
          break;
        }
        if (guide != nullptr) {
          if (const std::optional<FeatureMatch> match = guide->Match(index, view, options.ratio))
            result.matches.push_back(*match);
          continue;
        }
        const KdSearchResult found =
            searcher->Search(index.descriptor(view), search_options, neighbors);
        if (found.num_neighbors < 2) continue;
        if (!PassesRatioTest(neighbors[0].distance, neighbors[1].distance, options.ratio)) continue;
        result.matches.push_back(
            {neighbors[0].index, view, std::sqrt(static_cast<float>(neighbors[0].distance))});
      }
    }
    const uint32_t found_here = static_cast<uint32_t>(result.matches.size() - first_match);
    result.visited.push_back({best, votes[best], found_here});
    if (found_here < options.min_matches_to_vote) continue;
    // Co-visibility votes: every other cluster that sees a matched 3D point, once per match.
    for (size_t m = first_match; m < result.matches.size(); ++m) {
      track_clusters.clear();
      for (const uint32_t other_view : index.TrackOf(index.view_points()[result.matches[m].view])) {
        const uint32_t cluster = ClusterOfView(index, other_view);
        if (cluster == best || cluster == UINT32_MAX) continue;
        if (std::find(track_clusters.begin(), track_clusters.end(), cluster) ==
            track_clusters.end()) {
          track_clusters.push_back(cluster);
          vote(cluster);
        }
      }
    }
  }
  result.seconds_matching = stopwatch.Seconds();
  return result;
}

}  // namespace cwloc
