#pragma once

// Types every matching stage shares: a 2D-3D candidate, the ratio test, the clusters of an
// index. Stage files include this header, not each other.

#include <cstdint>
#include <span>
#include <vector>

#include "format/index.h"

namespace cwloc {

// A 2D-3D candidate: a query feature matched to a model view (hence to the view's 3D point).
struct FeatureMatch {
  uint32_t feature = 0;
  uint32_t view = 0;
  float distance = 0;  // L2 between the descriptors
};

// The ratio test ||q - a|| / ||q - b|| <= tau, on the squared distances the kd-forest returns.
inline bool PassesRatioTest(uint32_t nearest_squared, uint32_t other_squared, double ratio) {
  return static_cast<double>(nearest_squared) <= ratio * ratio * static_cast<double>(other_squared);
}

// What forward matching (or a matcher in its place) did for one query.
struct ForwardMatchingStats {
  uint32_t features_searched = 0;
  uint32_t passed_k_ratio = 0;
  uint32_t local_ratio_tests = 0;  // clusters with two neighbours of distinct points
  uint32_t t_ratio_tests = 0;      // clusters with a single neighbour
  double seconds_knn = 0;
  double seconds_ratio_test = 0;
  bool stopped_by_deadline = false;  // the latency budget ended the search before N_F
};

// The cluster of a view (UINT32_MAX for a view outside every image's range: a corrupt index).
uint32_t ClusterOfView(const Index& index, uint32_t view);

// A position prior's region: per cluster, 1 when it may be matched. Empty: every cluster.
using ClusterMask = std::span<const char>;

inline bool ClusterAllowed(ClusterMask allowed, uint32_t cluster) {
  return allowed.empty() || (cluster < allowed.size() && allowed[cluster] != 0);
}

// The kd-forest rows seen in the allowed clusters (views; points of a coded index) as its row
// filter (KdSearchOptions::allowed_rows); empty when every cluster is allowed.
std::vector<uint64_t> AllowedRows(const Index& index, ClusterMask allowed);

// The clusters of an index as lists of image rows, computed once per index.
struct ClusterMembers {
  explicit ClusterMembers(const Index& index);
  std::vector<uint32_t> offsets;  // cluster c's images: images[offsets[c] .. offsets[c+1])
  std::vector<uint32_t> images;
  uint32_t num_clusters() const { return static_cast<uint32_t>(offsets.size() - 1); }
};

}  // namespace cwloc
