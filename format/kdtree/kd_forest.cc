#include "format/kdtree/kd_forest.h"

#include <algorithm>
#include <functional>
#include <limits>

#include "format/base/prefetch.h"

namespace cwloc {
namespace {

constexpr uint32_t kEmptySlot = std::numeric_limits<uint32_t>::max();
// Row indices must stay below this so that the visited set can use it as its empty marker.
constexpr uint64_t kMaxDescriptors = std::numeric_limits<uint32_t>::max() - 1;

std::string NodeName(size_t tree, size_t node) {
  return "kd-forest tree " + std::to_string(tree) + " node " + std::to_string(node);
}

}  // namespace

bool ValidateKdForest(const KdForestView& forest, std::string* error) {
  auto fail = [error](std::string message) {
    if (error) *error = std::move(message);
    return false;
  };
  if (forest.descriptors.size() % kDescriptorDim != 0) {
    return fail("kd-forest descriptors: " + std::to_string(forest.descriptors.size()) +
                " bytes is not a multiple of 128");
  }
  const uint64_t n = forest.NumDescriptors();
  if (n > kMaxDescriptors)
    return fail("kd-forest: too many descriptors (" + std::to_string(n) + ")");
  const size_t num_trees = forest.roots.size();
  const size_t num_nodes = forest.nodes.size();
  if (num_trees == 0) {
    if (num_nodes != 0 || !forest.leaves.empty()) {
      return fail("kd-forest: no trees but " + std::to_string(num_nodes) + " nodes and " +
                  std::to_string(forest.leaves.size()) + " leaf entries");
    }
    return true;
  }
  if (num_nodes > std::numeric_limits<uint32_t>::max()) {
    return fail("kd-forest: too many nodes (" + std::to_string(num_nodes) + ")");
  }
  if (forest.leaves.size() != num_trees * n) {
    return fail("kd-forest leaves: " + std::to_string(forest.leaves.size()) +
                " entries, expected " + std::to_string(num_trees) + " trees x " +
                std::to_string(n) + " descriptors");
  }
  if (forest.roots[0] != 0) {
    return fail("kd-forest roots[0] = " + std::to_string(forest.roots[0]) + ", expected 0");
  }
  for (size_t t = 0; t < num_trees; ++t) {
    const uint64_t end = t + 1 < num_trees ? forest.roots[t + 1] : num_nodes;
    if (forest.roots[t] >= end || end > num_nodes) {
      return fail("kd-forest roots[" + std::to_string(t) +
                  "] = " + std::to_string(forest.roots[t]) +
                  ": trees must be non-empty, in order and within the " +
                  std::to_string(num_nodes) + " nodes");
    }
  }

  // Each subtree must be exactly a contiguous preorder range [node, end): the node itself, its
  // left subtree [node + 1, right), its right subtree [right, end). Ranges shrink strictly, so
  // this walk visits every node once and proves there is no sharing and no cycle.
  struct Range {
    uint32_t node;
    uint32_t end;
  };
  std::vector<Range> stack;
  std::vector<uint64_t> seen((n + 63) / 64);
  for (size_t t = 0; t < num_trees; ++t) {
    const uint32_t tree_end = t + 1 < num_trees ? forest.roots[t + 1] : uint32_t(num_nodes);
    uint64_t next_slot = t * n;  // buckets must tile this tree's slice of `leaves` in order
    std::fill(seen.begin(), seen.end(), 0);
    stack.assign(1, Range{forest.roots[t], tree_end});
    while (!stack.empty()) {
      const Range r = stack.back();
      stack.pop_back();
      const KdNode& node = forest.nodes[r.node];
      if (node.reserved != 0) return fail(NodeName(t, r.node) + ": reserved byte is not zero");
      if (node.dim == kKdLeaf) {
        if (r.end != r.node + 1) {
          return fail(NodeName(t, r.node) + ": a leaf where a subtree of " +
                      std::to_string(r.end - r.node) + " nodes should be");
        }
        if (node.high != 0) return fail(NodeName(t, r.node) + ": leaf with a nonzero high byte");
        if (node.index != next_slot) {
          return fail(NodeName(t, r.node) + ": leaf bucket starts at " +
                      std::to_string(node.index) + ", expected " + std::to_string(next_slot) +
                      " (buckets must tile the leaves)");
        }
        const uint64_t bucket_end = next_slot + node.low;
        if (bucket_end > (t + 1) * n) {
          return fail(NodeName(t, r.node) + ": leaf bucket [" + std::to_string(next_slot) + ", " +
                      std::to_string(bucket_end) + ") runs past the tree's leaves, which end at " +
                      std::to_string((t + 1) * n));
        }
        for (uint64_t s = next_slot; s < bucket_end; ++s) {
          const uint32_t v = forest.leaves[s];
          if (v >= n) {
            return fail("kd-forest leaves[" + std::to_string(s) + "] = " + std::to_string(v) +
                        " is not a descriptor index (N = " + std::to_string(n) + ")");
          }
          if (seen[v / 64] >> (v % 64) & 1) {
            return fail("kd-forest leaves[" + std::to_string(s) + "]: descriptor " +
                        std::to_string(v) + " appears twice in tree " + std::to_string(t));
          }
          seen[v / 64] |= uint64_t(1) << (v % 64);
        }
        next_slot = bucket_end;
        continue;
      }
      if (node.dim >= kDescriptorDim) {
        return fail(NodeName(t, r.node) + ": split dimension " + std::to_string(node.dim) +
                    " is not < 128 (nor the leaf marker 255)");
      }
      if (node.low > node.high) {
        return fail(NodeName(t, r.node) + ": split bounds low " + std::to_string(node.low) +
                    " > high " + std::to_string(node.high));
      }
      if (node.index <= r.node + 1 || node.index >= r.end) {
        return fail(NodeName(t, r.node) + ": right child " + std::to_string(node.index) +
                    " is not inside (" + std::to_string(r.node + 1) + ", " + std::to_string(r.end) +
                    "), the node's subtree after its left child");
      }
      stack.push_back(Range{node.index, r.end});
      stack.push_back(Range{r.node + 1, node.index});
    }
    if (next_slot != (t + 1) * n) {
      return fail("kd-forest tree " + std::to_string(t) + ": leaf buckets cover " +
                  std::to_string(next_slot - t * n) + " of " + std::to_string(n) + " descriptors");
    }
  }
  return true;
}

KdForestSearcher::KdForestSearcher(const KdForestView& forest, const DistanceFunctions& distance)
    : forest_(forest),
      distance_(&distance),
      num_descriptors_(uint32_t(std::min<uint64_t>(forest.NumDescriptors(), kMaxDescriptors))),
      cursor_rows_(size_t(kMaxInterleave) * 256) {
  heap_.reserve(4096);
}

KdSearchResult KdForestSearcher::Search(const uint8_t* query, const KdSearchOptions& options,
                                        std::span<KdNeighbor> out) {
  if (options.skip_range_checks) return SearchImpl<false>(query, options, out);
  return SearchImpl<true>(query, options, out);
}

uint32_t KdForestSearcher::WorstDistance() const {
  return num_results_ == k_ ? result_[k_ - 1].distance : std::numeric_limits<uint32_t>::max();
}

void KdForestSearcher::ResetVisited(size_t expected) {
  // Power-of-two table at most half full; multiplicative hashing spreads sequential indices.
  uint32_t log2 = 6;
  while ((size_t(1) << log2) < 2 * expected && log2 < 31) ++log2;
  const size_t capacity = size_t(1) << log2;
  if (visited_.size() < capacity) visited_.resize(capacity);
  std::fill(visited_.begin(), visited_.begin() + capacity, kEmptySlot);
  visited_shift_ = 32 - log2;
  visited_count_ = 0;
  visited_limit_ = capacity / 2;
}

inline bool KdForestSearcher::InsertVisited(uint32_t index) {
  const uint32_t mask = (uint32_t(1) << (32 - visited_shift_)) - 1;
  uint32_t slot = (index * 0x9E3779B1u) >> visited_shift_;
  for (;;) {
    const uint32_t value = visited_[slot];
    if (value == index) return false;
    if (value == kEmptySlot) break;
    slot = (slot + 1) & mask;
  }
  visited_[slot] = index;
  if (++visited_count_ > visited_limit_) {
    // More compared than expected (an exhaustive or unfillable search): grow and rehash.
    std::vector<uint32_t> old(visited_.begin(), visited_.begin() + (size_t(mask) + 1));
    ResetVisited(2 * visited_limit_);
    for (uint32_t v : old) {
      if (v != kEmptySlot) InsertVisited(v);
    }
  }
  return true;
}

void KdForestSearcher::AddCandidate(uint32_t index, uint32_t distance) {
  uint32_t i;
  if (num_results_ < k_) {
    i = num_results_++;
  } else {
    const KdNeighbor& worst = result_[k_ - 1];
    if (distance > worst.distance || (distance == worst.distance && index > worst.index)) return;
    i = k_ - 1;
  }
  while (i > 0 && (result_[i - 1].distance > distance ||
                   (result_[i - 1].distance == distance && result_[i - 1].index > index))) {
    result_[i] = result_[i - 1];
    --i;
  }
  result_[i] = KdNeighbor{index, distance};
}

// The search keeps up to `interleave` descents in flight and advances them round-robin, one
// memory access each: a kd descent is a chain of dependent cache misses (node, node, ..., leaf
// bucket, descriptor rows), so while one waits for its prefetched line the others work. With
// interleave = 1 this is exactly FLANN's order (pop the best branch, descend it to a leaf);
// with more, the few best branches are descended together.

template <bool kChecked>
bool KdForestSearcher::StepNode(Cursor& c) {
  const KdNode* nodes = forest_.nodes.data();
  const size_t num_nodes = forest_.nodes.size();
  uint32_t node_index = c.node;
  uint32_t bound = c.bound;
  for (;;) {
    if constexpr (kChecked) {
      // A tree visits each node once per search; more steps means shared subtrees.
      if (steps_left_ == 0) return false;
      --steps_left_;
    }
    const KdNode node = nodes[node_index];
    if (node.dim >= kDescriptorDim) {
      if constexpr (kChecked) {
        if (node.dim != kKdLeaf) return false;
      }
      if (BudgetSpent()) {
        c.stage = Cursor::kIdle;
        return true;
      }
      const uint64_t begin = node.index;
      const uint32_t count = node.low;
      if constexpr (kChecked) {
        if (begin + count > forest_.leaves.size()) return false;
      }
      if (count == 0) {
        c.stage = Cursor::kIdle;
        return true;
      }
      Prefetch(forest_.leaves.data() + begin);
      Prefetch(forest_.leaves.data() + begin + count - 1);
      c.stage = Cursor::kBucket;
      c.node = uint32_t(begin);
      c.count = count;
      return true;
    }
    if constexpr (kChecked) {
      if (node.index <= node_index + 1 || node.index >= num_nodes) return false;
    }
    // Lower bounds of the distance along `dim` to anything on either side: the side with the
    // smaller one is descended now, the other is queued with its gap added (like FLANN, which
    // sums the gaps of all splits crossed).
    const uint32_t q = query_[node.dim];
    const uint32_t gap_left = q > node.low ? q - node.low : 0;
    const uint32_t gap_right = q < node.high ? node.high - q : 0;
    uint32_t best, other, best_gap, other_gap;
    if (gap_left <= gap_right) {
      best = node_index + 1, other = node.index, best_gap = gap_left, other_gap = gap_right;
    } else {
      best = node.index, other = node_index + 1, best_gap = gap_right, other_gap = gap_left;
    }
    const uint32_t worst = WorstDistance();
    const uint32_t other_bound =
        uint32_t(std::min<uint64_t>(uint64_t(bound) + other_gap * other_gap, kEmptySlot));
    if (!prune_ || other_bound <= worst) {
      heap_.push_back(uint64_t(other_bound) << 32 | other);
      std::push_heap(heap_.begin(), heap_.end(), std::greater<uint64_t>());
    }
    bound = uint32_t(std::min<uint64_t>(uint64_t(bound) + best_gap * best_gap, kEmptySlot));
    if (prune_ && bound > worst) {
      c.stage = Cursor::kIdle;
      return true;
    }
    // The left child follows its parent: on the same cache line, keep going; otherwise fetch
    // it and let the other descents run meanwhile. Lines are counted from the array's start
    // (64-byte aligned in the index file), not from its address, so that the order of the
    // descents, and hence the result, never depends on where the array was allocated.
    const bool went_left = best == node_index + 1;
    node_index = best;
    if (went_left && (size_t{best} * sizeof(KdNode)) % 64 != 0) continue;
    Prefetch(nodes + best);
    c.node = best;
    c.bound = bound;
    return true;
  }
}

template <bool kChecked>
bool KdForestSearcher::StepBucket(Cursor& c, uint32_t* rows) {
  const uint32_t* bucket = forest_.leaves.data() + c.node;
  const uint8_t* descriptors = forest_.descriptors.data();
  uint32_t num_rows = 0;
  for (uint32_t i = 0; i < c.count; ++i) {
    const uint32_t row = bucket[i];
    if constexpr (kChecked) {
      if (row >= num_descriptors_) return false;
    }
    if (!InsertVisited(row)) continue;
    if (!allowed_.empty() &&
        (size_t{row} / 64 >= allowed_.size() || ((allowed_[row / 64] >> (row % 64)) & 1) == 0)) {
      ++checks_;  // walked past, not compared
      continue;
    }
    const uint8_t* p = descriptors + size_t(row) * kDescriptorDim;
    Prefetch(p);
    Prefetch(p + 64);
    rows[num_rows++] = row;
  }
  c.count = num_rows;
  c.stage = num_rows > 0 ? Cursor::kRows : Cursor::kIdle;
  return true;
}

void KdForestSearcher::StepRows(Cursor& c, const uint32_t* rows) {
  distance_->batch(query_, forest_.descriptors.data(), rows, c.count, leaf_distances_);
  for (uint32_t i = 0; i < c.count; ++i) {
    if (BudgetSpent()) break;
    ++checks_;
    AddCandidate(rows[i], leaf_distances_[i]);
  }
  c.stage = Cursor::kIdle;
}

template <bool kChecked>
KdSearchResult KdForestSearcher::SearchImpl(const uint8_t* query, const KdSearchOptions& options,
                                            std::span<KdNeighbor> out) {
  KdSearchResult result;
  query_ = query;
  result_ = out.data();
  k_ = uint32_t(std::min<size_t>(out.size(), num_descriptors_));
  num_results_ = 0;
  checks_ = 0;
  max_checks_ = options.max_checks;
  allowed_ = options.allowed_rows;
  if (k_ == 0 || forest_.roots.empty()) return result;
  prune_ = max_checks_ < num_descriptors_;
  steps_left_ = forest_.nodes.size();
  heap_.clear();
  // A few leaves in flight may be marked beyond the budget; a bigger overshoot just grows it.
  ResetVisited(std::min<size_t>(num_descriptors_, size_t(max_checks_) + 64));

  const uint32_t num_cursors = std::clamp<uint32_t>(options.interleave, 1, kMaxInterleave);
  Cursor cursors[kMaxInterleave];
  // Roots start with bound 0: the first ones as descents, the rest queued.
  for (size_t t = 0; t < forest_.roots.size(); ++t) {
    const uint32_t root = forest_.roots[t];
    if (kChecked && root >= forest_.nodes.size()) {
      result.corrupt = true;
      return result;
    }
    if (t < num_cursors) {
      Prefetch(forest_.nodes.data() + root);
      cursors[t] = Cursor{root, 0, 0, Cursor::kNode};
    } else {
      heap_.push_back(root);
      std::push_heap(heap_.begin(), heap_.end(), std::greater<uint64_t>());
    }
  }
  for (uint32_t i = uint32_t(forest_.roots.size()); i < num_cursors; ++i) cursors[i] = Cursor{};

  bool ok = true;
  for (bool busy = true; busy && ok;) {
    busy = false;
    for (uint32_t i = 0; i < num_cursors && ok; ++i) {
      Cursor& c = cursors[i];
      uint32_t* rows = cursor_rows_.data() + size_t(i) * 256;
      switch (c.stage) {
        case Cursor::kIdle: {
          if (heap_.empty() || BudgetSpent()) break;
          std::pop_heap(heap_.begin(), heap_.end(), std::greater<uint64_t>());
          const uint64_t branch = heap_.back();
          heap_.pop_back();
          const uint32_t bound = uint32_t(branch >> 32);
          if (prune_ && bound > WorstDistance()) {
            // Branches come out in order of their bound: all the queued ones are too far.
            heap_.clear();
            break;
          }
          Prefetch(forest_.nodes.data() + uint32_t(branch));
          c = Cursor{uint32_t(branch), bound, 0, Cursor::kNode};
          busy = true;
          break;
        }
        case Cursor::kNode:
          ok = StepNode<kChecked>(c);
          busy = true;
          break;
        case Cursor::kBucket:
          ok = StepBucket<kChecked>(c, rows);
          busy = true;
          break;
        case Cursor::kRows:
          StepRows(c, rows);
          busy = true;
          break;
      }
    }
    // FLANN's stopping rule: the budget is spent and k neighbours are known. Descents still
    // in flight are dropped.
    if (BudgetSpent()) break;
  }
  result.checks = checks_;
  if (!ok) {
    result.corrupt = true;
    return result;
  }
  result.num_neighbors = num_results_;
  return result;
}

template KdSearchResult KdForestSearcher::SearchImpl<true>(const uint8_t*, const KdSearchOptions&,
                                                           std::span<KdNeighbor>);
template KdSearchResult KdForestSearcher::SearchImpl<false>(const uint8_t*, const KdSearchOptions&,
                                                            std::span<KdNeighbor>);

}  // namespace cwloc
