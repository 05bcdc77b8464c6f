#include "kdtree/kd_forest_update.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/split_mix64.h"

namespace cwloc {
namespace {

class TreeUpdater {
 public:
  TreeUpdater(const KdForestView& parent, const KdForestChange& change,
              std::span<const uint8_t> descriptors, uint32_t max_leaf_size, uint64_t seed,
              KdForest* out, uint64_t slot_base)
      : parent_(parent),
        change_(change),
        descriptors_(descriptors),
        max_leaf_(max_leaf_size),
        seed_(seed),
        out_(out),
        slot_(slot_base) {}

  // Emits the updated subtree of parent node `node` with `inserted` rows added below it.
  void Emit(uint32_t node, std::vector<uint32_t> inserted) {
    const KdNode parent_node = parent_.nodes[node];
    if (parent_node.dim == kKdLeaf) {
      EmitLeaf(parent_node, std::move(inserted));
      return;
    }
    KdNode updated = parent_node;
    std::vector<uint32_t> left, right;
    for (uint32_t row : inserted) {
      const uint8_t value = descriptors_[size_t(row) * kDescriptorDim + parent_node.dim];
      const bool goes_left =
          value <= parent_node.low ||
          (value < parent_node.high && value - parent_node.low <= parent_node.high - value);
      if (goes_left) {
        left.push_back(row);
        updated.low = std::max(updated.low, value);
      } else {
        right.push_back(row);
        updated.high = std::min(updated.high, value);
      }
    }
    const size_t me = out_->nodes.size();
    out_->nodes.push_back(updated);
    Emit(node + 1, std::move(left));
    out_->nodes[me].index = uint32_t(out_->nodes.size());
    Emit(parent_node.index, std::move(right));
  }

 private:
  void EmitLeaf(const KdNode& leaf, std::vector<uint32_t> inserted) {
    std::vector<uint32_t> rows;
    rows.reserve(leaf.low + inserted.size());
    for (uint32_t s = leaf.index; s < leaf.index + leaf.low; ++s) {
      const uint32_t row = change_.parent_to_child[parent_.leaves[s]];
      if (row != kRemovedRow) rows.push_back(row);
    }
    // Both lists ascend: the bucket stays in row order, as the build leaves it.
    std::vector<uint32_t> merged(rows.size() + inserted.size());
    std::merge(rows.begin(), rows.end(), inserted.begin(), inserted.end(), merged.begin());
    if (merged.size() <= max_leaf_) {
      out_->nodes.push_back(KdNode{uint32_t(slot_), kKdLeaf, uint8_t(merged.size()), 0, 0});
    } else {
      // Seeded by the bucket's place, so update and apply split it alike.
      AppendKdSubtree(descriptors_, merged, max_leaf_, SplitMix64(seed_ ^ slot_).Next(), slot_,
                      &out_->nodes);
    }
    std::copy(merged.begin(), merged.end(), out_->leaves.begin() + slot_);
    slot_ += merged.size();
  }

  const KdForestView& parent_;
  const KdForestChange& change_;
  std::span<const uint8_t> descriptors_;
  uint32_t max_leaf_;
  uint64_t seed_;
  KdForest* out_;
  uint64_t slot_;
};

}  // namespace

KdForest UpdateKdForest(const KdForestView& parent, const KdForestChange& change,
                        std::span<const uint8_t> descriptors, uint32_t max_leaf_size,
                        uint64_t seed) {
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
  out.leaves.resize(parent.roots.size() * n);
  for (size_t t = 0; t < parent.roots.size(); ++t) {
    out.roots.push_back(uint32_t(out.nodes.size()));
    TreeUpdater updater(parent, change, descriptors, max_leaf_size,
                        SplitMix64(seed ^ (t + 1)).Next(), &out, t * n);
    updater.Emit(parent.roots[t], {change.inserted.begin(), change.inserted.end()});
  }
  return out;
}

}  // namespace cwloc
