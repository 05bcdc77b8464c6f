#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <unordered_set>
#include <utility>
#include <vector>

#include "base/deadline.h"
#include "format/index.h"
#include "kdtree/kd_forest_builder.h"
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
  // H_c when the last cluster was chosen: the votes of the last cluster visited are cast only
  // if the matching goes on (they choose the next cluster; most queries stop after one).
  std::vector<uint32_t> cluster_votes;
  double seconds_query_tree = 0;
  double seconds_matching = 0;
  bool stopped_by_deadline = false;   // the latency budget ended it, possibly inside a cluster
  BackStop stop = BackStop::kNotRun;  // why the last Run ended
};

// Back-matching's ratio test and N_B for this query: `ratio` and `back_matches`, or for a query
// whose focal length is unknown LocalizerOptions::unknown_focal_back_ratio and
// unknown_focal_back_matches.
double BackMatchingRatio(const LocalizerOptions& options, const QueryCamera& camera);
uint32_t BackMatchingTarget(const LocalizerOptions& options, const QueryCamera& camera);

// Algorithm 3: forward matches vote for their clusters; the most voted unvisited cluster's
// views are matched back against a kd-forest of the query's features (1-ratio test at
// `ratio`); a cluster with at least options.min_matches_to_vote back-matches votes, through each
// matched view's 3D point, for every cluster that sees that point. Stops at N_B matches or
// options.max_back_clusters clusters, or when no cluster has votes left. Clusters outside
// `allowed` get no votes, so they are never back-matched. With `guide`, views are matched near
// their projection (pose_guide.h) instead of in a kd-forest of the query's features. Stops
// once `stop` has passed (a latency budget).
//
// A BackMatcher keeps its votes and visited clusters, so that a query whose pose the first N_B
// matches leave weakly constrained can continue with a larger N_B where it stopped.
class BackMatcher {
 public:
  // The index, the clusters, the query, the options and the guide must outlive the matcher;
  // the forward matches are read here, for their votes.
  BackMatcher(const Index& index, const ClusterMembers& clusters, const Query& query,
              std::span<const FeatureMatch> forward_matches, const LocalizerOptions& options,
              double ratio, ClusterMask allowed = {}, PoseGuide* guide = nullptr,
              const Deadline& stop = {});
  BackMatcher(const BackMatcher&) = delete;
  BackMatcher& operator=(const BackMatcher&) = delete;

  // Back-matches until the result holds back_matches matches (or a stop above): first N_B
  // (BackMatchingTarget), then, to continue where it stopped, a larger target.
  void Run(uint32_t back_matches);
  const BackMatchingResult& result() const { return result_; }
  BackMatchingResult TakeResult() { return std::move(result_); }

 private:
  void Vote(uint32_t cluster);
  // The co-visibility votes of the last cluster visited, if it matched enough views to vote.
  void CastPendingVotes();
  // The view's back-match, if it passes the ratio test.
  std::optional<FeatureMatch> MatchView(uint32_t view);

  const Index& index_;
  const ClusterMembers& clusters_;
  const Query& query_;
  const LocalizerOptions& options_;
  const double ratio_;  // the views' ratio test (BackMatchingRatio for a query alone)
  ClusterMask allowed_;
  PoseGuide* guide_;
  Deadline stop_;
  BackMatchingResult result_;
  std::vector<uint32_t> voted_;  // clusters with votes, to find the best without scanning all
  std::vector<bool> visited_;
  std::optional<KdForest> query_forest_;  // without a guide: over all the query's features
  std::optional<KdForestSearcher> searcher_;
  KdSearchOptions search_options_;
  std::vector<KdNeighbor> neighbors_;
  std::vector<uint32_t> track_clusters_;
  uint8_t decoded_[128];                       // a coded index's view descriptor
  std::unordered_set<uint32_t> tried_points_;  // a coded index's points back-matched so far
  bool started_ = false;                       // the first Run builds the query forest
  // The cluster whose matches from this index on have votes to cast.
  std::optional<std::pair<uint32_t, size_t>> pending_votes_;
};

// One BackMatcher run to options.back_matches.
BackMatchingResult MatchBack(const Index& index, const ClusterMembers& clusters, const Query& query,
                             std::span<const FeatureMatch> forward_matches,
                             const LocalizerOptions& options, ClusterMask allowed = {},
                             PoseGuide* guide = nullptr, const Deadline& stop = {});

}  // namespace cwloc
