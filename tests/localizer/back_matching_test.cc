#include "localizer/back_matching.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "localizer/query_pose.h"
#include "tests/localizer/matching_fixture.h"

namespace cwloc {
namespace {

// Queries hold copies of chosen views plus random features. Back-matching a cluster then finds
// exactly its copied views: a copy is at distance 0 from its view, while every other query
// feature is about equally far from a view (SetUp checks this once for the whole model).
// Forward matches are made by hand: only their views count, as votes for their clusters.
class BackMatchingTest : public test::MatchingFixture {
 protected:
  void SetUp() override {
    MatchingFixture::SetUp();
    for (int i = 0; i < 20; ++i) AddFeature(&randoms_, RandomDescriptor());
    // No view has a random feature clearly nearest: the 1-ratio test rejects them all.
    for (uint32_t view = 0; view < index_->num_views(); ++view) {
      std::vector<uint32_t> distances;
      for (uint32_t f = 0; f < randoms_.NumFeatures(); ++f) {
        distances.push_back(
            SquaredL2(index_->ViewDescriptor(view, nullptr), randoms_.Descriptor(f)));
      }
      std::partial_sort(distances.begin(), distances.begin() + 2, distances.end());
      ASSERT_GT(distances[0], 0.6 * distances[1]) << "view " << view;
    }
  }

  // The `i`-th cluster (an image), and its `j`-th view.
  uint32_t Cluster(uint32_t i) const { return index_->images()[i].cluster; }
  uint32_t View(uint32_t cluster, uint32_t j) const {
    return ImageOfCluster(cluster).first_view + j;
  }

  // Copies `views` into a query followed by the random features; the copies are the expected
  // back-matches, in view order.
  Query QueryOf(const std::vector<uint32_t>& views, std::vector<FeatureMatch>* copies) const {
    Query query;
    for (const uint32_t view : views)
      copies->push_back({AddFeature(&query, ViewDescriptor(view)), view, 0.0f});
    query.keypoints.insert(query.keypoints.end(), randoms_.keypoints.begin(),
                           randoms_.keypoints.end());
    query.descriptors.insert(query.descriptors.end(), randoms_.descriptors.begin(),
                             randoms_.descriptors.end());
    std::sort(copies->begin(), copies->end(),
              [](const auto& a, const auto& b) { return a.view < b.view; });
    return query;
  }

  // The first `count` views of `cluster`.
  std::vector<uint32_t> ViewsOf(uint32_t cluster, uint32_t count) const {
    EXPECT_GE(ImageOfCluster(cluster).num_views, count);
    std::vector<uint32_t> views;
    for (uint32_t j = 0; j < count; ++j) views.push_back(View(cluster, j));
    return views;
  }

  // `votes[c]` forward matches into each cluster c, listed in the order given.
  std::vector<FeatureMatch> Votes(const std::vector<std::pair<uint32_t, uint32_t>>& votes) const {
    std::vector<FeatureMatch> matches;
    for (const auto& [cluster, count] : votes) {
      for (uint32_t i = 0; i < count; ++i) matches.push_back({i, View(cluster, i), 1.0f});
    }
    return matches;
  }

  // Exact searches in the query's forest.
  LocalizerOptions Options(const Query& query) const {
    LocalizerOptions options;
    options.query_tree_checks = query.NumFeatures();
    return options;
  }

  BackMatchingResult Run(const Query& query, const std::vector<FeatureMatch>& forward,
                         const LocalizerOptions& options) const {
    return MatchBack(*index_, *clusters_, query, forward, options);
  }

  Query randoms_;
};

void ExpectVisited(const std::vector<VisitedCluster>& actual,
                   const std::vector<VisitedCluster>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(actual[i].cluster, expected[i].cluster) << "visit " << i;
    EXPECT_EQ(actual[i].votes, expected[i].votes) << "visit " << i;
    EXPECT_EQ(actual[i].matches, expected[i].matches) << "visit " << i;
  }
}

void ExpectMatches(const std::vector<FeatureMatch>& actual,
                   const std::vector<FeatureMatch>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(actual[i].feature, expected[i].feature) << "match " << i;
    EXPECT_EQ(actual[i].view, expected[i].view) << "match " << i;
    EXPECT_EQ(actual[i].distance, expected[i].distance) << "match " << i;
  }
}

// The matches of `copies` into the given clusters, in that order.
std::vector<FeatureMatch> CopiesOf(const std::vector<FeatureMatch>& copies,
                                   const std::vector<uint32_t>& order, const Index& index) {
  std::vector<FeatureMatch> out;
  for (const uint32_t cluster : order) {
    for (const FeatureMatch& copy : copies) {
      if (ClusterOfView(index, copy.view) == cluster) out.push_back(copy);
    }
  }
  return out;
}

