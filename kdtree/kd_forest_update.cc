#include "kdtree/kd_forest_update.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "base/huge_pages.h"
#include "base/parallel_for.h"
#include "base/split_mix64.h"

namespace cwloc {
namespace {

// Where the updated rows' descriptors are: one array of the updated rows (`updated`), or the
// parent's rows and the inserted ones apart.
struct RowDescriptors {
  const KdForestChange& change;
  std::span<const uint8_t> updated;
  std::span<const uint8_t> parent;
  std::span<const uint8_t> inserted;

  // Parent row `row`, which the change keeps.
  const uint8_t* Kept(uint32_t row) const {
    return updated.empty() ? &parent[size_t(row) * kDescriptorDim]
                           : &updated[size_t(change.parent_to_child[row]) * kDescriptorDim];
  }
  // The `rank`-th inserted row.
  const uint8_t* Inserted(size_t rank) const {
    return updated.empty() ? &inserted[rank * kDescriptorDim]
                           : &updated[size_t(change.inserted[rank]) * kDescriptorDim];
  }
};

// Emits one tree of the updated forest, its inner nodes' right children relative to the tree's
// first node (UpdateKdForest adds the tree's offset).
class TreeUpdater {
 public:
  TreeUpdater(const KdForestView& parent, const KdForestChange& change, const RowDescriptors& rows,
              uint32_t max_leaf_size, uint64_t seed, std::vector<KdNode>* nodes, uint32_t* leaves,
              uint64_t slot_base)
      : parent_(parent),
        change_(change),
        rows_(rows),
        max_leaf_(max_leaf_size),
        seed_(seed),
        nodes_(nodes),
        leaves_(leaves),
        slot_base_(slot_base) {}

  // Emits the updated subtree of parent node `node`, with the inserted rows whose ranks (in
  // change.inserted) are [begin, end) (reordered here) inserted below it.
  void Emit(uint32_t node, uint32_t* begin, uint32_t* end) {
    const KdNode parent_node = parent_.nodes[node];
    if (parent_node.dim == kKdLeaf) {
      EmitLeaf(parent_node, begin, end);
      return;
    }
    KdNode updated = parent_node;
    uint32_t* middle = std::partition(begin, end, [&](uint32_t rank) {
      const uint8_t value = rows_.Inserted(rank)[parent_node.dim];
      return value <= parent_node.low ||
             (value < parent_node.high && value - parent_node.low <= parent_node.high - value);
    });
    for (const uint32_t* rank = begin; rank != end; ++rank) {
      const uint8_t value = rows_.Inserted(*rank)[parent_node.dim];
      if (rank < middle) {
        updated.low = std::max(updated.low, value);
      } else {
        updated.high = std::min(updated.high, value);
      }
    }
    const size_t me = nodes_->size();
    nodes_->push_back(updated);
    Emit(node + 1, begin, middle);
    (*nodes_)[me].index = uint32_t(nodes_->size());
    Emit(parent_node.index, middle, end);
  }

 private:
  // The updated row of the parent's leaf slot `slot`. Slots are read in order and rows at
  // random: the row of a slot further on is fetched meanwhile, so the random reads overlap.
  uint32_t KeptRow(uint32_t slot) const {
    constexpr uint32_t kAhead = 32;
    if (slot + kAhead < parent_.leaves.size())
      __builtin_prefetch(&change_.parent_to_child[parent_.leaves[slot + kAhead]]);
    return change_.parent_to_child[parent_.leaves[slot]];
  }

  void EmitLeaf(const KdNode& leaf, uint32_t* begin, uint32_t* end) {
    const uint64_t slot = slot_base_ + filled_;
    uint32_t* leaves = leaves_ + filled_;
    // Nothing inserted and nothing to split: the kept rows, still in row order.
    if (begin == end && leaf.low <= max_leaf_) {
      size_t kept = 0;
      for (uint32_t s = leaf.index; s < leaf.index + leaf.low; ++s) {
        const uint32_t row = KeptRow(s);
        if (row != kRemovedRow) leaves[kept++] = row;
      }
      nodes_->push_back(KdNode{uint32_t(slot), kKdLeaf, uint8_t(kept), 0, 0});
      filled_ += kept;
      return;
    }
    // The bucket: (updated row, its descriptor).
    bucket_.clear();
    for (uint32_t s = leaf.index; s < leaf.index + leaf.low; ++s) {
      const uint32_t row = KeptRow(s);
      if (row != kRemovedRow) bucket_.push_back({row, rows_.Kept(parent_.leaves[s])});
    }
    // Kept rows ascend, and so do the ranks of inserted ones: with the new ones sorted in, the
    // bucket is in row order, as a build leaves it (whatever order the partitions left).
    const size_t kept = bucket_.size();
    std::sort(begin, end);
    for (const uint32_t* rank = begin; rank != end; ++rank)
      bucket_.push_back({change_.inserted[*rank], rows_.Inserted(*rank)});
    std::inplace_merge(bucket_.begin(), bucket_.begin() + kept, bucket_.end());
    if (bucket_.size() <= max_leaf_) {
      nodes_->push_back(KdNode{uint32_t(slot), kKdLeaf, uint8_t(bucket_.size()), 0, 0});
      for (size_t i = 0; i < bucket_.size(); ++i) leaves[i] = bucket_[i].first;
    } else {
      // Seeded by the bucket's place, so update and apply split it alike. The split sees the
      // bucket as rows 0..n-1 (in row order, as it sees a build's), which it reorders.
      split_descriptors_.resize(bucket_.size() * kDescriptorDim);
      for (size_t i = 0; i < bucket_.size(); ++i) {
        std::copy_n(bucket_[i].second, kDescriptorDim, &split_descriptors_[i * kDescriptorDim]);
        leaves[i] = uint32_t(i);
      }
      AppendKdSubtree(split_descriptors_, {leaves, bucket_.size()}, max_leaf_,
                      SplitMix64(seed_ ^ slot).Next(), slot, nodes_);
      for (size_t i = 0; i < bucket_.size(); ++i) leaves[i] = bucket_[leaves[i]].first;
    }
    filled_ += bucket_.size();
  }

