#include "kdtree/kd_forest_update.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/huge_pages.h"
#include "base/parallel_for.h"
#include "base/split_mix64.h"

namespace cwloc {
namespace {

// Emits one tree of the updated forest, its inner nodes' right children relative to the tree's
// first node (UpdateKdForest adds the tree's offset).
class TreeUpdater {
 public:
  TreeUpdater(const KdForestView& parent, const KdForestChange& change,
              std::span<const uint8_t> descriptors, uint32_t max_leaf_size, uint64_t seed,
              std::vector<KdNode>* nodes, uint32_t* leaves, uint64_t slot_base)
      : parent_(parent),
        change_(change),
        descriptors_(descriptors),
        max_leaf_(max_leaf_size),
        seed_(seed),
        nodes_(nodes),
        leaves_(leaves),
        slot_base_(slot_base) {}

  // Emits the updated subtree of parent node `node`, with the rows [begin, end) (reordered
  // here) inserted below it.
  void Emit(uint32_t node, uint32_t* begin, uint32_t* end) {
    const KdNode parent_node = parent_.nodes[node];
    if (parent_node.dim == kKdLeaf) {
      EmitLeaf(parent_node, begin, end);
      return;
    }
    KdNode updated = parent_node;
    uint32_t* middle = std::partition(begin, end, [&](uint32_t row) {
      const uint8_t value = descriptors_[size_t(row) * kDescriptorDim + parent_node.dim];
      return value <= parent_node.low ||
             (value < parent_node.high && value - parent_node.low <= parent_node.high - value);
    });
    for (const uint32_t* row = begin; row != end; ++row) {
      const uint8_t value = descriptors_[size_t(*row) * kDescriptorDim + parent_node.dim];
      if (row < middle) {
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
  void EmitLeaf(const KdNode& leaf, uint32_t* begin, uint32_t* end) {
    bucket_.clear();
    for (uint32_t s = leaf.index; s < leaf.index + leaf.low; ++s) {
      const uint32_t row = change_.parent_to_child[parent_.leaves[s]];
      if (row != kRemovedRow) bucket_.push_back(row);
    }
    // Kept rows ascend; with the new ones sorted in, the bucket is in row order, as a build
    // leaves it (and independent of the order the partitions left them in).
    const size_t kept = bucket_.size();
    bucket_.insert(bucket_.end(), begin, end);
    std::sort(bucket_.begin() + kept, bucket_.end());
    std::inplace_merge(bucket_.begin(), bucket_.begin() + kept, bucket_.end());
    const uint64_t slot = slot_base_ + filled_;
    if (bucket_.size() <= max_leaf_) {
      nodes_->push_back(KdNode{uint32_t(slot), kKdLeaf, uint8_t(bucket_.size()), 0, 0});
    } else {
      // Seeded by the bucket's place, so update and apply split it alike.
      AppendKdSubtree(descriptors_, bucket_, max_leaf_, SplitMix64(seed_ ^ slot).Next(), slot,
                      nodes_);
    }
    std::copy(bucket_.begin(), bucket_.end(), leaves_ + filled_);
    filled_ += bucket_.size();
  }

  const KdForestView& parent_;
  const KdForestChange& change_;
  std::span<const uint8_t> descriptors_;
  uint32_t max_leaf_;
  uint64_t seed_;
  std::vector<KdNode>* nodes_;
  uint32_t* leaves_;
  uint64_t slot_base_;
  uint64_t filled_ = 0;
  std::vector<uint32_t> bucket_;
};

}  // namespace

KdForest UpdateKdForest(const KdForestView& parent, const KdForestChange& change,
                        std::span<const uint8_t> descriptors, uint32_t max_leaf_size, uint64_t seed,
                        int num_threads) {
  const size_t n = descriptors.size() / kDescriptorDim;
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
    std::vector<uint32_t> inserted(change.inserted.begin(), change.inserted.end());
    TreeUpdater updater(parent, change, descriptors, max_leaf_size,
                        SplitMix64(seed ^ (t + 1)).Next(), &trees[t], out.leaves.data() + t * n,
                        t * n);
    updater.Emit(parent.roots[t], inserted.data(), inserted.data() + inserted.size());
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

}  // namespace cwloc
