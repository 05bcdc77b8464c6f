#include "localizer/cluster_wise_ratio.h"

#include <gtest/gtest.h>

#include <tuple>

#include "tests/localizer/matching_fixture.h"

namespace cwloc {
namespace {

// Neighbour lists are made by hand over a real index (one cluster per image) so that each
// branch of Algorithm 2 is exercised with known distances.
class ClusterRatioTest : public test::MatchingFixture {
 protected:
  // The i-th view of image row `image` (distinct points for distinct i in practice).
  uint32_t View(uint32_t image, uint32_t i) const { return index_->images()[image].first_view + i; }

  std::vector<FeatureMatch> Run(const std::vector<KdNeighbor>& neighbors,
                                ForwardMatchingStats* stats) const {
    std::vector<FeatureMatch> accepted;
    ClusterWiseRatioTest(*index_, 7, neighbors, 0.7, &accepted, stats);
    return accepted;
  }
};

TEST_F(ClusterRatioTest, TwoViewsOfDistinctPointsInOneClusterUseTheLocalRatio) {
  ASSERT_NE(index_->view_points()[View(0, 0)], index_->view_points()[View(0, 1)]);
  ForwardMatchingStats stats;
  // d1 = 10, d2 = 20 in cluster 0: 0.5 <= 0.7 passes; others in other clusters.
  auto accepted = Run({{View(0, 0), 100},
                       {View(1, 0), 150},
                       {View(0, 1), 400},
                       {View(2, 0), 500},
                       {View(3, 0), 600},
                       {View(4, 0), 700}},
                      &stats);
  EXPECT_GE(stats.local_ratio_tests, 1u);
  ASSERT_FALSE(accepted.empty());
  EXPECT_EQ(accepted[0].feature, 7u);
  EXPECT_EQ(accepted[0].view, View(0, 0));
  EXPECT_FLOAT_EQ(accepted[0].distance, 10.0f);
  // d1 = 10, d2 = 12: 0.83 fails, and the second view is never a candidate itself.
  stats = {};
  accepted = Run({{View(0, 0), 100},
                  {View(0, 1), 144},
                  {View(1, 0), 10000},
                  {View(2, 0), 10000},
                  {View(3, 0), 10000},
                  {View(4, 0), 10000}},
                 &stats);
  for (const FeatureMatch& match : accepted) {
    EXPECT_NE(match.view, View(0, 0));
    EXPECT_NE(match.view, View(0, 1));
  }
}

TEST_F(ClusterRatioTest, TheLastNeighbourServesOnlyAsASecondNeighbour) {
  ForwardMatchingStats stats;
  // Cluster 0's second view is the (k+1)-th neighbour: 10 / 20 passes by the local test.
  const auto accepted = Run({{View(0, 0), 100},
                             {View(1, 0), 9000},
                             {View(2, 0), 9000},
                             {View(3, 0), 9000},
                             {View(4, 0), 9000},
                             {View(0, 1), 400}},
                            &stats);
  EXPECT_EQ(stats.local_ratio_tests, 1u);
  EXPECT_EQ(stats.t_ratio_tests, 4u);
  ASSERT_FALSE(accepted.empty());
  EXPECT_EQ(accepted[0].view, View(0, 0));
  for (const FeatureMatch& match : accepted) EXPECT_NE(match.view, View(0, 1));
}

TEST_F(ClusterRatioTest, ASingletonUsesTheTRatioWithTheStoredNeighbourDistance) {
  const uint32_t view = View(0, 0);
  const float neighbor = index_->view_neighbor_distances()[view];
  ASSERT_TRUE(std::isfinite(neighbor));
  // t-ratio d / (d + nn) <= 0.7  <=>  d <= 7/3 nn.
  const float pass = neighbor * 2.0f;
  const float fail = neighbor * 2.5f;
  for (const auto& [d, expect_pass] : {std::pair{pass, true}, std::pair{fail, false}}) {
    ForwardMatchingStats stats;
    const uint32_t squared = static_cast<uint32_t>(d * d);
    const auto accepted = Run({{view, squared},
                               {View(1, 0), squared + 1},
                               {View(2, 0), squared + 2},
                               {View(3, 0), squared + 3},
                               {View(4, 0), squared + 4},
                               {View(5, 0), squared * 9}},
                              &stats);
    EXPECT_EQ(stats.t_ratio_tests, 5u);
    const bool passed = std::any_of(accepted.begin(), accepted.end(),
                                    [&](const auto& m) { return m.view == view; });
    EXPECT_EQ(passed, expect_pass) << "d = " << d << ", v_NN distance = " << neighbor;
  }
}

TEST_F(ClusterRatioTest, AViewOfTheSamePointIsNoLocalSecondNeighbour) {
  // Two views of one point in one image (COLMAP allows it; the fixture model has some).
  uint32_t image = 0, u = 0, w = 0;
  for (; image < index_->images().size() && u == w; ++image) {
    for (uint32_t i = 0; i < index_->images()[image].num_views && u == w; ++i) {
      for (uint32_t j = i + 1; j < index_->images()[image].num_views; ++j) {
        if (index_->view_points()[View(image, i)] == index_->view_points()[View(image, j)]) {
          std::tie(u, w) = std::pair(View(image, i), View(image, j));
          break;
        }
      }
    }
  }
  ASSERT_NE(u, w) << "no point is seen twice in one image";
  ASSERT_TRUE(std::isfinite(index_->view_neighbor_distances()[u]));
  std::vector<KdNeighbor> neighbors = {{u, 100}, {w, 121}};
  for (uint32_t other = 0; neighbors.size() < 6; ++other) {
    if (index_->ImageOfView(View(other, 0)) != index_->ImageOfView(u)) {
      neighbors.push_back({View(other, 0), 10000});
    }
  }
  // 10 / 11 would fail the local 1-ratio; u's cluster has no other point among the
  // neighbours, so the t-ratio decides (v_NN is ~260 away) and accepts.
  ForwardMatchingStats stats;
  const auto accepted = Run(neighbors, &stats);
  EXPECT_EQ(stats.local_ratio_tests, 0u);
  EXPECT_EQ(stats.t_ratio_tests, 4u);
  ASSERT_FALSE(accepted.empty());
  EXPECT_EQ(accepted[0].view, u);
  EXPECT_FLOAT_EQ(accepted[0].distance, 10.0f);
}

}  // namespace
}  // namespace cwloc
