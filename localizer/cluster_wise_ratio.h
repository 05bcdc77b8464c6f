#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/index.h"
#include "kdtree/kd_forest.h"
#include "localizer/matching.h"

namespace cwloc {

// Algorithm 2 (cluster-wise ratio test) for one query feature whose k+1 global nearest
// neighbours (at most kMaxK + 1) passed the k-ratio test. For each cluster among the first k
// neighbours, its closest view v_c1 is tested:
//  - against the next neighbour in the same cluster that is a view of another 3D point (the
//    local 1-ratio; the (k+1)-th neighbour counts too, since everything closer was retrieved);
//  - otherwise with the t-ratio ||q - v_c1|| / (||q - v_c1|| + ||v_c1 - v_NN||), v_NN from VNND.
// Accepted (feature, v_c1) pairs are appended to `accepted`.
// In a coded index the neighbours are 3D points, and a point belongs to every cluster that
// sees it: it is the candidate of each such cluster (as its view in that cluster) at its
// distance, and v_NN is the point's PVNN (docs/algorithm.md, "The compact index").
// With `allowed` (a position prior), clusters outside it take no part: a coded index's point
// in the region is not a candidate of its clusters elsewhere, so the test judges as it would in
// a tile of the region (`cwloc-index extract`).
void ClusterWiseRatioTest(const Index& index, uint32_t feature,
                          std::span<const KdNeighbor> neighbors, double ratio,
                          std::vector<FeatureMatch>* accepted, ForwardMatchingStats* stats,
                          ClusterMask allowed = {});

}  // namespace cwloc
