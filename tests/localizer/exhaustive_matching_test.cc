#include "localizer/exhaustive_matching.h"

#include <gtest/gtest.h>

#include "tests/localizer/matching_fixture.h"

namespace cwloc {
namespace {

// Queries made of model descriptors, over the fixture index (one cluster per image, random
// descriptors per view), so each cluster's nearest and second-nearest views are known.
class ExhaustiveMatchingTest : public test::MatchingFixture {
 protected:
  void AddFeature(Query* query, const uint8_t* descriptor) const {
    query->keypoints.insert(query->keypoints.end(), {10.0f, 20.0f});
    query->descriptors.insert(query->descriptors.end(), descriptor, descriptor + 128);
  }
};

TEST_F(ExhaustiveMatchingTest, AModelDescriptorMatchesItsOwnPointInItsCluster) {
  const IndexImage& image = index_->images()[0];
  ASSERT_GE(image.num_views, 3u);
  Query query;
  for (uint32_t i = 0; i < 3; ++i)
    AddFeature(&query, index_->ViewDescriptor(image.first_view + i, nullptr));
  ForwardMatchingStats stats;
  const std::vector<ClusterMatches> found =
      MatchEachClusterExhaustively(*index_, *clusters_, query, 0.7, &stats);
  EXPECT_EQ(stats.features_searched, 3u);
  const auto own = std::find_if(found.begin(), found.end(), [&](const ClusterMatches& c) {
    return c.cluster == image.cluster;
  });
  ASSERT_NE(own, found.end());
  ASSERT_EQ(own->matches.size(), 3u);
  for (uint32_t i = 0; i < 3; ++i) {
    const FeatureMatch& match = own->matches[i];
    EXPECT_EQ(match.feature, i);
    // Distance 0 to the copied view: the match is that view or another view of its point with
    // the same descriptor.
    EXPECT_EQ(match.distance, 0.0f);
    EXPECT_EQ(index_->view_points()[match.view], index_->view_points()[image.first_view + i]);
  }
  // Random descriptors of other images are far from each other: no cluster passes the ratio
  // test for a copied descriptor by chance except its own and the clusters sharing its point.
  for (const ClusterMatches& cluster : found) {
    for (const FeatureMatch& match : cluster.matches) {
      EXPECT_EQ(index_->view_points()[match.view],
                index_->view_points()[image.first_view + match.feature]);
    }
  }
}

TEST_F(ExhaustiveMatchingTest, AFeatureBetweenTwoPointsOfOneClusterFailsTheRatioTest) {
  const IndexImage& image = index_->images()[0];
  const uint32_t a = image.first_view, b = image.first_view + 1;
  ASSERT_NE(index_->view_points()[a], index_->view_points()[b]);
  uint8_t midpoint[128];
  for (size_t d = 0; d < 128; ++d) {
    midpoint[d] = static_cast<uint8_t>(
        (index_->ViewDescriptor(a, nullptr)[d] + index_->ViewDescriptor(b, nullptr)[d]) / 2);
  }
  Query query;
  AddFeature(&query, midpoint);
  ForwardMatchingStats stats;
  for (const ClusterMatches& cluster :
       MatchEachClusterExhaustively(*index_, *clusters_, query, 0.7, &stats)) {
    EXPECT_NE(cluster.cluster, image.cluster) << "nearly equidistant views of two points passed";
  }
  // With tau = 1 the nearer of the two is accepted in that cluster.
  const auto loose = MatchEachClusterExhaustively(*index_, *clusters_, query, 1.0, &stats);
  const auto own = std::find_if(loose.begin(), loose.end(), [&](const ClusterMatches& c) {
    return c.cluster == image.cluster;
  });
  ASSERT_NE(own, loose.end());
  ASSERT_EQ(own->matches.size(), 1u);
  const uint32_t point = index_->view_points()[own->matches[0].view];
  EXPECT_TRUE(point == index_->view_points()[a] || point == index_->view_points()[b]);
}

}  // namespace
}  // namespace cwloc