  const KdForestView& parent_;
  const KdForestChange& change_;
  const RowDescriptors& rows_;
  uint32_t max_leaf_;
  uint64_t seed_;
  std::vector<KdNode>* nodes_;
  uint32_t* leaves_;
  uint64_t slot_base_;
  uint64_t filled_ = 0;
  std::vector<std::pair<uint32_t, const uint8_t*>> bucket_;
  std::vector<uint8_t> split_descriptors_;
};

KdForest Update(const KdForestView& parent, const KdForestChange& change, size_t n,
                const RowDescriptors& rows, uint32_t max_leaf_size, uint64_t seed, int num_threads);

}  // namespace

KdForest UpdateKdForest(const KdForestView& parent, const KdForestChange& change,
                        std::span<const uint8_t> descriptors, uint32_t max_leaf_size, uint64_t seed,
                        int num_threads) {
  return Update(parent, change, descriptors.size() / kDescriptorDim, {change, descriptors, {}, {}},
                max_leaf_size, seed, num_threads);
}

KdForest UpdateKdForest(const KdForestView& parent, const KdForestChange& change,
                        std::span<const uint8_t> parent_descriptors,
                        std::span<const uint8_t> inserted_descriptors, uint32_t max_leaf_size,
                        uint64_t seed, int num_threads) {
  if (parent_descriptors.size() != change.parent_to_child.size() * kDescriptorDim ||
      inserted_descriptors.size() != change.inserted.size() * kDescriptorDim) {
    throw std::invalid_argument(
        "UpdateKdForest: the descriptors are not the parent's and the inserted rows'");
  }
  size_t kept = 0;
  for (uint32_t row : change.parent_to_child) kept += row != kRemovedRow;
  return Update(parent, change, kept + change.inserted.size(),
                {change, {}, parent_descriptors, inserted_descriptors}, max_leaf_size, seed,
                num_threads);
}

namespace {

KdForest Update(const KdForestView& parent, const KdForestChange& change, size_t n,
                const RowDescriptors& rows, uint32_t max_leaf_size, uint64_t seed,
                int num_threads) {
  const size_t parent_rows = parent.leaves.size() / std::max<size_t>(parent.roots.size(), 1);
  if (change.parent_to_child.size() != parent_rows) {
    throw std::invalid_argument("UpdateKdForest: " + std::to_string(change.parent_to_child.size()) +
                                " row mappings for a forest of " + std::to_string(parent_rows) +
                                " rows");
  }
  size_t kept = 0;
  for (uint32_t row : change.parent_to_child) {
    if (row == kRemovedRow) continue;
    if (row >= n) throw std::invalid_argument("UpdateKdForest: a kept row is out of range");
    ++kept;
  }
  for (size_t i = 0; i < change.inserted.size(); ++i) {
    if (change.inserted[i] >= n || (i > 0 && change.inserted[i] <= change.inserted[i - 1]))
      throw std::invalid_argument("UpdateKdForest: inserted rows must ascend and be in range");
  }
  if (kept + change.inserted.size() != n) {
    throw std::invalid_argument("UpdateKdForest: " + std::to_string(kept) + " kept and " +
                                std::to_string(change.inserted.size()) + " inserted rows, but " +
                                std::to_string(n) + " descriptors");
  }
  KdForest out;
  const size_t num_trees = parent.roots.size();
  ReserveOnHugePages(&out.leaves, num_trees * n);
  out.leaves.resize(num_trees * n);
  std::vector<std::vector<KdNode>> trees(num_trees);
  ParallelFor(num_trees, num_threads, [&](size_t t, int) {
    std::vector<uint32_t> ranks(change.inserted.size());
    for (uint32_t r = 0; r < ranks.size(); ++r) ranks[r] = r;
    // The parent tree's nodes and at most one split per inserted row: no regrowth copies.
    const size_t tree_end = t + 1 < num_trees ? parent.roots[t + 1] : parent.nodes.size();
    if (tree_end > parent.roots[t]) trees[t].reserve(tree_end - parent.roots[t] + 2 * ranks.size());
    TreeUpdater updater(parent, change, rows, max_leaf_size, SplitMix64(seed ^ (t + 1)).Next(),
                        &trees[t], out.leaves.data() + t * n, t * n);
    updater.Emit(parent.roots[t], ranks.data(), ranks.data() + ranks.size());
  });
  size_t num_nodes = 0;
  for (const std::vector<KdNode>& tree : trees) num_nodes += tree.size();
  ReserveOnHugePages(&out.nodes, num_nodes);
  for (std::vector<KdNode>& tree : trees) {
    const auto base = uint32_t(out.nodes.size());
    out.roots.push_back(base);
    for (KdNode node : tree) {
      if (node.dim != kKdLeaf) node.index += base;
      out.nodes.push_back(node);
    }
    std::vector<KdNode>().swap(tree);
  }
  return out;
}

}  // namespace
}  // namespace cwloc