TEST_F(BackMatchingTest, ForwardVotesOrderTheClusters) {
  const uint32_t a = Cluster(3), b = Cluster(6), c = Cluster(1);
  std::vector<uint32_t> views = ViewsOf(a, 4);
  for (const uint32_t v : ViewsOf(b, 3)) views.push_back(v);
  for (const uint32_t v : ViewsOf(c, 2)) views.push_back(v);
  std::vector<FeatureMatch> copies;
  const Query query = QueryOf(views, &copies);
  const BackMatchingResult result = Run(query, Votes({{c, 1}, {b, 3}, {a, 5}}), Options(query));
  // Most votes first; with fewer than 12 back-matches a cluster votes for nothing, so the loop
  // ends when the three voted clusters are done.
  ExpectVisited(result.visited, {{a, 5, 4}, {b, 3, 3}, {c, 1, 2}});
  ExpectMatches(result.matches, CopiesOf(copies, {a, b, c}, *index_));
  std::vector<uint32_t> votes(clusters_->num_clusters(), 0);
  votes[a] = 5, votes[b] = 3, votes[c] = 1;
  EXPECT_EQ(result.cluster_votes, votes);
}

TEST_F(BackMatchingTest, EqualVotesGoToTheLowerClusterFirst) {
  const uint32_t a = Cluster(7), b = Cluster(2), c = Cluster(5);
  ASSERT_TRUE(b < c && c < a);
  std::vector<uint32_t> views;
  for (const uint32_t cluster : {a, b, c}) views.push_back(View(cluster, 0));
  std::vector<FeatureMatch> copies;
  const Query query = QueryOf(views, &copies);
  // Voted for in the order a, b, c: neither the first voted nor the highest id goes first.
  const BackMatchingResult result = Run(query, Votes({{a, 3}, {b, 3}, {c, 3}}), Options(query));
  ExpectVisited(result.visited, {{b, 3, 1}, {c, 3, 1}, {a, 3, 1}});
  ExpectMatches(result.matches, CopiesOf(copies, {b, c, a}, *index_));
}

TEST_F(BackMatchingTest, StopsAfterMaxBackImagesClusters) {
  EXPECT_EQ(LocalizerOptions().max_back_clusters, 20u);  // the paper's 20 clusters
  std::vector<uint32_t> views;
  std::vector<std::pair<uint32_t, uint32_t>> votes;
  for (uint32_t i = 0; i < 6; ++i) {
    views.push_back(View(Cluster(i), 0));
    votes.push_back({Cluster(i), 6 - i});
  }
  std::vector<FeatureMatch> copies;
  const Query query = QueryOf(views, &copies);
  LocalizerOptions options = Options(query);
  options.max_back_clusters = 3;
  const BackMatchingResult result = Run(query, Votes(votes), options);
  ExpectVisited(result.visited, {{Cluster(0), 6, 1}, {Cluster(1), 5, 1}, {Cluster(2), 4, 1}});
  ExpectMatches(result.matches, CopiesOf(copies, {Cluster(0), Cluster(1), Cluster(2)}, *index_));
  options.max_back_clusters = 20;
  EXPECT_EQ(Run(query, Votes(votes), options).visited.size(), 6u);
}

TEST_F(BackMatchingTest, StopsOnceNBBackMatchesAreFound) {
  const uint32_t a = Cluster(4), b = Cluster(0), c = Cluster(8);
  std::vector<uint32_t> views;
  for (const uint32_t cluster : {a, b, c}) {
    for (const uint32_t v : ViewsOf(cluster, 6)) views.push_back(v);
  }
  std::vector<FeatureMatch> copies;
  const Query query = QueryOf(views, &copies);
  LocalizerOptions options = Options(query);
  const auto forward = Votes({{a, 5}, {b, 4}, {c, 3}});
  // N_B is checked before each cluster, so the cluster that reaches it is back-matched whole.
  options.back_matches = 6;
  ExpectVisited(Run(query, forward, options).visited, {{a, 5, 6}});
  options.back_matches = 7;
  BackMatchingResult result = Run(query, forward, options);
  ExpectVisited(result.visited, {{a, 5, 6}, {b, 4, 6}});
  ExpectMatches(result.matches, CopiesOf(copies, {a, b}, *index_));
  options.back_matches = 13;
  ExpectVisited(Run(query, forward, options).visited, {{a, 5, 6}, {b, 4, 6}, {c, 3, 6}});
}

