#include "indexer/neighbor_distances.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "base/parallel_for.h"
#include "base/progress.h"
#include "kdtree/descriptor_distance.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {
namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Smallest squared distance from each member to a member of another 3D point, each pair once.
std::vector<uint32_t> ExactNearestOtherPoint(const ModelViews& views,
                                             const std::vector<uint32_t>& members) {
  const auto distance = BestDistanceFunctions().one;
  const uint8_t* descriptors = views.descriptors.data();
  std::vector<uint32_t> best(members.size(), kNone);
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
  return best;
}

// The same from a kd-forest over the members: the first of the nearest neighbours that is a
// view of another point.
std::vector<uint32_t> ApproximateNearestOtherPoint(const ModelViews& views,
                                                   const std::vector<uint32_t>& members,
                                                   int num_threads) {
  std::vector<uint8_t> descriptors(members.size() * kDescriptorBytes);
  for (size_t m = 0; m < members.size(); ++m) {
    std::memcpy(descriptors.data() + m * kDescriptorBytes,
                views.descriptors.data() + size_t{members[m]} * kDescriptorBytes, kDescriptorBytes);
  }
  KdForestBuildOptions options;
  options.num_threads = static_cast<uint32_t>(num_threads);
  const KdForest forest = BuildKdForest(descriptors, options);
  const KdForestView view = forest.View(descriptors);

  std::vector<uint32_t> best(members.size(), kNone);
  std::vector<KdForestSearcher> searchers(num_threads, KdForestSearcher(view));
  std::vector<std::vector<KdNeighbor>> neighbors(num_threads,
                                                 std::vector<KdNeighbor>(kApproxNeighborCount));
  KdSearchOptions search_options;
  search_options.max_checks = kApproxNeighborChecks;
  ParallelFor(members.size(), num_threads, [&](size_t m, int worker) {
    const KdSearchResult found = searchers[worker].Search(descriptors.data() + m * kDescriptorBytes,
                                                          search_options, neighbors[worker]);
    const uint32_t point = views.view_points[members[m]];
    for (uint32_t i = 0; i < found.num_neighbors; ++i) {
      const KdNeighbor& neighbor = neighbors[worker][i];
      if (views.view_points[members[neighbor.index]] != point) {
        best[m] = neighbor.distance;
        break;
      }
    }
  });
  return best;
}

}  // namespace

std::vector<float> ComputeViewNeighborDistances(const ModelViews& views,
                                                const Clustering& clustering, int num_threads,
                                                const std::vector<bool>* only_clusters) {
  const auto wanted = [&](size_t c) { return only_clusters == nullptr || (*only_clusters)[c]; };
  std::vector<std::vector<uint32_t>> cluster_images(clustering.num_clusters);
  std::vector<size_t> cluster_views(clustering.num_clusters, 0);
  for (uint32_t i = 0; i < views.images.size(); ++i) {
    cluster_images[clustering.cluster_of_image[i]].push_back(i);
    cluster_views[clustering.cluster_of_image[i]] += views.images[i].num_views;
  }
  auto members_of = [&](size_t c) {
    std::vector<uint32_t> members;
    for (uint32_t i : cluster_images[c]) {
      for (uint32_t v = 0; v < views.images[i].num_views; ++v)
        members.push_back(views.images[i].first_view + v);
    }
    return members;
  };

  std::vector<float> distances(views.num_views(), std::numeric_limits<float>::infinity());
  auto store = [&](const std::vector<uint32_t>& members, const std::vector<uint32_t>& best) {
    for (size_t m = 0; m < members.size(); ++m) {
      if (best[m] != kNone) distances[members[m]] = std::sqrt(static_cast<float>(best[m]));
    }
  };
  const int threads = ResolveThreads(num_threads);
  Progress progress("v_NN distances", clustering.num_clusters);
  ParallelFor(clustering.num_clusters, threads, [&](size_t c, int) {
    if (!wanted(c) || cluster_views[c] > kExactNeighborMaxViews) return;  // below, with all threads
    const std::vector<uint32_t> members = members_of(c);
    store(members, ExactNearestOtherPoint(views, members));
    progress.Advance();
  });
  for (size_t c = 0; c < clustering.num_clusters; ++c) {
    if (!wanted(c) || cluster_views[c] <= kExactNeighborMaxViews) continue;
    const std::vector<uint32_t> members = members_of(c);
    store(members, ApproximateNearestOtherPoint(views, members, threads));
    progress.Advance();
  }
  progress.Finish();
  return distances;
}

}  // namespace cwloc
