#include "indexer/neighbor_distances.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "kdtree/descriptor_distance.h"

namespace cwloc {
namespace {

// Views of `points` 3D points, two views each, with SIFT-like structure: each point's
// descriptor is one of 64 "words" plus noise, and its two views differ by a little more noise.
ModelViews TwoViewsPerPoint(uint32_t points, uint32_t images) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 120), noise(-12, 12), small(-4, 4);
  std::vector<std::array<int, 128>> words(64);
  for (auto& word : words)
    for (int& value : word) value = byte(rng);
  ModelViews views;
  const uint32_t num_views = 2 * points;
  views.descriptors.resize(size_t{num_views} * 128);
  for (uint32_t p = 0; p < points; ++p) {
    const auto& word = words[rng() % words.size()];
    std::array<int, 128> base;
    for (size_t d = 0; d < 128; ++d) base[d] = word[d] + noise(rng);
    for (uint32_t copy = 0; copy < 2; ++copy) {
      uint8_t* out = views.descriptors.data() + size_t{2 * p + copy} * 128;
      for (size_t d = 0; d < 128; ++d)
        out[d] = static_cast<uint8_t>(std::clamp(base[d] + small(rng), 0, 255));
      views.view_points.push_back(p);
    }
  }
  const uint32_t per_image = num_views / images;
  for (uint32_t i = 0; i < images; ++i) {
    IndexImage image{};
    image.first_view = i * per_image;
    image.num_views = i + 1 == images ? num_views - i * per_image : per_image;
    views.images.push_back(image);
  }
  return views;
}

std::vector<uint32_t> BruteForce(const ModelViews& views) {
  std::vector<uint32_t> best(views.num_views(), UINT32_MAX);
  for (uint32_t a = 0; a < views.num_views(); ++a) {
    for (uint32_t b = 0; b < views.num_views(); ++b) {
      if (views.view_points[a] == views.view_points[b]) continue;
      best[a] = std::min(best[a], SquaredL2(&views.descriptors[size_t{a} * 128],
                                            &views.descriptors[size_t{b} * 128]));
    }
  }
  return best;
}

TEST(NeighborDistances, SmallClustersAreExact) {
  const ModelViews views = TwoViewsPerPoint(1000, 4);
  const Clustering one{{0, 0, 0, 0}, 1, "file"};
  const std::vector<float> distances = ComputeViewNeighborDistances(views, one, 2);
  const std::vector<uint32_t> exact = BruteForce(views);
  for (uint32_t v = 0; v < views.num_views(); ++v) {
    EXPECT_EQ(distances[v], std::sqrt(static_cast<float>(exact[v]))) << v;
  }
}

TEST(NeighborDistances, LargeClustersAreNearlyExactAndNeverTooSmall) {
  // One cluster just above the exact limit searches a kd-forest instead of n^2 / 2 distances.
  const uint32_t points = kExactNeighborMaxViews / 2 + 500;
  const ModelViews views = TwoViewsPerPoint(points, 8);
  const Clustering one{std::vector<uint32_t>(8, 0), 1, "file"};
  const std::vector<float> distances = ComputeViewNeighborDistances(views, one, 2);
  const std::vector<uint32_t> exact = BruteForce(views);
  uint32_t equal = 0;
  for (uint32_t v = 0; v < views.num_views(); ++v) {
    const float truth = std::sqrt(static_cast<float>(exact[v]));
    ASSERT_GE(distances[v], truth) << v;  // a missed neighbour can only overestimate
    equal += distances[v] == truth;
  }
  // Measured: every distance exact on this data.
  EXPECT_GE(equal, 0.95 * views.num_views());
}

}  // namespace
}  // namespace cwloc
