#pragma once

// Updates a kd-forest for a changed set of rows without rebuilding it, as FAISS and HNSW add
// vectors to a trained index: kept rows stay in their leaves (renumbered), removed ones leave,
// and new rows descend the existing splits to a leaf; a leaf that grows past the bucket size is
// split as the build splits (AppendKdSubtree). Used by `cwloc-index update` and `apply`, which
// must give the same bytes: the output is a function of the inputs only.

#include <cstdint>
#include <limits>
#include <span>

#include "kdtree/kd_forest_builder.h"

namespace cwloc {

inline constexpr uint32_t kRemovedRow = std::numeric_limits<uint32_t>::max();

struct KdForestChange {
  // Row r of the parent forest is row parent_to_child[r] of the updated one, or kRemovedRow.
  // Kept rows keep their order (r < s gives parent_to_child[r] < parent_to_child[s]).
  std::span<const uint32_t> parent_to_child;
  // The updated forest's rows that are not the parent's, ascending.
  std::span<const uint32_t> inserted;
};

// The parent forest (a valid one: ValidateKdForest) with `change` applied, over `descriptors`
// (the updated rows, N x 128). A new row goes left of a split when its value is at most `low`,
// right when at least `high`, and between them to the nearer bound, which then moves to it, so
// that the bounds the search prunes with stay exact. Throws std::invalid_argument when the
// change does not fit the forest. Trees are updated in parallel on `num_threads` (0 = all
// cores), which never changes the output.
KdForest UpdateKdForest(const KdForestView& parent, const KdForestChange& change,
                        std::span<const uint8_t> descriptors, uint32_t max_leaf_size, uint64_t seed,
                        int num_threads);

// The same forest when the updated rows are not in one array: `parent_descriptors` are the
// parent forest's rows (N x 128; kept rows are read there), `inserted_descriptors` the inserted
// rows', in the order of `change.inserted`. An update reads the parent index's rows where the
// file maps them, and only those of a leaf it splits.
KdForest UpdateKdForest(const KdForestView& parent, const KdForestChange& change,
                        std::span<const uint8_t> parent_descriptors,
                        std::span<const uint8_t> inserted_descriptors, uint32_t max_leaf_size,
                        uint64_t seed, int num_threads);

}  // namespace cwloc