TEST_F(BackMatchingTest, OnlyClustersWithMinMatchesToVoteCastCovisibilityVotes) {
  EXPECT_EQ(LocalizerOptions().min_matches_to_vote, 12u);
  // Cluster a back-matches 12 of its views whose points cluster b also sees. One of the points
  // is seen twice by b, which still gets one vote for it; the others have the shortest tracks,
  // so that every other cluster sees fewer of the 12 points than b.
  auto other_clusters = [&](uint32_t a, uint32_t view) {  // one per view of the track
    std::vector<uint32_t> clusters;
    for (const uint32_t other : index_->TrackOf(PointOf(view))) {
      if (ClusterOf(other) != a) clusters.push_back(ClusterOf(other));
    }
    return clusters;
  };
  auto votes_of = [&](uint32_t a, const std::vector<uint32_t>& views) {
    std::vector<uint32_t> votes(clusters_->num_clusters(), 0);
    for (const uint32_t view : views) {
      const std::vector<uint32_t> clusters = other_clusters(a, view);
      for (const uint32_t cluster : std::set<uint32_t>(clusters.begin(), clusters.end())) {
        ++votes[cluster];
      }
    }
    return votes;
  };
  // Tries each point seen twice in one image b, with a another image seeing it.
  uint32_t a = UINT32_MAX, b = UINT32_MAX;
  std::vector<uint32_t> views, expected_votes;
  for (uint32_t point = 0; point < index_->points().size() && views.empty(); ++point) {
    const std::span<const uint32_t> track = index_->TrackOf(point);
    auto views_in = [&](uint32_t cluster) {
      return std::count_if(track.begin(), track.end(),
                           [&](uint32_t v) { return ClusterOf(v) == cluster; });
    };
    const auto twice = std::find_if(track.begin(), track.end(),
                                    [&](uint32_t v) { return views_in(ClusterOf(v)) == 2; });
    if (twice == track.end()) continue;
    const auto once = std::find_if(track.begin(), track.end(),
                                   [&](uint32_t v) { return views_in(ClusterOf(v)) == 1; });
    if (once == track.end()) continue;
    const uint32_t try_a = ClusterOf(*once), try_b = ClusterOf(*twice);
    std::vector<uint32_t> candidates;
    const IndexImage& image = ImageOfCluster(try_a);
    for (uint32_t view = image.first_view; view < image.first_view + image.num_views; ++view) {
      const std::vector<uint32_t> clusters = other_clusters(try_a, view);
      if (view != *once && std::count(clusters.begin(), clusters.end(), try_b) == 1) {
        candidates.push_back(view);
      }
    }
    if (candidates.size() < 11) continue;
    std::stable_sort(candidates.begin(), candidates.end(), [&](uint32_t u, uint32_t v) {
      return index_->TrackOf(PointOf(u)).size() < index_->TrackOf(PointOf(v)).size();
    });
    candidates.resize(11);
    candidates.insert(candidates.begin(), *once);
    const std::vector<uint32_t> votes = votes_of(try_a, candidates);
    // b leads by two, so that it still leads when a votes with 11 matches.
    if (std::count_if(votes.begin(), votes.end(), [](uint32_t v) { return v >= 11; }) == 1) {
      std::tie(a, b, views, expected_votes) = std::tuple(try_a, try_b, candidates, votes);
    }
  }
  ASSERT_EQ(views.size(), 12u) << "no point is seen twice by one cluster and by another";
  ASSERT_EQ(expected_votes[b], 12u);
  expected_votes[a] = 1;  // its forward vote

  const auto forward = Votes({{a, 1}});
  std::vector<FeatureMatch> copies;
  Query query = QueryOf(views, &copies);
  LocalizerOptions options = Options(query);
  options.max_back_clusters = 2;
  BackMatchingResult result = Run(query, forward, options);
  // b had no forward vote; it is visited second with a's 12 votes (and finds nothing).
  ExpectVisited(result.visited, {{a, 1, 12}, {b, 12, 0}});
  ExpectMatches(result.matches, copies);
  EXPECT_EQ(result.cluster_votes, expected_votes);

  // With 11 back-matches a does not vote: nothing else is visited.
  views.pop_back();
  copies.clear();
  query = QueryOf(views, &copies);
  options = Options(query);
  options.max_back_clusters = 2;
  result = Run(query, forward, options);
  ExpectVisited(result.visited, {{a, 1, 11}});
  std::vector<uint32_t> forward_votes(clusters_->num_clusters(), 0);
  forward_votes[a] = 1;
  EXPECT_EQ(result.cluster_votes, forward_votes);
  // ... unless the threshold is lowered to 11.
  options.min_matches_to_vote = 11;
  result = Run(query, forward, options);
  ASSERT_EQ(result.visited.size(), 2u);
  EXPECT_EQ(result.visited[1].cluster, b);
  EXPECT_EQ(result.visited[1].votes, 11u);
}

class UniqueCorrespondencesTest : public test::MatchingFixture {};

TEST_F(UniqueCorrespondencesTest, KeepsTheNearestViewOfEachFeature) {
  const uint32_t out_of_range = static_cast<uint32_t>(index_->num_views());
  const std::vector<FeatureMatch> unique =
      UniqueCorrespondences(*index_, {
                                         {3, 10, 5.0f},
                                         {1, 40, 7.0f},
                                         {3, 11, 2.0f},
                                         {3, 12, 9.0f},
                                         {2, out_of_range, 1.0f},
                                         {5, out_of_range + 9, 0.5f},
                                         {5, 13, 4.0f},
                                         {5, 14, 6.0f},
                                     });
  // Sorted by feature; an out-of-range view is dropped and does not hide a valid one.
  ExpectMatches(unique, {{1, 40, 7.0f}, {3, 11, 2.0f}, {5, 13, 4.0f}});
}

}  // namespace
}  // namespace cwloc
