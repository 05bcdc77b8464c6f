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
//   descriptors       N x 128 uint8, row-major; or N product-quantization codes
//                     (descriptor_codes.h), decoded as the leaves compare them.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "kdtree/descriptor_codes.h"
#include "kdtree/descriptor_distance.h"

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
  std::span<const uint8_t> descriptors;  // N x 128, or empty when `codes` holds the rows
  DescriptorCodes codes{};

  size_t NumDescriptors() const {
    return codes.empty() ? descriptors.size() / kDescriptorDim : codes.NumRows();
  }
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

// Searches one forest. Holds reusable scratch (per search in flight: the branch heap and the
// visited set), so searches after the first allocate nothing. Not thread-safe: use one per
// thread.
class KdForestSearcher {
 public:
  // Upper bound on SearchBatch's `width`.
  static constexpr uint32_t kMaxBatchWidth = 64;
  // SearchBatch's default width. With interleave 4, 2 was ~5% faster than one at a time on
  // herz_jesu_p25 (in cache) and 4 or 8 slower; on 2M generated rows none gained (#24).
  static constexpr uint32_t kDefaultBatchWidth = 2;

  explicit KdForestSearcher(const KdForestView& forest,
                            const DistanceFunctions& distance = BestDistanceFunctions());

  // The out.size() nearest descriptors to `query` (128 bytes), sorted by ascending distance
  // (ties by index). Never reads outside the forest's arrays, whatever they contain.
  KdSearchResult Search(const uint8_t* query, const KdSearchOptions& options,
                        std::span<KdNeighbor> out);

  // results[i] = Search(queries[i], options, outs[i]) for every i, bit for bit, but with up to
  // `width` searches in flight, stepped round-robin one memory access per descent: one search
  // is a chain of dependent cache misses, so the others work while it waits (throughput when
  // the forest does not fit in cache). outs and results need queries.size() entries
  // (std::invalid_argument otherwise); width is clamped to 1..kMaxBatchWidth.
  void SearchBatch(std::span<const uint8_t* const> queries, const KdSearchOptions& options,
                   std::span<const std::span<KdNeighbor>> outs, std::span<KdSearchResult> results,
                   uint32_t width = kDefaultBatchWidth);

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

  // Everything one search reads and writes besides the forest, so that a search can be
  // advanced a round at a time and several can take turns.
  struct State {
    const uint8_t* query = nullptr;
    KdNeighbor* result = nullptr;
    uint32_t k = 0;
    uint32_t num_results = 0;
    uint32_t checks = 0;
    uint32_t max_checks = 0;
    uint32_t num_cursors = 0;
    bool prune = true;
    bool ok = true;  // false: the forest is corrupt
    uint64_t steps_left = 0;
    std::span<const uint64_t> allowed;
    Cursor cursors[kMaxInterleave];

    // Min-heap of (bound << 32 | node).
    std::vector<uint64_t> heap;
    // Open-addressing set of the descriptors compared in this search; a few KB, so it stays
    // in L1 (a per-descriptor bitset or epoch array would cost a cache miss per check at 10M
    // rows).
    std::vector<uint32_t> visited;
    uint32_t visited_shift = 0;
    uint32_t visited_count = 0;
    size_t visited_limit = 0;
    // Each cursor's unvisited bucket rows (a bucket holds at most 255).
    std::vector<uint32_t> cursor_rows;

    bool BudgetSpent() const {
      return checks >= max_checks && (num_results == k || !allowed.empty());
    }
    uint32_t WorstDistance() const {
      return num_results == k ? result[k - 1].distance : std::numeric_limits<uint32_t>::max();
    }
    void ResetVisited(size_t expected);
    bool InsertVisited(uint32_t index);
    void AddCandidate(uint32_t index, uint32_t distance);
  };

  // Sets up a search; false when it is already finished (nothing to search, or a corrupt root).
  template <bool kChecked>
  bool Start(State& s, const uint8_t* query, const KdSearchOptions& options,
             std::span<KdNeighbor> out);
  // Advances every descent of the search by one memory access; false when it is finished.
  template <bool kChecked>
  bool Round(State& s);
  static KdSearchResult Finish(const State& s);
  template <bool kChecked>
  bool StepNode(State& s, Cursor& c);
  template <bool kChecked>
  bool StepBucket(State& s, Cursor& c, uint32_t* rows);
  void StepRows(State& s, Cursor& c, const uint32_t* rows);
  template <bool kChecked>
  KdSearchResult SearchImpl(const uint8_t* query, const KdSearchOptions& options,
                            std::span<KdNeighbor> out);
  template <bool kChecked>
  void SearchBatchImpl(std::span<const uint8_t* const> queries, const KdSearchOptions& options,
                       std::span<const std::span<KdNeighbor>> outs,
                       std::span<KdSearchResult> results, uint32_t width);

  KdForestView forest_;
  const DistanceFunctions* distance_;
  uint32_t num_descriptors_;
  // states_[0] serves Search; SearchBatch uses as many as its width.
  std::vector<State> states_;
  // A bucket's distances, filled and consumed within one step.
  uint32_t leaf_distances_[256];
  // Coded rows: a bucket's decoded descriptors, and the row numbers 0..255 into them.
  std::vector<uint8_t> decoded_;
  uint32_t decoded_rows_[256];
};

}  // namespace cwloc
