#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/index/index.h"
#include "format/kdtree/kd_forest.h"
#include "localizer/forward_matching.h"
#include "localizer/localizer_options.h"
#include "localizer/query.h"

namespace cwloc {

// The clusters of an index as lists of image rows, computed once per index.
struct ClusterMembers {
  explicit ClusterMembers(const Index& index);
  std::vector<uint32_t> offsets;  // cluster c's images: images[offsets[c] .. offsets[c+1])
  std::vector<uint32_t> images;
  uint32_t num_clusters() const { return static_cast<uint32_t>(offsets.size() - 1); }
};

struct VisitedCluster {
  uint32_t cluster = 0;
  uint32_t votes = 0;     // when it was chosen
  uint32_t matches = 0;   // back-matches it gave
};

struct BackMatchingResult {
  std::vector<FeatureMatch> matches;
  std::vector<VisitedCluster> visited;
  std::vector<uint32_t> cluster_votes;  // final H_c
  double seconds_query_tree = 0;
  double seconds_matching = 0;
};

// Algorithm 3: forward matches vote for their clusters; the most voted unvisited cluster's
// views are matched back against a kd-forest of the query's features (1-ratio test); a cluster
// with at least options.min_matches_to_vote back-matches votes, through each matched view's
// 3D point, for every cluster that sees that point. Stops at options.back_matches matches or
// options.max_back_images clusters, or when no cluster has votes left.
BackMatchingResult MatchBack(const Index& index, const ClusterMembers& clusters, const Query& query,
                             std::span<const FeatureMatch> forward_matches, const LocalizerOptions& options);

}  // namespace cwloc
