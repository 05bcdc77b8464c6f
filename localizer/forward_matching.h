#pragma once

#include <cstdint>
#include <vector>

#include "base/deadline.h"
#include "format/index.h"
#include "kdtree/kd_forest.h"
#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/query.h"

namespace cwloc {

// Algorithms 1 and 2 of the paper, interleaved: query features in a random order drawn from
// options.seed, (k+1)-NN in the global kd-forest, the k-ratio test, then the cluster-wise ratio
// test on the k neighbours; stops once options.forward_matches matches have passed both.
// With `allowed` (a position prior), the searches compare only the views of those clusters.
// No feature is searched once `stop` has passed (a latency budget).
std::vector<FeatureMatch> MatchForward(const Index& index, const Query& query,
                                       const LocalizerOptions& options, KdForestSearcher& searcher,
                                       ForwardMatchingStats* stats, ClusterMask allowed = {},
                                       const Deadline& stop = {});

// The diagnostic baseline: every query feature's 2-NN in the global forest, the plain 1-ratio
// test; with `allowed`, among the views of those clusters only; until `stop`.
std::vector<FeatureMatch> MatchGlobalRatio(const Index& index, const Query& query,
                                           const LocalizerOptions& options,
                                           KdForestSearcher& searcher, ForwardMatchingStats* stats,
                                           ClusterMask allowed = {}, const Deadline& stop = {});

}  // namespace cwloc
