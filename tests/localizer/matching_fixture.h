#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <optional>
#include <vector>

#include "base/split_mix64.h"
#include "format/index.h"
#include "kdtree/descriptor_distance.h"
#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/query.h"
#include "tests/localizer/matching_scene.h"
#include "tests/test_util.h"

namespace cwloc::test {

// The index of a random matching scene (tests/localizer/matching_scene.h: one cluster per
// image, random descriptors in [0, 64) per view), drawn from Rng() and opened, with tools to
// build queries whose neighbours are known: copies of model views' descriptors are at distance
// 0 from their view and ~260 from every other one, and random descriptors are about equally far
// from everything. Made in memory: no SQLite, COLMAP readers or indexer, so device builds run
// these tests too.
class MatchingFixture : public testing::Test {
 protected:
  using Descriptor = std::array<uint8_t, 128>;

  void SetUp() override {
    SplitMix64 rng(Rng()());
    const std::filesystem::path path = dir_ / "model.cwl";
    WriteMatchingIndex(RandomMatchingScene(rng), path);
    index_.emplace(Index::Open(path));
    clusters_.emplace(*index_);
    // One cluster per image, so a cluster is an image and its views are known.
    ASSERT_EQ(clusters_->num_clusters(), index_->images().size());
  }

  // Exhaustive kd-forest searches (a budget of N checks is exact), so the neighbours are those
  // of the brute-force NearestViews below.
  LocalizerOptions ExactOptions() const {
    LocalizerOptions options;
    options.checks = static_cast<uint32_t>(index_->num_views());
    return options;
  }

  static Descriptor RandomDescriptor() {
    Descriptor descriptor;
    for (uint8_t& byte : descriptor) byte = static_cast<uint8_t>(Rng()() % 64);
    return descriptor;
  }

  Descriptor ViewDescriptor(uint32_t view) const {
    Descriptor descriptor;
    std::copy_n(index_->ViewDescriptor(view, nullptr), 128, descriptor.begin());
    return descriptor;
  }

  // Appends a feature; returns its index in the query.
  static uint32_t AddFeature(Query* query, const Descriptor& descriptor) {
    query->keypoints.insert(query->keypoints.end(), {10.0f, 20.0f});
    query->descriptors.insert(query->descriptors.end(), descriptor.begin(), descriptor.end());
    return query->NumFeatures() - 1;
  }

  // All views by ascending squared distance to `descriptor` (ties by view): the oracle the
  // tests check their preconditions with.
  std::vector<KdNeighbor> NearestViews(const Descriptor& descriptor) const {
    std::vector<KdNeighbor> all(index_->num_views());
    for (uint32_t view = 0; view < all.size(); ++view) {
      all[view] = {view, SquaredL2(descriptor.data(), index_->ViewDescriptor(view, nullptr))};
    }
    std::sort(all.begin(), all.end(), [](const KdNeighbor& a, const KdNeighbor& b) {
      return a.distance != b.distance ? a.distance < b.distance : a.index < b.index;
    });
    return all;
  }

  uint32_t ClusterOf(uint32_t view) const { return ClusterOfView(*index_, view); }
  uint32_t PointOf(uint32_t view) const { return index_->view_points()[view]; }
  const IndexImage& ImageOfCluster(uint32_t cluster) const {
    return index_->images()[clusters_->images[clusters_->offsets[cluster]]];
  }

  TempDir dir_;  // outlives the index, which maps its file
  std::optional<Index> index_;
  std::optional<ClusterMembers> clusters_;
};

}  // namespace cwloc::test
