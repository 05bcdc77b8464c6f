#include "kdtree/kd_forest.h"

#include <algorithm>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/prefetch.h"

namespace cwloc {
namespace {

constexpr uint32_t kEmptySlot = std::numeric_limits<uint32_t>::max();
// Row indices must stay below this so that the visited set can use it as its empty marker.
constexpr uint64_t kMaxDescriptors = std::numeric_limits<uint32_t>::max() - 1;

std::string NodeName(size_t tree, size_t node) {
  return "kd-forest tree " + std::to_string(tree) + " node " + std::to_string(node);
}

}  // namespace

namespace {

// The arrays' sizes agree, and the trees' roots are in order within the nodes: "" or what is
// wrong.
std::string ShapeError(const KdForestView& forest) {
  if (forest.descriptors.size() % kDescriptorDim != 0) {
    return "kd-forest descriptors: " + std::to_string(forest.descriptors.size()) +
           " bytes is not a multiple of 128";
  }
  if (!forest.codes.empty() && (!IsValidCodeBytes(forest.codes.code_bytes) ||
                                forest.codes.codebook.size() != DescriptorCodes::kCodebookBytes ||
                                forest.codes.codes.size() % forest.codes.code_bytes != 0)) {
    return "kd-forest codes: " + std::to_string(forest.codes.code_bytes) + "-byte codes over " +
           std::to_string(forest.codes.codes.size()) + " bytes with a " +
           std::to_string(forest.codes.codebook.size()) + "-byte codebook";
  }
  const uint64_t n = forest.NumDescriptors();
  if (n > kMaxDescriptors) return "kd-forest: too many descriptors (" + std::to_string(n) + ")";
  const size_t num_trees = forest.roots.size();
  const size_t num_nodes = forest.nodes.size();
  if (num_trees == 0) {
    if (num_nodes != 0 || !forest.leaves.empty()) {
      return "kd-forest: no trees but " + std::to_string(num_nodes) + " nodes and " +
             std::to_string(forest.leaves.size()) + " leaf entries";
    }
    return "";
  }
  if (num_nodes > std::numeric_limits<uint32_t>::max()) {
    return "kd-forest: too many nodes (" + std::to_string(num_nodes) + ")";
  }
  if (forest.leaves.size() != num_trees * n) {
    return "kd-forest leaves: " + std::to_string(forest.leaves.size()) + " entries, expected " +
           std::to_string(num_trees) + " trees x " + std::to_string(n) + " descriptors";
  }
  if (forest.roots[0] != 0) {
    return "kd-forest roots[0] = " + std::to_string(forest.roots[0]) + ", expected 0";
  }
  for (size_t t = 0; t < num_trees; ++t) {
    const uint64_t end = t + 1 < num_trees ? forest.roots[t + 1] : num_nodes;
    if (forest.roots[t] >= end || end > num_nodes) {
      return "kd-forest roots[" + std::to_string(t) + "] = " + std::to_string(forest.roots[t]) +
             ": trees must be non-empty, in order and within the " + std::to_string(num_nodes) +
             " nodes";
    }
  }
  return "";
}

// Leaf `node` of tree t holds the bucket that starts at leaves[next_slot], within the tree's
// slice, of descriptors not `seen` in the tree before (marked now): "" or what is wrong.
std::string BucketError(const KdForestView& forest, size_t t, uint32_t node, uint64_t next_slot,
                        std::vector<uint64_t>* seen) {
  const uint64_t n = forest.NumDescriptors();
  const KdNode& leaf = forest.nodes[node];
  if (leaf.high != 0) return NodeName(t, node) + ": leaf with a nonzero high byte";
  if (leaf.index != next_slot) {
    return NodeName(t, node) + ": leaf bucket starts at " + std::to_string(leaf.index) +
           ", expected " + std::to_string(next_slot) + " (buckets must tile the leaves)";
  }
  const uint64_t bucket_end = next_slot + leaf.low;
  if (bucket_end > (t + 1) * n) {
    return NodeName(t, node) + ": leaf bucket [" + std::to_string(next_slot) + ", " +
           std::to_string(bucket_end) + ") runs past the tree's leaves, which end at " +
           std::to_string((t + 1) * n);
  }
  for (uint64_t s = next_slot; s < bucket_end; ++s) {
    const uint32_t v = forest.leaves[s];
    if (v >= n) {
      return "kd-forest leaves[" + std::to_string(s) + "] = " + std::to_string(v) +
             " is not a descriptor index (N = " + std::to_string(n) + ")";
    }
    if ((*seen)[v / 64] >> (v % 64) & 1) {
      return "kd-forest leaves[" + std::to_string(s) + "]: descriptor " + std::to_string(v) +
             " appears twice in tree " + std::to_string(t);
    }
    (*seen)[v / 64] |= uint64_t(1) << (v % 64);
  }
  return "";
}

// Tree t's nodes, its leaves' buckets tiling its slice of `leaves` in order: "" or what is
// wrong. `seen` is scratch of a bit per descriptor.
std::string TreeError(const KdForestView& forest, size_t t, std::vector<uint64_t>* seen) {
  const uint64_t n = forest.NumDescriptors();
  const size_t num_trees = forest.roots.size();
  // Each subtree must be exactly a contiguous preorder range [node, end): the node itself, its
  // left subtree [node + 1, right), its right subtree [right, end). Ranges shrink strictly, so
  // this walk visits every node once and proves there is no sharing and no cycle.
  struct Range {
    uint32_t node;
    uint32_t end;
  };
  const uint32_t tree_end = t + 1 < num_trees ? forest.roots[t + 1] : uint32_t(forest.nodes.size());
  uint64_t next_slot = t * n;  // buckets must tile this tree's slice of `leaves` in order
  std::fill(seen->begin(), seen->end(), 0);
  std::vector<Range> stack(1, Range{forest.roots[t], tree_end});
  while (!stack.empty()) {
    const Range r = stack.back();
    stack.pop_back();
    const KdNode& node = forest.nodes[r.node];
    if (node.reserved != 0) return NodeName(t, r.node) + ": reserved byte is not zero";
    if (node.dim == kKdLeaf) {
      if (r.end != r.node + 1) {
        return NodeName(t, r.node) + ": a leaf where a subtree of " +
               std::to_string(r.end - r.node) + " nodes should be";
      }
      std::string error = BucketError(forest, t, r.node, next_slot, seen);
      if (!error.empty()) return error;
      next_slot += node.low;
      continue;
    }
    if (node.dim >= kDescriptorDim) {
      return NodeName(t, r.node) + ": split dimension " + std::to_string(node.dim) +
             " is not < 128 (nor the leaf marker 255)";
    }
    if (node.low > node.high) {
      return NodeName(t, r.node) + ": split bounds low " + std::to_string(node.low) + " > high " +
             std::to_string(node.high);
    }
    if (node.index <= r.node + 1 || node.index >= r.end) {
      return NodeName(t, r.node) + ": right child " + std::to_string(node.index) +
             " is not inside (" + std::to_string(r.node + 1) + ", " + std::to_string(r.end) +
             "), the node's subtree after its left child";
    }
    stack.push_back(Range{node.index, r.end});
    stack.push_back(Range{r.node + 1, node.index});
  }
  if (next_slot != (t + 1) * n) {
    return "kd-forest tree " + std::to_string(t) + ": leaf buckets cover " +
           std::to_string(next_slot - t * n) + " of " + std::to_string(n) + " descriptors";
  }
  return "";
}

}  // namespace

bool ValidateKdForest(const KdForestView& forest, std::string* error) {
  std::string message = ShapeError(forest);
  if (message.empty() && !forest.roots.empty()) {
    std::vector<uint64_t> seen((forest.NumDescriptors() + 63) / 64);
    for (size_t t = 0; message.empty() && t < forest.roots.size(); ++t) {
      message = TreeError(forest, t, &seen);
    }
  }
  if (message.empty()) return true;
  if (error) *error = std::move(message);
  return false;
}

KdForestSearcher::KdForestSearcher(const KdForestView& forest, const DistanceFunctions& distance)
    : forest_(forest),
      distance_(&distance),
      num_descriptors_(uint32_t(std::min<uint64_t>(forest.NumDescriptors(), kMaxDescriptors))),
      states_(1) {
  states_[0].heap.reserve(4096);
  states_[0].cursor_rows.resize(size_t(kMaxInterleave) * 256);
  if (!forest.codes.empty()) {
    decoded_.resize(size_t{256} * kDescriptorDim);
    for (uint32_t i = 0; i < 256; ++i) decoded_rows_[i] = i;
  }
}

KdSearchResult KdForestSearcher::Search(const uint8_t* query, const KdSearchOptions& options,
                                        std::span<KdNeighbor> out) {
  if (options.skip_range_checks) return SearchImpl<false>(query, options, out);
  return SearchImpl<true>(query, options, out);
}

void KdForestSearcher::SearchBatch(std::span<const uint8_t* const> queries,
                                   const KdSearchOptions& options,
                                   std::span<const std::span<KdNeighbor>> outs,
                                   std::span<KdSearchResult> results, uint32_t width) {
  if (outs.size() != queries.size() || results.size() != queries.size()) {
    throw std::invalid_argument("KdForestSearcher::SearchBatch: " + std::to_string(queries.size()) +
                                " queries but " + std::to_string(outs.size()) + " outputs and " +
                                std::to_string(results.size()) + " results");
  }
  if (options.skip_range_checks)
    return SearchBatchImpl<false>(queries, options, outs, results, width);
  SearchBatchImpl<true>(queries, options, outs, results, width);
}

void KdForestSearcher::State::ResetVisited(size_t expected) {
  // Power-of-two table at most half full; multiplicative hashing spreads sequential indices.
  uint32_t log2 = 6;
  while ((size_t(1) << log2) < 2 * expected && log2 < 31) ++log2;
  const size_t capacity = size_t(1) << log2;
  if (visited.size() < capacity) visited.resize(capacity);
  std::fill(visited.begin(), visited.begin() + capacity, kEmptySlot);
  visited_shift = 32 - log2;
  visited_count = 0;
  visited_limit = capacity / 2;
}

inline bool KdForestSearcher::State::InsertVisited(uint32_t index) {
  const uint32_t mask = (uint32_t(1) << (32 - visited_shift)) - 1;
  uint32_t slot = (index * 0x9E3779B1u) >> visited_shift;
  for (;;) {
    const uint32_t value = visited[slot];
    if (value == index) return false;
    if (value == kEmptySlot) break;
    slot = (slot + 1) & mask;
  }
  visited[slot] = index;
  if (++visited_count > visited_limit) {
    // More compared than expected (an exhaustive or unfillable search): grow and rehash.
    std::vector<uint32_t> old(visited.begin(), visited.begin() + (size_t(mask) + 1));
    ResetVisited(2 * visited_limit);
    for (uint32_t v : old) {
      if (v != kEmptySlot) InsertVisited(v);
    }
  }
  return true;
}

void KdForestSearcher::State::AddCandidate(uint32_t index, uint32_t distance) {
  uint32_t i;
  if (num_results < k) {
    i = num_results++;
  } else {
    const KdNeighbor& worst = result[k - 1];
    if (distance > worst.distance || (distance == worst.distance && index > worst.index)) return;
    i = k - 1;
  }
  while (i > 0 && (result[i - 1].distance > distance ||
                   (result[i - 1].distance == distance && result[i - 1].index > index))) {
    result[i] = result[i - 1];
    --i;
  }
  result[i] = KdNeighbor{index, distance};
}

// The search keeps up to `interleave` descents in flight and advances them round-robin, one
// memory access each: a kd descent is a chain of dependent cache misses (node, node, ..., leaf
// bucket, descriptor rows), so while one waits for its prefetched line the others work. With
// interleave = 1 this is exactly FLANN's order (pop the best branch, descend it to a leaf);
// with more, the few best branches are descended together. A search's order depends only on
// its own state, so taking turns with other searches (SearchBatch) cannot change its result.

template <bool kChecked>
bool KdForestSearcher::StepNode(State& s, Cursor& c) {
  const KdNode* nodes = forest_.nodes.data();
  const size_t num_nodes = forest_.nodes.size();
  uint32_t node_index = c.node;
  uint32_t bound = c.bound;
  for (;;) {
    if constexpr (kChecked) {
      // A tree visits each node once per search; more steps means shared subtrees.
      if (s.steps_left == 0) return false;
      --s.steps_left;
    }
    const KdNode node = nodes[node_index];
    if (node.dim >= kDescriptorDim) {
      if constexpr (kChecked) {
        if (node.dim != kKdLeaf) return false;
      }
      if (s.BudgetSpent()) {
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
    const uint32_t q = s.query[node.dim];
    const uint32_t gap_left = q > node.low ? q - node.low : 0;
    const uint32_t gap_right = q < node.high ? node.high - q : 0;
    uint32_t best, other, best_gap, other_gap;
    if (gap_left <= gap_right) {
      best = node_index + 1, other = node.index, best_gap = gap_left, other_gap = gap_right;
    } else {
      best = node.index, other = node_index + 1, best_gap = gap_right, other_gap = gap_left;
    }
    const uint32_t worst = s.WorstDistance();
    const uint32_t other_bound =
        uint32_t(std::min<uint64_t>(uint64_t(bound) + other_gap * other_gap, kEmptySlot));
    if (!s.prune || other_bound <= worst) {
      s.heap.push_back(uint64_t(other_bound) << 32 | other);
      std::push_heap(s.heap.begin(), s.heap.end(), std::greater<uint64_t>());
    }
    bound = uint32_t(std::min<uint64_t>(uint64_t(bound) + best_gap * best_gap, kEmptySlot));
    if (s.prune && bound > worst) {
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
bool KdForestSearcher::StepBucket(State& s, Cursor& c, uint32_t* rows) {
  const uint32_t* bucket = forest_.leaves.data() + c.node;
  const uint8_t* descriptors = forest_.descriptors.data();
  uint32_t num_rows = 0;
  for (uint32_t i = 0; i < c.count; ++i) {
    const uint32_t row = bucket[i];
    if constexpr (kChecked) {
      if (row >= num_descriptors_) return false;
    }
    if (!s.InsertVisited(row)) continue;
    if (!s.allowed.empty() &&
        (size_t{row} / 64 >= s.allowed.size() || ((s.allowed[row / 64] >> (row % 64)) & 1) == 0)) {
      ++s.checks;  // walked past, not compared
      continue;
    }
    if (forest_.codes.empty()) {
      const uint8_t* p = descriptors + size_t(row) * kDescriptorDim;
      Prefetch(p);
      Prefetch(p + 64);
    } else {
      Prefetch(forest_.codes.Code(row));
    }
    rows[num_rows++] = row;
  }
  c.count = num_rows;
  c.stage = num_rows > 0 ? Cursor::kRows : Cursor::kIdle;
  return true;
}

void KdForestSearcher::StepRows(State& s, Cursor& c, const uint32_t* rows) {
  if (forest_.codes.empty()) {
    distance_->batch(s.query, forest_.descriptors.data(), rows, c.count, leaf_distances_);
  } else {
    for (uint32_t i = 0; i < c.count; ++i)
      forest_.codes.Decode(rows[i], decoded_.data() + size_t{i} * kDescriptorDim);
    distance_->batch(s.query, decoded_.data(), decoded_rows_, c.count, leaf_distances_);
  }
  for (uint32_t i = 0; i < c.count; ++i) {
    if (s.BudgetSpent()) break;
    ++s.checks;
    s.AddCandidate(rows[i], leaf_distances_[i]);
  }
  c.stage = Cursor::kIdle;
}

template <bool kChecked>
bool KdForestSearcher::Start(State& s, const uint8_t* query, const KdSearchOptions& options,
                             std::span<KdNeighbor> out) {
  s.query = query;
  s.result = out.data();
  s.k = uint32_t(std::min<size_t>(out.size(), num_descriptors_));
  s.num_results = 0;
  s.checks = 0;
  s.max_checks = options.max_checks;
  s.allowed = options.allowed_rows;
  s.ok = true;
  if (s.k == 0 || forest_.roots.empty()) return false;
  s.prune = s.max_checks < num_descriptors_;
  s.steps_left = forest_.nodes.size();
  s.heap.clear();
  // A few leaves in flight may be marked beyond the budget; a bigger overshoot just grows it.
  s.ResetVisited(std::min<size_t>(num_descriptors_, size_t(s.max_checks) + 64));

  s.num_cursors = std::clamp<uint32_t>(options.interleave, 1, kMaxInterleave);
  if (s.cursor_rows.size() < size_t(s.num_cursors) * 256) {
    s.cursor_rows.resize(size_t(s.num_cursors) * 256);
  }
  // Roots start with bound 0: the first ones as descents, the rest queued.
  for (size_t t = 0; t < forest_.roots.size(); ++t) {
    const uint32_t root = forest_.roots[t];
    if (kChecked && root >= forest_.nodes.size()) {
      s.ok = false;
      return false;
    }
    if (t < s.num_cursors) {
      Prefetch(forest_.nodes.data() + root);
      s.cursors[t] = Cursor{root, 0, 0, Cursor::kNode};
    } else {
      s.heap.push_back(root);
      std::push_heap(s.heap.begin(), s.heap.end(), std::greater<uint64_t>());
    }
  }
  for (uint32_t i = uint32_t(forest_.roots.size()); i < s.num_cursors; ++i) {
    s.cursors[i] = Cursor{};
  }
  return true;
}

template <bool kChecked>
inline bool KdForestSearcher::Round(State& s) {
  bool busy = false;
  for (uint32_t i = 0; i < s.num_cursors; ++i) {
    Cursor& c = s.cursors[i];
    uint32_t* rows = s.cursor_rows.data() + size_t(i) * 256;
    switch (c.stage) {
      case Cursor::kIdle: {
        if (s.heap.empty() || s.BudgetSpent()) break;
        std::pop_heap(s.heap.begin(), s.heap.end(), std::greater<uint64_t>());
        const uint64_t branch = s.heap.back();
        s.heap.pop_back();
        const uint32_t bound = uint32_t(branch >> 32);
        if (s.prune && bound > s.WorstDistance()) {
          // Branches come out in order of their bound: all the queued ones are too far.
          s.heap.clear();
          break;
        }
        Prefetch(forest_.nodes.data() + uint32_t(branch));
        c = Cursor{uint32_t(branch), bound, 0, Cursor::kNode};
        busy = true;
        break;
      }
      case Cursor::kNode:
        if (!StepNode<kChecked>(s, c)) return s.ok = false;
        busy = true;
        break;
      case Cursor::kBucket:
        if (!StepBucket<kChecked>(s, c, rows)) return s.ok = false;
        busy = true;
        break;
      case Cursor::kRows:
        StepRows(s, c, rows);
        busy = true;
        break;
    }
  }
  // FLANN's stopping rule: the budget is spent and k neighbours are known. Descents still in
  // flight are dropped.
  return busy && !s.BudgetSpent();
}

KdSearchResult KdForestSearcher::Finish(const State& s) {
  KdSearchResult result;
  result.checks = s.checks;
  if (!s.ok) {
    result.corrupt = true;
    return result;
  }
  result.num_neighbors = s.num_results;
  return result;
}

template <bool kChecked>
KdSearchResult KdForestSearcher::SearchImpl(const uint8_t* query, const KdSearchOptions& options,
                                            std::span<KdNeighbor> out) {
  State& s = states_[0];
  if (Start<kChecked>(s, query, options, out)) {
    while (Round<kChecked>(s)) {
    }
  }
  return Finish(s);
}

template <bool kChecked>
void KdForestSearcher::SearchBatchImpl(std::span<const uint8_t* const> queries,
                                       const KdSearchOptions& options,
                                       std::span<const std::span<KdNeighbor>> outs,
                                       std::span<KdSearchResult> results, uint32_t width) {
  width = std::clamp<uint32_t>(width, 1, kMaxBatchWidth);
  width = uint32_t(std::min<size_t>(width, queries.size()));
  if (states_.size() < width) states_.resize(width);
  // live[0, active): the states with a search in flight; query[slot]: whose search.
  uint32_t live[kMaxBatchWidth];
  size_t query[kMaxBatchWidth];
  uint32_t active = 0;
  size_t next = 0;
  // Starts the next query that needs any stepping in `slot`; false when none is left.
  const auto start = [&](uint32_t slot) {
    while (next < queries.size()) {
      const size_t q = next++;
      if (Start<kChecked>(states_[slot], queries[q], options, outs[q])) {
        query[slot] = q;
        return true;
      }
      results[q] = Finish(states_[slot]);
    }
    return false;
  };
  for (uint32_t slot = 0; slot < width; ++slot) {
    if (start(slot)) live[active++] = slot;
  }
  while (active > 0) {
    for (uint32_t j = 0; j < active;) {
      const uint32_t slot = live[j];
      if (Round<kChecked>(states_[slot])) {
        ++j;
        continue;
      }
      results[query[slot]] = Finish(states_[slot]);
      if (start(slot)) {
        ++j;
      } else {
        live[j] = live[--active];
      }
    }
  }
}

template KdSearchResult KdForestSearcher::SearchImpl<true>(const uint8_t*, const KdSearchOptions&,
                                                           std::span<KdNeighbor>);
template KdSearchResult KdForestSearcher::SearchImpl<false>(const uint8_t*, const KdSearchOptions&,
                                                            std::span<KdNeighbor>);

}  // namespace cwloc
