#include <gtest/gtest.h>

#include <vector>

#include "kdtree/kd_forest.h"
#include "kdtree/kd_forest_builder.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// The search result must depend on the forest's contents only, never on where its arrays
// live: the per-query forest is a heap vector whose address changes from call to call.
TEST(KdForestDeterminism, ResultsDoNotDependOnTheArraysAddresses) {
  const size_t n = 3000;
  std::vector<uint8_t> descriptors(n * 128);
  for (auto& value : descriptors) value = static_cast<uint8_t>(test::Rng()() % 40);
  const KdForest forest = BuildKdForest(descriptors, KdForestBuildOptions{});

  // Copies of the node array at every 8-byte offset within a cache line.
  std::vector<std::vector<KdNeighbor>> results;
  for (size_t shift = 0; shift < 8; ++shift) {
    std::vector<KdNode> shifted(forest.nodes.size() + shift);
    std::copy(forest.nodes.begin(), forest.nodes.end(), shifted.begin() + shift);
    KdForestView view = forest.View(descriptors);
    view.nodes = std::span<const KdNode>(shifted).subspan(shift);
    KdForestSearcher searcher(view);
    std::vector<KdNeighbor> all;
    std::vector<KdNeighbor> neighbors(6);
    KdSearchOptions options;
    options.max_checks = 48;
    for (size_t q = 0; q < 300; ++q) {
      searcher.Search(descriptors.data() + q * 7 % n * 128, options, neighbors);
      all.insert(all.end(), neighbors.begin(), neighbors.end());
    }
    results.push_back(all);
  }
  for (size_t shift = 1; shift < results.size(); ++shift)
    EXPECT_EQ(results[shift], results[0]) << "shift " << shift;
}

}  // namespace
}  // namespace cwloc
