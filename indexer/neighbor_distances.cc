#include "indexer/neighbor_distances.h"

#include <cmath>
#include <limits>

#include "format/descriptor_distance.h"
#include "format/progress.h"
#include "format/parallel_for.h"

namespace cwloc {

std::vector<float> ComputeViewNeighborDistances(const ModelViews& views, const Clustering& clustering,
                                                int num_threads) {
  std::vector<std::vector<uint32_t>> cluster_images(clustering.num_clusters);
  for (uint32_t i = 0; i < views.images.size(); ++i) cluster_images[clustering.cluster_of_image[i]].push_back(i);

  std::vector<float> distances(views.num_views(), std::numeric_limits<float>::infinity());
  const auto distance = BestDistanceFunctions().one;
  const uint8_t* descriptors = views.descriptors.data();
  Progress progress("v_NN distances", clustering.num_clusters);
  ParallelFor(clustering.num_clusters, ResolveThreads(num_threads), [&](size_t c, int) {
    std::vector<uint32_t> members;
    for (uint32_t i : cluster_images[c]) {
      for (uint32_t v = 0; v < views.images[i].num_views; ++v) members.push_back(views.images[i].first_view + v);
    }
    std::vector<uint32_t> best(members.size(), std::numeric_limits<uint32_t>::max());
    // Each pair once, updating both ends.
    for (size_t a = 0; a < members.size(); ++a) {
      const uint32_t va = members[a];
      const uint8_t* da = descriptors + size_t{va} * kDescriptorBytes;
      const uint32_t pa = views.view_points[va];
      uint32_t best_a = best[a];
      for (size_t b = a + 1; b < members.size(); ++b) {
        const uint32_t vb = members[b];
        if (views.view_points[vb] == pa) continue;
        const uint32_t d = distance(da, descriptors + size_t{vb} * kDescriptorBytes);
        best_a = std::min(best_a, d);
        best[b] = std::min(best[b], d);
      }
      best[a] = best_a;
    }
    for (size_t a = 0; a < members.size(); ++a) {
      if (best[a] != std::numeric_limits<uint32_t>::max()) distances[members[a]] = std::sqrt(static_cast<float>(best[a]));
    }
    progress.Advance();
  });
  progress.Finish();
  return distances;
}

}  // namespace cwloc
