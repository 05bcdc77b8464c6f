#include "localizer/forward_matching.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <span>
#include <string>
#include <tuple>

#include "base/split_mix64.h"
#include "localizer/cluster_wise_ratio.h"
#include "tests/localizer/matching_fixture.h"

namespace cwloc {
namespace {

class ForwardMatchingTest : public test::MatchingFixture {
 protected:
  std::vector<FeatureMatch> Run(const Query& query, const LocalizerOptions& options,
                                ForwardMatchingStats* stats) const {
    KdForestSearcher searcher(index_->kd_forest());
    return MatchForward(*index_, query, options, searcher, stats);
  }

  // Squared distance ratio of the nearest and the (k+1)-th nearest view.
  double KRatioSquared(const Descriptor& descriptor, uint32_t k) const {
    const std::vector<KdNeighbor> nearest = NearestViews(descriptor);
    return static_cast<double>(nearest[0].distance) / static_cast<double>(nearest[k].distance);
  }

  // A query of `num_features` features: every fourth one a copy of the fourth view of image
  // row 0, 1, ..., the others random. With k = 1 a copy gives exactly one match (its view at
  // distance 0) and a random feature fails the k-ratio test.
  Query CopiesAndRandoms(uint32_t num_features, std::map<uint32_t, uint32_t>* copied_view) const {
    Query query;
    for (uint32_t f = 0; f < num_features; ++f) {
      if (f % 4 == 0) {
        const uint32_t view = index_->images()[f / 4].first_view + 3;
        (*copied_view)[AddFeature(&query, ViewDescriptor(view))] = view;
      } else {
        const Descriptor random = RandomDescriptor();
        EXPECT_GT(KRatioSquared(random, 1), 0.6) << "a random feature would pass the k-ratio test";
        AddFeature(&query, random);
      }
    }
    return query;
  }

