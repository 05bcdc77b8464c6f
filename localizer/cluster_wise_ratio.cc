#include "localizer/cluster_wise_ratio.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "localizer/localizer_options.h"

namespace cwloc {

void ClusterWiseRatioTest(const Index& index, uint32_t feature,
                          std::span<const KdNeighbor> neighbors, double ratio,
                          std::vector<FeatureMatch>* accepted, ForwardMatchingStats* stats) {
  constexpr size_t kMaxNeighbors = kMaxK + 1;
  if (neighbors.size() > kMaxNeighbors) {
    throw std::invalid_argument("cluster-wise ratio test: " + std::to_string(neighbors.size()) +
                                " neighbours, at most " + std::to_string(kMaxNeighbors));
  }
  const size_t n = neighbors.size();
  if (n < 2) return;
  uint32_t clusters[kMaxNeighbors];
  uint32_t points[kMaxNeighbors];
  for (size_t i = 0; i < n; ++i) {
    clusters[i] = ClusterOfView(index, neighbors[i].index);
    points[i] = neighbors[i].index < index.num_views() ? index.view_points()[neighbors[i].index]
                                                       : UINT32_MAX;
  }
  const size_t k = n - 1;  // the last neighbour only serves as a local second neighbour
  for (size_t i = 0; i < k; ++i) {
    if (clusters[i] == UINT32_MAX) continue;
    bool seen_cluster = false;
    for (size_t j = 0; j < i && !seen_cluster; ++j) seen_cluster = clusters[j] == clusters[i];
    if (seen_cluster) continue;  // only the cluster's nearest view is a candidate

    const float d1 = std::sqrt(static_cast<float>(neighbors[i].distance));
    float alpha;
    size_t second = n;
    for (size_t j = i + 1; j < n; ++j) {
      if (clusters[j] == clusters[i] && points[j] != points[i]) {
        second = j;
        break;
      }
    }
    if (second < n) {
      ++stats->local_ratio_tests;
      const float d2 = std::sqrt(static_cast<float>(neighbors[second].distance));
      alpha = d2 > 0 ? d1 / d2 : 1.0f;
    } else {
      ++stats->t_ratio_tests;
      const float neighbor_distance = index.view_neighbor_distances()[neighbors[i].index];
      const float denominator = d1 + neighbor_distance;
      alpha = denominator > 0 ? d1 / denominator : 1.0f;  // inf v_NN gives 0: nothing competes
    }
    if (alpha <= ratio) accepted->push_back({feature, neighbors[i].index, d1});
  }
}

}  // namespace cwloc
