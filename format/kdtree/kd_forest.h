#pragma once

// A forest of randomized kd-trees over uint8 SIFT descriptors, stored as flat arrays of
// fixed-width little-endian integers so that it can be searched in place from a read-only
// memory mapping. The search is FLANN's priority search (Muja & Lowe): one best-bin-first
// queue shared by all trees, a budget of distance computations ("checks"), and each
// descriptor compared at most once per query.
//
// Layout (docs/format.md has the byte-level spec; docs/kd_forest.md the design and benchmarks):
//   nodes   KdNode[]  all trees, each in preorder: the left child of an inner node is the next
//                     node, so descending left stays on the same cache line; the right child's
//                     index is stored and is always larger than its parent's.
//   roots   uint32[]  the root node of each tree; tree t owns nodes [roots[t], roots[t+1]).
//   leaves  uint32[]  for each tree, a permutation of the descriptor indices 0..N-1; a leaf
//                     node owns a contiguous bucket of it (at most 255, normally <= 8).
//   descriptors       N x 128 uint8, row-major.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "format/kdtree/descriptor_distance.h"

namespace cwloc {

static_assert(std::endian::native == std::endian::little,
              "the index stores little-endian integers and is read in place");

struct KdNode {
  // Inner node: index of the right child. Leaf: first slot of its bucket in `leaves`.
  uint32_t index;
  // Inner node: split dimension (< 128). Leaf: kKdLeaf.
  uint8_t dim;
  // Inner node: every left descriptor has value <= low in `dim`, every right one >= high
  // (low <= high). Leaf: `low` is the bucket size.
  uint8_t low;
  uint8_t high;
  uint8_t reserved;  // zero
};
static_assert(sizeof(KdNode) == 8);
static_assert(offsetof(KdNode, index) == 0);
static_assert(offsetof(KdNode, dim) == 4);
static_assert(offsetof(KdNode, low) == 5);
static_assert(offsetof(KdNode, high) == 6);
static_assert(offsetof(KdNode, reserved) == 7);

inline constexpr uint8_t kKdLeaf = 0xFF;

// Borrowed views; the arrays usually live in the memory-mapped index file.
struct KdForestView {
  std::span<const KdNode> nodes;
  std::span<const uint32_t> roots;
  std::span<const uint32_t> leaves;
  std::span<const uint8_t> descriptors;  // N x 128

  size_t NumDescriptors() const { return descriptors.size() / kDescriptorDim; }
  size_t NumTrees() const { return roots.size(); }
};

// O(nodes + trees * N) structural check of an untrusted forest: array sizes, every tree is a
// proper preorder tree (children in range and after their parent, no sharing, no cycles), leaf
// buckets in bounds and tiling each tree's slice of `leaves`, every view index < N and each
// appearing once per tree. On failure returns false and a message naming the problem.
bool ValidateKdForest(const KdForestView& forest, std::string* error);

struct KdNeighbor {
  uint32_t index;     // row in the descriptor matrix
  uint32_t distance;  // squared L2

  friend bool operator==(const KdNeighbor&, const KdNeighbor&) = default;
};

struct KdSearchResult {
  uint32_t num_neighbors = 0;  // valid entries at the front of the output span, ascending
  uint32_t checks = 0;         // distance computations made
  // An index read from the forest was out of range (or the walk did not terminate like a
  // tree's); the search stopped and the neighbours must not be used. ValidateKdForest says why.
  bool corrupt = false;
};

struct KdSearchOptions {
  // Distance computations before the search stops (FLANN's `checks`). A leaf bucket spends
  // checks less selectively than FLANN's one-point leaves: 384 matches or beats the recall of
  // FLANN at the paper's 128 on real and generated SIFT, still ~3x faster (docs/kd_forest.md).
  // A budget of at least N makes the search exhaustive and exact: it then also ignores the
  // (heuristic) bounds.
  uint32_t max_checks = 384;
  // Descents kept in flight (1..16). 1 is FLANN's strict best-first order; more hide memory
  // latency (a descent is a chain of cache misses) at a slight cost in recall per check.
  uint32_t interleave = 4;
  // Measurement only: skips the per-read range checks. Safe only for a forest that passed
  // ValidateKdForest.
  bool skip_range_checks = false;
  // Empty: every row may be returned. Else bit (r % 64) of word r / 64 set means row r may be;
  // the search walks the leaves it would walk unfiltered, and a row it skips is not compared
  // but counts against max_checks, so filtering never makes a search slower. It then stops
  // when the budget is spent even with fewer than the neighbours asked for.
  std::span<const uint64_t> allowed_rows;
};

// Searches one forest. Holds reusable scratch (the branch heap and the visited set), so
// searches after the first allocate nothing. Not thread-safe: use one per thread.
class KdForestSearcher {
 public:
  explicit KdForestSearcher(const KdForestView& forest,
                            const DistanceFunctions& distance = BestDistanceFunctions());

  // The out.size() nearest descriptors to `query` (128 bytes), sorted by ascending distance
  // (ties by index). Never reads outside the forest's arrays, whatever they contain.
  KdSearchResult Search(const uint8_t* query, const KdSearchOptions& options,
                        std::span<KdNeighbor> out);

  const KdForestView& forest() const { return forest_; }

 private:
  static constexpr uint32_t kMaxInterleave = 16;
  // One descent in flight: which memory access it makes next.
  struct Cursor {
    enum Stage : uint8_t { kIdle, kNode, kBucket, kRows };
    uint32_t node = 0;   // kNode: node to read; kBucket: first slot of the leaf's bucket
    uint32_t bound = 0;  // kNode: lower bound of the branch
    uint32_t count = 0;  // kBucket: bucket size; kRows: rows to compare
    Stage stage = kIdle;
  };

  template <bool kChecked>
  KdSearchResult SearchImpl(const uint8_t* query, const KdSearchOptions& options,
                            std::span<KdNeighbor> out);
  template <bool kChecked>
  bool StepNode(Cursor& c);
  template <bool kChecked>
  bool StepBucket(Cursor& c, uint32_t* rows);
  void StepRows(Cursor& c, const uint32_t* rows);
  bool BudgetSpent() const {
    return checks_ >= max_checks_ && (num_results_ == k_ || !allowed_.empty());
  }
  void ResetVisited(size_t expected);
  bool InsertVisited(uint32_t index);
  void AddCandidate(uint32_t index, uint32_t distance);
  uint32_t WorstDistance() const;

  KdForestView forest_;
  const DistanceFunctions* distance_;
  uint32_t num_descriptors_;

  // Per-search state.
  const uint8_t* query_ = nullptr;
  KdNeighbor* result_ = nullptr;
  uint32_t k_ = 0;
  uint32_t num_results_ = 0;
  uint32_t checks_ = 0;
  uint32_t max_checks_ = 0;
  bool prune_ = true;
  uint64_t steps_left_ = 0;
  std::span<const uint64_t> allowed_;

  // Min-heap of (bound << 32 | node).
  std::vector<uint64_t> heap_;
  // Open-addressing set of the descriptors compared in this search; a few KB, so it stays in
  // L1 (a per-descriptor bitset or epoch array would cost a cache miss per check at 10M rows).
  std::vector<uint32_t> visited_;
  uint32_t visited_shift_ = 0;
  uint32_t visited_count_ = 0;
  size_t visited_limit_ = 0;

  // Each cursor's unvisited bucket rows (a bucket holds at most 255), and their distances.
  std::vector<uint32_t> cursor_rows_;
  uint32_t leaf_distances_[256];
};

}  // namespace cwloc