  // The matches MatchForward must give for such a query with k = 1: the copies in the order
  // SplitMix64(seed) shuffles the features into, at most `limit` of them. Sets `searched` to
  // the features visited until then.
  static std::vector<FeatureMatch> CopiesInShuffledOrder(
      uint32_t num_features, const std::map<uint32_t, uint32_t>& copied_view, uint64_t seed,
      uint32_t limit, uint32_t* searched) {
    std::vector<uint32_t> order(num_features);
    std::iota(order.begin(), order.end(), 0u);
    SplitMix64(seed).Shuffle(std::span<uint32_t>(order));
    std::vector<FeatureMatch> expected;
    *searched = 0;
    for (const uint32_t feature : order) {
      if (expected.size() == limit) break;
      ++*searched;
      if (const auto it = copied_view.find(feature); it != copied_view.end()) {
        expected.push_back({feature, it->second, 0.0f});
      }
    }
    return expected;
  }
};

MATCHER_P(EqualsMatch, expected, "") {
  return arg.feature == expected.feature && arg.view == expected.view &&
         arg.distance == expected.distance;
}

// Compares whole match lists, printing the feature and view of each.
void ExpectMatches(const std::vector<FeatureMatch>& actual,
                   const std::vector<FeatureMatch>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(actual[i].feature, expected[i].feature) << "match " << i;
    EXPECT_EQ(actual[i].view, expected[i].view) << "match " << i;
    EXPECT_EQ(actual[i].distance, expected[i].distance) << "match " << i;
  }
}

TEST_F(ForwardMatchingTest, StopsOnceNFMatchesPassedBothTests) {
  std::map<uint32_t, uint32_t> copied_view;
  const Query query = CopiesAndRandoms(32, &copied_view);
  ASSERT_EQ(copied_view.size(), 8u);
  LocalizerOptions options = ExactOptions();
  options.k = 1;
  options.seed = 5;
  for (const uint32_t nf : {1u, 3u, 8u, 100u}) {
    SCOPED_TRACE("N_F = " + std::to_string(nf));
    options.forward_matches = nf;
    uint32_t searched = 0;
    const std::vector<FeatureMatch> expected =
        CopiesInShuffledOrder(32, copied_view, 5, nf, &searched);
    if (nf <= 3) {
      ASSERT_LT(searched, 32u) << "the N_F-th copy should come before the last feature";
    }
    ForwardMatchingStats stats;
    ExpectMatches(Run(query, options, &stats), expected);
    // The loop stops right after the feature that gave the N_F-th match (all 32 for 100).
    EXPECT_EQ(stats.features_searched, searched);
    EXPECT_EQ(stats.passed_k_ratio, expected.size());
    EXPECT_EQ(stats.local_ratio_tests + stats.t_ratio_tests, expected.size());
  }
}

TEST_F(ForwardMatchingTest, NFCountsMatchesNotFeatures) {
  // With k = 5 a copy gives its own view and often views of other clusters among its 5 nearest
  // (the t-ratio is loose on random descriptors). Those come from Algorithm 2, tested on its own
  // in cluster_wise_ratio_test.cc; here it is run on brute-force neighbours as the reference.
  std::map<uint32_t, uint32_t> copied_view;
  const Query query = CopiesAndRandoms(32, &copied_view);
  LocalizerOptions options = ExactOptions();
  options.k = 5;
  options.seed = 3;
  std::map<uint32_t, std::vector<FeatureMatch>> matches_of;
  for (const auto& [feature, view] : copied_view) {
    Descriptor descriptor;
    std::copy_n(query.Descriptor(feature), 128, descriptor.begin());
    const std::vector<KdNeighbor> nearest = NearestViews(descriptor);
    ForwardMatchingStats unused;
    ClusterWiseRatioTest(*index_, feature, std::span(nearest).first(options.k + 1), options.ratio,
                         &matches_of[feature], &unused);
  }
  for (uint32_t f = 0; f < 32; ++f) {
    if (copied_view.contains(f)) continue;
    Descriptor random;
    std::copy_n(query.Descriptor(f), 128, random.begin());
    ASSERT_GT(KRatioSquared(random, options.k), 0.6) << "feature " << f;
  }
  std::vector<uint32_t> order(32);
  std::iota(order.begin(), order.end(), 0u);
  SplitMix64(options.seed).Shuffle(std::span<uint32_t>(order));
  for (const uint32_t nf : {3u, 6u}) {
    SCOPED_TRACE("N_F = " + std::to_string(nf));
    options.forward_matches = nf;
    std::vector<FeatureMatch> expected;
    uint32_t searched = 0, copies = 0;
    for (const uint32_t feature : order) {
      if (expected.size() >= nf) break;
      ++searched;
      if (!copied_view.contains(feature)) continue;
      ++copies;
      expected.insert(expected.end(), matches_of[feature].begin(), matches_of[feature].end());
    }
    // Counting features instead would search on until the N_F-th copy.
    ASSERT_LT(copies, nf);
    ForwardMatchingStats stats;
    ExpectMatches(Run(query, options, &stats), expected);
    EXPECT_EQ(stats.features_searched, searched);
    EXPECT_EQ(stats.passed_k_ratio, copies);
  }
}

TEST_F(ForwardMatchingTest, TheKRatioTestRejectsFeaturesWithoutADistinctNearestView) {
  // Copies (d1 = 0) and near copies (16 bytes moved by 32: d1 = 128) pass; far copies (53 bytes
  // moved: d1 = 233) and random features fail: the 6th view is ~260 away from anything.
  auto moved = [](Descriptor descriptor, int bytes) {
    for (int d = 0; d < bytes; ++d) {
      descriptor[d] =
          static_cast<uint8_t>(descriptor[d] < 32 ? descriptor[d] + 32 : descriptor[d] - 32);
    }
    return descriptor;
  };
  LocalizerOptions options = ExactOptions();
  options.k = 5;
  options.forward_matches = 1000;
  Query query;
  std::vector<FeatureMatch> passing;  // each passing feature with its nearest view
  for (uint32_t i = 0; i < 4; ++i) {
    const uint32_t view = index_->images()[i].first_view + 1;
    passing.push_back({AddFeature(&query, ViewDescriptor(view)), view, 0.0f});
    const Descriptor near = moved(ViewDescriptor(view + 1), 16);
    ASSERT_EQ(NearestViews(near)[0].index, view + 1);
    ASSERT_LT(KRatioSquared(near, options.k), 0.35);
    passing.push_back({AddFeature(&query, near), view + 1, 128.0f});
    const Descriptor far = moved(ViewDescriptor(view + 2), 53);
    ASSERT_GT(KRatioSquared(far, options.k), 0.65);
    AddFeature(&query, far);
    const Descriptor random = RandomDescriptor();
    ASSERT_GT(KRatioSquared(random, options.k), 0.65);
    AddFeature(&query, random);
  }
  ForwardMatchingStats stats;
  const std::vector<FeatureMatch> matches = Run(query, options, &stats);
  EXPECT_EQ(stats.features_searched, 16u);
  EXPECT_EQ(stats.passed_k_ratio, 8u);
  // Only features that passed are matched, each to its nearest view at least (the other
  // clusters among its k neighbours may pass the cluster-wise test too).
  std::set<uint32_t> matched_features;
  for (const FeatureMatch& match : matches) matched_features.insert(match.feature);
  std::set<uint32_t> passing_features;
  for (const FeatureMatch& match : passing) passing_features.insert(match.feature);
  EXPECT_EQ(matched_features, passing_features);
  for (const FeatureMatch& match : passing) {
    EXPECT_THAT(matches, testing::Contains(EqualsMatch(match))) << "feature " << match.feature;
  }
}

TEST_F(ForwardMatchingTest, TheLocalRatioDecidesWhenTheClusterHasAViewOfAnotherPoint) {
  LocalizerOptions options = ExactOptions();
  options.forward_matches = 1000;
  // k = 1: a copied view is tested against its nearest other view, locally when that view is in
  // the same cluster (of another point), otherwise with the t-ratio; both accept distance 0.
  std::vector<uint32_t> local_views, t_views;
  for (uint32_t view = 0; view < index_->num_views(); ++view) {
    const uint32_t second = NearestViews(ViewDescriptor(view))[1].index;
    const bool local = ClusterOf(second) == ClusterOf(view) && PointOf(second) != PointOf(view);
    if (ClusterOf(second) == ClusterOf(view) && !local) continue;
    std::vector<uint32_t>& views = local ? local_views : t_views;
    if (views.size() < 3) views.push_back(view);
    if (local_views.size() == 3 && t_views.size() == 3) break;
  }
  ASSERT_EQ(local_views.size(), 3u);
  ASSERT_EQ(t_views.size(), 3u);
  options.k = 1;
  for (const auto& [views, local] : {std::pair{local_views, true}, std::pair{t_views, false}}) {
    SCOPED_TRACE(local ? "local 1-ratio" : "t-ratio");
    Query query;
    std::vector<FeatureMatch> expected;
    for (const uint32_t view : views) {
      expected.push_back({AddFeature(&query, ViewDescriptor(view)), view, 0.0f});
    }
    options.seed = 0;
    ForwardMatchingStats stats;
    std::vector<FeatureMatch> matches = Run(query, options, &stats);
    std::sort(matches.begin(), matches.end(),
              [](const auto& a, const auto& b) { return a.feature < b.feature; });
    ExpectMatches(matches, expected);
    EXPECT_EQ(stats.local_ratio_tests, local ? 3u : 0u);
    EXPECT_EQ(stats.t_ratio_tests, local ? 0u : 3u);
  }

  // k = 2: the midpoint of the closest two views of distinct points in one image has both as
  // its two nearest views, at about the same distance. It passes the k-ratio test (the third
  // view is far); the local 1-ratio rejects it, where the t-ratio would have accepted it.
  uint32_t a = 0, b = 0, best = UINT32_MAX;
  for (const IndexImage& image : index_->images()) {
    for (uint32_t u = image.first_view; u < image.first_view + image.num_views; ++u) {
      for (uint32_t v = u + 1; v < image.first_view + image.num_views; ++v) {
        const uint32_t distance =
            SquaredL2(index_->ViewDescriptor(u, nullptr), index_->ViewDescriptor(v, nullptr));
        if (PointOf(u) != PointOf(v) && distance < best) {
          std::tie(a, b, best) = std::tuple(u, v, distance);
        }
      }
    }
  }
  Descriptor midpoint;
  for (size_t d = 0; d < 128; ++d) {
    midpoint[d] = static_cast<uint8_t>(
        (index_->ViewDescriptor(a, nullptr)[d] + index_->ViewDescriptor(b, nullptr)[d]) / 2);
  }
  const std::vector<KdNeighbor> nearest = NearestViews(midpoint);
  ASSERT_EQ(std::min(nearest[0].index, nearest[1].index), a);
  ASSERT_EQ(std::max(nearest[0].index, nearest[1].index), b);
  const double d1 = std::sqrt(nearest[0].distance), d2 = std::sqrt(nearest[1].distance);
  ASSERT_LT(d1 / std::sqrt(nearest[2].distance), 0.65) << "the k-ratio test must pass";
  ASSERT_GT(d1 / d2, 0.9) << "the local 1-ratio must fail";
  ASSERT_LT(d1 / (d1 + index_->view_neighbor_distances()[nearest[0].index]), 0.5)
      << "the t-ratio would pass";
  options.k = 2;
  Query query;
  AddFeature(&query, midpoint);
  ForwardMatchingStats stats;
  EXPECT_TRUE(Run(query, options, &stats).empty());
  EXPECT_EQ(stats.passed_k_ratio, 1u);
  EXPECT_EQ(stats.local_ratio_tests, 1u);
  EXPECT_EQ(stats.t_ratio_tests, 0u);
}

TEST_F(ForwardMatchingTest, TheSeedFixesTheFeatureOrder) {
  std::map<uint32_t, uint32_t> copied_view;
  const Query query = CopiesAndRandoms(32, &copied_view);
  LocalizerOptions options = ExactOptions();
  options.k = 1;
  options.forward_matches = 1000;
  std::vector<std::vector<FeatureMatch>> runs;
  for (const uint64_t seed : {1u, 1u, 2u}) {
    options.seed = seed;
    ForwardMatchingStats stats;
    runs.push_back(Run(query, options, &stats));
    uint32_t searched = 0;
    ExpectMatches(runs.back(), CopiesInShuffledOrder(32, copied_view, seed, 1000, &searched));
  }
  ExpectMatches(runs[1], runs[0]);
  // Another seed: the same matches in another order.
  auto features = [](const std::vector<FeatureMatch>& matches) {
    std::vector<uint32_t> out;
    for (const FeatureMatch& match : matches) out.push_back(match.feature);
    return out;
  };
  EXPECT_NE(features(runs[2]), features(runs[0]));
  std::vector<uint32_t> sorted0 = features(runs[0]), sorted2 = features(runs[2]);
  std::sort(sorted0.begin(), sorted0.end());
  std::sort(sorted2.begin(), sorted2.end());
  EXPECT_EQ(sorted2, sorted0);
}

}  // namespace
}  // namespace cwloc
