#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/base/deadline.h"
#include "format/index/index.h"
#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/pose_guide.h"
#include "localizer/query.h"

namespace cwloc {

struct VisitedCluster {
  uint32_t cluster = 0;
  uint32_t votes = 0;    // when it was chosen
  uint32_t matches = 0;  // back-matches it gave
};

struct BackMatchingResult {
  std::vector<FeatureMatch> matches;
  std::vector<VisitedCluster> visited;
  std::vector<uint32_t> cluster_votes;  // final H_c
  double seconds_query_tree = 0;
  double seconds_matching = 0;
  bool stopped_by_deadline = false;  // the latency budget ended it, possibly inside a cluster
};

// Algorithm 3: forward matches vote for their clusters; the most voted unvisited cluster's
// views are matched back against a kd-forest of the query's features (1-ratio test); a cluster
// with at least options.min_matches_to_vote back-matches votes, through each matched view's
// 3D point, for every cluster that sees that point. Stops at options.back_matches matches or
// options.max_back_clusters clusters, or when no cluster has votes left. Clusters outside
// `allowed` get no votes, so they are never back-matched. With `guide`, views are matched near
// their projection (pose_guide.h) instead of in a kd-forest of the query's features. Stops
// once `stop` has passed (a latency budget).
BackMatchingResult MatchBack(const Index& index, const ClusterMembers& clusters, const Query& query,
                             std::span<const FeatureMatch> forward_matches,
                             const LocalizerOptions& options, ClusterMask allowed = {},
                             PoseGuide* guide = nullptr, const Deadline& stop = {});

}  // namespace cwloc
