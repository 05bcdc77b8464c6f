#pragma once

#include <cstdint>
#include <vector>

#include "format/index.h"
#include "localizer/matching.h"
#include "localizer/query.h"

namespace cwloc {

// The matches one cluster gave in exhaustive local matching.
struct ClusterMatches {
  uint32_t cluster = 0;
  std::vector<FeatureMatch> matches;
};

// The paper's gold standard (Table 1), a diagnostic: every query feature is compared with every
// view of each cluster by brute force, and keeps its nearest view when the next nearest view of
// another 3D point *in the same cluster* is far enough (the 1-ratio test inside the cluster).
// Costs features x views distances, so it is for evaluation, not for devices. Returns the
// clusters with at least one match, in cluster order; stats->seconds_knn gets the time.
std::vector<ClusterMatches> MatchEachClusterExhaustively(const Index& index,
                                                         const ClusterMembers& clusters,
                                                         const Query& query, double ratio,
                                                         ForwardMatchingStats* stats);

}  // namespace cwloc
