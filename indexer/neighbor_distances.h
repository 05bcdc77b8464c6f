#pragma once

#include <cstdint>
#include <vector>

#include "indexer/clustering.h"
#include "indexer/model_views.h"

namespace cwloc {

// The t-ratio's ||v - v_NN||: for each view, the exact L2 distance to the nearest view of a
// *different* 3D point in the same cluster (views of the same point are not competitors in the
// local ratio test). +infinity when the cluster holds no other point's view.
// Cost: sum over clusters of (views in cluster)^2 / 2 distances.
std::vector<float> ComputeViewNeighborDistances(const ModelViews& views, const Clustering& clustering,
                                                int num_threads);

}  // namespace cwloc
