#include "localizer/exhaustive_matching.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/stopwatch.h"
#include "kdtree/descriptor_distance.h"

namespace cwloc {
namespace {

// The two nearest views of distinct 3D points seen so far, for one query feature.
struct NearestTwo {
  uint32_t best = std::numeric_limits<uint32_t>::max();
  uint32_t second = std::numeric_limits<uint32_t>::max();
  uint32_t view = 0;
  uint32_t point = std::numeric_limits<uint32_t>::max();

  void Offer(uint32_t distance, uint32_t candidate_view, uint32_t candidate_point) {
    if (distance < best) {
      if (candidate_point != point) second = best;
      best = distance;
      view = candidate_view;
      point = candidate_point;
    } else if (distance < second && candidate_point != point) {
      second = distance;
    }
  }
};

// Views are compared in blocks small enough to stay in L2 while every query feature passes.
constexpr size_t kBlockViews = 1024;

}  // namespace

std::vector<ClusterMatches> MatchEachClusterExhaustively(const Index& index,
                                                         const ClusterMembers& clusters,
                                                         const Query& query, double ratio,
                                                         ForwardMatchingStats* stats) {
  const Stopwatch stopwatch;
  const DistanceFunctions& distance = BestDistanceFunctions();
  const uint32_t num_features = query.NumFeatures();
  const std::span<const uint32_t> view_points = index.view_points();
  std::vector<ClusterMatches> out;
  std::vector<NearestTwo> nearest(num_features);
  std::vector<uint32_t> block;
  std::vector<uint32_t> distances(kBlockViews);
  block.reserve(kBlockViews);

  // A coded index's block is decoded once, then compared like exact rows.
  std::vector<uint8_t> decoded(index.coded() ? kBlockViews * kDescriptorBytes : 0);
  std::vector<uint32_t> decoded_rows(index.coded() ? kBlockViews : 0);
  for (uint32_t i = 0; i < decoded_rows.size(); ++i) decoded_rows[i] = i;

  auto compare_block = [&] {
    const uint8_t* base = index.descriptors().data();
    const uint32_t* rows = block.data();
    if (index.coded()) {
      for (size_t i = 0; i < block.size(); ++i)
        index.ViewDescriptor(block[i], &decoded[i * kDescriptorBytes]);
      base = decoded.data();
      rows = decoded_rows.data();
    }
    for (uint32_t feature = 0; feature < num_features; ++feature) {
      distance.batch(query.Descriptor(feature), base, rows, block.size(), distances.data());
      NearestTwo& two = nearest[feature];
      for (size_t i = 0; i < block.size(); ++i)
        two.Offer(distances[i], block[i], view_points[block[i]]);
    }
    block.clear();
  };

  for (uint32_t cluster = 0; cluster < clusters.num_clusters(); ++cluster) {
    std::fill(nearest.begin(), nearest.end(), NearestTwo{});
    for (uint32_t i = clusters.offsets[cluster]; i < clusters.offsets[cluster + 1]; ++i) {
      const IndexImage& image = index.images()[clusters.images[i]];
      const uint64_t end =
          std::min<uint64_t>(uint64_t{image.first_view} + image.num_views, index.num_views());
      for (uint64_t view = image.first_view; view < end; ++view) {
        if (view_points[view] >= index.num_points()) continue;  // a corrupt view; verify names it
        block.push_back(static_cast<uint32_t>(view));
        if (block.size() == kBlockViews) compare_block();
      }
    }
    if (!block.empty()) compare_block();

    ClusterMatches found{cluster, {}};
    for (uint32_t feature = 0; feature < num_features; ++feature) {
      const NearestTwo& two = nearest[feature];
      // A cluster with a single 3D point near this feature offers no second neighbour to test.
      if (two.second == std::numeric_limits<uint32_t>::max()) continue;
      if (!PassesRatioTest(two.best, two.second, ratio)) continue;
      found.matches.push_back({feature, two.view, std::sqrt(static_cast<float>(two.best))});
    }
    if (!found.matches.empty()) out.push_back(std::move(found));
  }
  stats->features_searched = num_features;
  stats->seconds_knn = stopwatch.Seconds();
  return out;
}

}  // namespace cwloc
