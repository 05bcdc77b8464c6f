#pragma once

#include <cstdint>
#include <vector>

#include "indexer/clustering.h"
#include "indexer/model_views.h"

namespace cwloc {

// Clusters up to this many views get exact v_NN distances by brute force; larger ones (e.g.
// `--clusters 1` over a whole city) search a kd-forest, since n^2 / 2 distances would take hours.
inline constexpr size_t kExactNeighborMaxViews = 16384;
// The larger clusters' search: enough neighbours to skip the other views of a view's own 3D
// point, and a budget far above the localizer's, as this runs once, offline.
inline constexpr uint32_t kApproxNeighborCount = 32;
inline constexpr uint32_t kApproxNeighborChecks = 2048;

// The t-ratio's ||v - v_NN||: for each view, the L2 distance to the nearest view of a
// *different* 3D point in the same cluster (views of the same point are not competitors in the
// local ratio test). +infinity when the cluster holds no other point's view, or when a large
// cluster's search found none among its kApproxNeighborCount neighbours. Exact for clusters of
// at most kExactNeighborMaxViews views (sum of n^2 / 2 distances); approximate beyond, where a
// missed nearest neighbour can only make the distance larger.
// With `only_clusters` (one flag per cluster), only the flagged clusters' views get theirs (the
// others stay +infinity): `cwloc-index update` recomputes the clusters it changed, exactly as
// a build does.
std::vector<float> ComputeViewNeighborDistances(const ModelViews& views,
                                                const Clustering& clustering, int num_threads,
                                                const std::vector<bool>* only_clusters = nullptr);

}  // namespace cwloc
