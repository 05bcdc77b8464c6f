// UpdateKdForest: rows removed and inserted into a built forest leave a valid forest in which
// every row is where the search looks first, exhaustive searches stay exact, and the output is
// a function of the inputs (update and apply must agree).
#include "kdtree/kd_forest_update.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "kdtree/descriptor_distance.h"

namespace cwloc {
namespace {

constexpr uint32_t kLeafSize = 8;

std::vector<uint8_t> RandomRows(size_t n, std::mt19937_64& rng, int spread) {
  std::vector<uint8_t> rows(n * kDescriptorDim);
  for (uint8_t& value : rows) value = uint8_t(rng() % spread);
  return rows;
}

struct Change {
  std::vector<uint8_t> child_rows;
  std::vector<uint32_t> parent_to_child, inserted;
};

// Drops every 5th parent row, keeps the rest in order and interleaves new rows: random ones,
// copies of kept rows and rows beyond every split value (255s), which must move the bounds.
Change MakeChange(const std::vector<uint8_t>& parent_rows, std::mt19937_64& rng) {
  Change change;
  const size_t n = parent_rows.size() / kDescriptorDim;
  const std::vector<uint8_t> fresh = RandomRows(n / 2, rng, 64);
  size_t next_fresh = 0;
  auto insert = [&](const uint8_t* row) {
    change.inserted.push_back(uint32_t(change.child_rows.size() / kDescriptorDim));
    change.child_rows.insert(change.child_rows.end(), row, row + kDescriptorDim);
  };
  const std::vector<uint8_t> far(kDescriptorDim, 255);
  for (size_t r = 0; r < n; ++r) {
    const uint8_t* row = &parent_rows[r * kDescriptorDim];
    if (r % 5 == 0) {
      change.parent_to_child.push_back(kRemovedRow);
    } else {
      change.parent_to_child.push_back(uint32_t(change.child_rows.size() / kDescriptorDim));
      change.child_rows.insert(change.child_rows.end(), row, row + kDescriptorDim);
    }
    if (r % 3 == 0 && next_fresh < n / 2) insert(&fresh[kDescriptorDim * next_fresh++]);
    if (r % 97 == 0) insert(row);
    if (r % 499 == 0) insert(far.data());
  }
  return change;
}

TEST(KdForestUpdateTest, EveryRowIsWhereTheSearchLooksAndExhaustiveSearchStaysExact) {
  std::mt19937_64 rng(7);
  const std::vector<uint8_t> parent_rows = RandomRows(4000, rng, 64);
  KdForestBuildOptions options;
  options.max_leaf_size = kLeafSize;
  options.num_threads = 1;
  const KdForest parent = BuildKdForest(parent_rows, options);
  const Change change = MakeChange(parent_rows, rng);
  const KdForest child =
      UpdateKdForest(parent.View(parent_rows), {change.parent_to_child, change.inserted},
                     change.child_rows, kLeafSize, 11, 2);
  const KdForestView view = child.View(change.child_rows);
  std::string error;
  ASSERT_TRUE(ValidateKdForest(view, &error)) << error;
  EXPECT_GT(child.nodes.size(), parent.nodes.size());  // overfull leaves were split

  KdForestSearcher searcher(view);
  KdSearchOptions first_leaf;
  first_leaf.max_checks = kLeafSize;
  first_leaf.interleave = 1;
  std::vector<KdNeighbor> nearest(1);
  const size_t n = change.child_rows.size() / kDescriptorDim;
  for (uint32_t row = 0; row < n; ++row) {
    searcher.Search(&change.child_rows[size_t(row) * kDescriptorDim], first_leaf, nearest);
    ASSERT_EQ(nearest[0].distance, 0u) << "row " << row;
  }

  KdSearchOptions exhaustive;
  exhaustive.max_checks = uint32_t(n);
  const std::vector<uint8_t> queries = RandomRows(20, rng, 64);
  std::vector<KdNeighbor> found(5);
  for (size_t q = 0; q < 20; ++q) {
    const uint8_t* query = &queries[q * kDescriptorDim];
    searcher.Search(query, exhaustive, found);
    std::vector<uint32_t> distances;
    for (size_t r = 0; r < n; ++r)
      distances.push_back(
          BestDistanceFunctions().one(query, &change.child_rows[r * kDescriptorDim]));
    std::sort(distances.begin(), distances.end());
    for (size_t k = 0; k < 5; ++k) EXPECT_EQ(found[k].distance, distances[k]) << q << " " << k;
  }

  const KdForest again =
      UpdateKdForest(parent.View(parent_rows), {change.parent_to_child, change.inserted},
                     change.child_rows, kLeafSize, 11, 1);
  EXPECT_EQ(again.leaves, child.leaves);
  EXPECT_EQ(again.roots, child.roots);
  ASSERT_EQ(again.nodes.size(), child.nodes.size());
  EXPECT_EQ(
      std::memcmp(again.nodes.data(), child.nodes.data(), child.nodes.size() * sizeof(KdNode)), 0);

  // The same forest from the parent's rows and the inserted ones apart, as apply reads them.
  std::vector<uint8_t> inserted_rows;
  for (uint32_t row : change.inserted) {
    const uint8_t* descriptor = &change.child_rows[size_t(row) * kDescriptorDim];
    inserted_rows.insert(inserted_rows.end(), descriptor, descriptor + kDescriptorDim);
  }
  const KdForest apart =
      UpdateKdForest(parent.View(parent_rows), {change.parent_to_child, change.inserted},
                     parent_rows, inserted_rows, kLeafSize, 11, 2);
  EXPECT_EQ(apart.leaves, child.leaves);
  EXPECT_EQ(apart.roots, child.roots);
  ASSERT_EQ(apart.nodes.size(), child.nodes.size());
  EXPECT_EQ(
      std::memcmp(apart.nodes.data(), child.nodes.data(), child.nodes.size() * sizeof(KdNode)), 0);
  EXPECT_THROW(
      UpdateKdForest(parent.View(parent_rows), {change.parent_to_child, change.inserted},
                     parent_rows, std::span(inserted_rows).first(kDescriptorDim), kLeafSize, 11, 2),
      std::invalid_argument);
}

TEST(KdForestUpdateTest, RefusesAChangeThatDoesNotFitTheForest) {
  std::mt19937_64 rng(3);
  const std::vector<uint8_t> rows = RandomRows(100, rng, 64);
  const KdForest forest = BuildKdForest(rows, {});
  std::vector<uint32_t> identity(100);
  for (uint32_t r = 0; r < 100; ++r) identity[r] = r;
  const std::vector<uint32_t> none;
  EXPECT_THROW(
      UpdateKdForest(forest.View(rows), {std::span(identity).first(99), none}, rows, 8, 0, 1),
      std::invalid_argument);
  const std::vector<uint32_t> twice = {5, 5};
  EXPECT_THROW(UpdateKdForest(forest.View(rows), {identity, twice}, rows, 8, 0, 1),
               std::invalid_argument);
}

}  // namespace
}  // namespace cwloc
