#include "localizer/cluster_wise_ratio.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "localizer/localizer_options.h"

namespace cwloc {

namespace {

// A neighbour as a member of one cluster.
struct ClusterMember {
  uint32_t rank;  // position among the neighbours
  uint32_t cluster;
  uint32_t point;
  uint32_t view;  // the neighbour's view in that cluster
};

// The neighbours' cluster memberships, in neighbour order: one per view neighbour; one per
// cluster that sees a point neighbour (its first view there) and is allowed.
void ListMembers(const Index& index, std::span<const KdNeighbor> neighbors, ClusterMask allowed,
                 std::vector<ClusterMember>* members) {
  members->clear();
  for (uint32_t rank = 0; rank < neighbors.size(); ++rank) {
    const uint32_t row = neighbors[rank].index;
    const uint32_t point = index.PointOfRow(row);
    if (!index.coded()) {
      members->push_back({rank, ClusterOfView(index, row), point, row});
      continue;
    }
    const size_t first = members->size();
    for (const uint32_t view : index.TrackOf(point)) {
      const uint32_t cluster = ClusterOfView(index, view);
      if (cluster == UINT32_MAX || !ClusterAllowed(allowed, cluster)) continue;
      bool seen = false;
      for (size_t m = first; m < members->size() && !seen; ++m)
        seen = (*members)[m].cluster == cluster;
      if (!seen) members->push_back({rank, cluster, point, view});
    }
  }
}

}  // namespace

void ClusterWiseRatioTest(const Index& index, uint32_t feature,
                          std::span<const KdNeighbor> neighbors, double ratio,
                          std::vector<FeatureMatch>* accepted, ForwardMatchingStats* stats,
                          ClusterMask allowed) {
  constexpr size_t kMaxNeighbors = kMaxK + 1;
  if (neighbors.size() > kMaxNeighbors) {
    throw std::invalid_argument("cluster-wise ratio test: " + std::to_string(neighbors.size()) +
                                " neighbours, at most " + std::to_string(kMaxNeighbors));
  }
  const size_t n = neighbors.size();
  if (n < 2) return;
  thread_local std::vector<ClusterMember> members;
  ListMembers(index, neighbors, allowed, &members);
  const uint32_t k = static_cast<uint32_t>(n - 1);  // the last only serves as a second neighbour
  for (size_t i = 0; i < members.size() && members[i].rank < k; ++i) {
    const ClusterMember& candidate = members[i];
    if (candidate.cluster == UINT32_MAX) continue;
    bool seen_cluster = false;
    for (size_t j = 0; j < i && !seen_cluster; ++j)
      seen_cluster = members[j].cluster == candidate.cluster;
    if (seen_cluster) continue;  // only the cluster's nearest neighbour is a candidate

    const KdNeighbor& nearest = neighbors[candidate.rank];
    const float d1 = std::sqrt(static_cast<float>(nearest.distance));
    float alpha;
    size_t second = members.size();
    for (size_t j = i + 1; j < members.size(); ++j) {
      if (members[j].cluster == candidate.cluster && members[j].point != candidate.point) {
        second = j;
        break;
      }
    }
    if (second < members.size()) {
      ++stats->local_ratio_tests;
      const float d2 = std::sqrt(static_cast<float>(neighbors[members[second].rank].distance));
      alpha = d2 > 0 ? d1 / d2 : 1.0f;
    } else {
      ++stats->t_ratio_tests;
      const float neighbor_distance = index.RowNeighborDistance(nearest.index);
      const float denominator = d1 + neighbor_distance;
      alpha = denominator > 0 ? d1 / denominator : 1.0f;  // inf v_NN gives 0: nothing competes
    }
    if (alpha <= ratio) accepted->push_back({feature, candidate.view, d1});
  }
}

}  // namespace cwloc
