#pragma once

// Builds the flat randomized kd-forest of format/kd_forest.h (FLANN's KDTreeIndex recipe:
// split on a dimension drawn at random among the 5 of highest variance, at the mean).

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "kdtree/kd_forest.h"

namespace cwloc {

// The most trees a forest has, and descriptors a leaf holds (a leaf's count is a byte, whose
// largest value kKdLeaf marks a leaf). BuildKdForest refuses options beyond them.
inline constexpr uint32_t kMaxKdTrees = 64;
inline constexpr uint32_t kMaxKdLeafSize = kKdLeaf - 1;

struct KdForestBuildOptions {
  uint32_t num_trees = 4;  // 1..kMaxKdTrees
  // Nodes with at most this many descriptors become leaves (1..kMaxKdLeafSize). Buckets of 8
  // make a leaf visit one cache line of indices and cut the node count 8x against FLANN's 1.
  uint32_t max_leaf_size = 8;
  // The output is a function of (descriptors, num_trees, max_leaf_size, seed) only.
  uint64_t seed = 0;
  // Worker threads; 0 = std::thread::hardware_concurrency().
  uint32_t num_threads = 0;
  // Called with the fraction done (0..1], never concurrently, from any thread.
  std::function<void(double)> progress;
};

// Owns the arrays; View() borrows them for search or for writing to the index file.
struct KdForest {
  std::vector<KdNode> nodes;
  std::vector<uint32_t> roots;
  std::vector<uint32_t> leaves;

  KdForestView View(std::span<const uint8_t> descriptors) const {
    return KdForestView{nodes, roots, leaves, descriptors};
  }
  size_t MemoryBytes() const {
    return nodes.size() * sizeof(KdNode) + (roots.size() + leaves.size()) * sizeof(uint32_t);
  }
};

// `descriptors` is N x 128 uint8, row-major, N < 2^32 - 1. Throws std::invalid_argument on bad
// options or sizes.
KdForest BuildKdForest(std::span<const uint8_t> descriptors, const KdForestBuildOptions& options);

// The subtree BuildKdForest splits over `rows` (descriptor indices, reordered in place into its
// leaf buckets' order), appended to `nodes` in preorder with absolute child indices; its leaves
// own the slots [slot_base, slot_base + rows.size()). A function of (the rows' descriptors and
// order, max_leaf_size, seed) only: UpdateKdForest splits an overfull leaf with it.
void AppendKdSubtree(std::span<const uint8_t> descriptors, std::span<uint32_t> rows,
                     uint32_t max_leaf_size, uint64_t seed, uint64_t slot_base,
                     std::vector<KdNode>* nodes);

}  // namespace cwloc
