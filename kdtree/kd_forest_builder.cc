#include "kdtree/kd_forest_builder.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "base/huge_pages.h"
#include "base/prefetch.h"
#include "base/split_mix64.h"

namespace cwloc {
namespace {

// FLANN estimates the variance from the first 100 points of a node. We keep indices sorted
// (stable partition: the rows of a node are then read in address order), so the first 100
// would all come from one image; an evenly strided sample of the node is used instead.
constexpr uint32_t kVarianceSample = 100;
// FLANN's RAND_DIM: the split dimension is drawn among this many of the highest variance.
constexpr uint32_t kRandomDims = 5;
// The top levels of every tree are split serially; the subtrees below are independent jobs.
// Fixed (not derived from the thread count) so that the output never depends on threads.
constexpr uint32_t kJobDepth = 4;
constexpr uint32_t kNoParent = std::numeric_limits<uint32_t>::max();

// A well-mixed seed from `z`: the first output of SplitMix64 seeded with it.
uint64_t Mix(uint64_t z) { return SplitMix64(z).Next(); }
uint64_t ChildSeed(uint64_t seed, int side) { return Mix(seed ^ (0x51ed2701u + side)); }

// Kept separate with restrict-qualified pointers so that the compiler vectorizes it: this
// loop is most of the build's arithmetic.
void AccumulateRow(const uint8_t* __restrict row, uint32_t* __restrict sum,
                   uint32_t* __restrict sum_sq) {
  for (size_t d = 0; d < kDescriptorDim; ++d) {
    const uint32_t v = row[d];
    sum[d] += v;
    sum_sq[d] += v * v;
  }
}

struct Split {
  bool leaf = false;
  uint8_t dim = 0, low = 0, high = 0;
  uint32_t left_count = 0;  // the first left_count indices go left
};

// Per-thread buffers, sized to the largest node the thread splits.
struct Scratch {
  std::vector<uint8_t> column;
  std::vector<uint32_t> right, right_ids;
  // A small subtree's rows copied together (see kLocalRows) and their positions in the copy.
  std::vector<uint8_t> local_rows;
  std::vector<uint32_t> local_ids;
};

// Once a subtree has at most this many rows, they are copied into one 1 MB block that stays
// in L2 for the ~10 levels below, instead of being read at random from the whole matrix at
// every level (one cache and TLB miss per row and level). The output does not change.
constexpr uint32_t kLocalRows = 8192;

// The rows of one node: ind[i] are descriptor indices (what the leaves store); row i is read
// at base + ids[i] * 128, with ids == ind and base = the matrix, or positions in a local copy.
struct NodeRows {
  uint32_t* ind;
  uint32_t* ids;
  const uint8_t* base;
  const uint8_t* Row(uint32_t i) const { return base + size_t(ids[i]) * kDescriptorDim; }
};

// Reports leaves completed (in descriptors), at most every 1/200 of the total.
class BuildProgress {
 public:
  BuildProgress(const std::function<void(double)>& callback, uint64_t total)
      : callback_(callback), total_(total) {}
  void Add(uint64_t done) {
    if (!callback_ || total_ == 0) return;
    const uint64_t now = done_.fetch_add(done) + done;
    if (now * 200 / total_ == reported_.load(std::memory_order_relaxed)) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const uint64_t step = now * 200 / total_;
    if (step <= reported_) return;
    reported_ = step;
    callback_(std::min(1.0, double(now) / double(total_)));
  }

 private:
  const std::function<void(double)>& callback_;
  uint64_t total_;
  std::atomic<uint64_t> done_{0};
  std::atomic<uint64_t> reported_{0};
  std::mutex mutex_;
};

class ForestBuilder {
 public:
  ForestBuilder(std::span<const uint8_t> descriptors, const KdForestBuildOptions& options)
      : data_(descriptors.data()),
        n_(uint32_t(descriptors.size() / kDescriptorDim)),
        max_leaf_(options.max_leaf_size),
        progress_(options.progress, uint64_t(options.num_trees) * n_) {}

  // Splits the `count` rows of one node and partitions them (left first, both sides keeping
  // their order). Deterministic in (row contents and order, seed).
  Split SplitNode(const NodeRows& rows, uint32_t count, uint64_t seed, Scratch* scratch) const;

  // Builds the subtree over ind[begin, begin + count) of a tree whose leaf slice starts at
  // `slot_base`, appending its nodes in preorder; right-child indices are relative to the
  // first appended node.
  void BuildSubtree(uint32_t* ind, uint64_t slot_base, uint32_t begin, uint32_t count,
                    uint64_t seed, std::vector<KdNode>* out, Scratch* scratch);

  NodeRows GlobalRows(uint32_t* ind) const { return NodeRows{ind, ind, data_}; }
  BuildProgress& progress() { return progress_; }
  uint32_t max_leaf() const { return max_leaf_; }

 private:
  // Splits by `dim` at a value threshold with both sides non-empty, or returns false.
  bool TrySplit(const NodeRows& rows, uint32_t count, uint32_t dim, uint32_t sum, uint32_t samples,
                Scratch* scratch, Split* split) const;
  Split FallbackSplit(const NodeRows& rows, uint32_t count, Scratch* scratch) const;
  static void Partition(const NodeRows& rows, uint32_t count, const uint8_t* column,
                        uint32_t threshold, Scratch* scratch);

  const uint8_t* data_;
  uint32_t n_;
  uint32_t max_leaf_;
  BuildProgress progress_;
};

void ForestBuilder::Partition(const NodeRows& rows, uint32_t count, const uint8_t* column,
                              uint32_t threshold, Scratch* scratch) {
  // Stable: both halves keep ascending row order, so deeper levels read memory in order.
  // Branch-free (the side is a coin flip): write both places, advance one.
  const auto partition = [&](uint32_t* values, uint32_t* right) {
    uint32_t num_left = 0, num_right = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t v = values[i];
      const uint32_t goes_left = column[i] < threshold;
      values[num_left] = v;
      right[num_right] = v;
      num_left += goes_left;
      num_right += 1 - goes_left;
    }
    std::memcpy(values + num_left, right, size_t(num_right) * sizeof(uint32_t));
  };
  partition(rows.ind, scratch->right.data());
  if (rows.ids != rows.ind) partition(rows.ids, scratch->right_ids.data());
}

bool ForestBuilder::TrySplit(const NodeRows& rows, uint32_t count, uint32_t dim, uint32_t sum,
                             uint32_t samples, Scratch* scratch, Split* split) const {
  uint8_t* column = scratch->column.data();
  uint32_t histogram[256] = {};
  constexpr uint32_t kAhead = 32;
  for (uint32_t i = 0; i < count; ++i) {
    if (i + kAhead < count) Prefetch(rows.Row(i + kAhead) + dim);
    column[i] = rows.Row(i)[dim];
    ++histogram[column[i]];
  }
  // The sample mean m as integer thresholds: v < m <=> v < ceil(m); v <= m <=> v < floor(m)+1.
  const uint32_t below_mean = (sum + samples - 1) / samples;
  const uint32_t up_to_mean = sum / samples + 1;
  uint32_t count_below = 0, count_up_to = 0;
  for (uint32_t v = 0; v < 256; ++v) {
    if (v < below_mean) count_below += histogram[v];
    if (v < up_to_mean) count_up_to += histogram[v];
  }
  // FLANN's choice between "< mean" and "<= mean"; where FLANN would cut the run of values equal
  // to the mean at count/2, we keep a value threshold (exact bounds for the search) and take
  // the more balanced side of the run.
  const uint32_t half = count / 2;
  uint32_t threshold;
  if (count_below > half) {
    threshold = below_mean;
  } else if (count_up_to < half && count_up_to > 0) {
    threshold = up_to_mean;
  } else {
    const bool below_ok = count_below > 0 && count_below < count;
    const bool up_to_ok = count_up_to > 0 && count_up_to < count;
    if (!below_ok && !up_to_ok) return false;
    const auto imbalance = [half](uint32_t c) { return c > half ? c - half : half - c; };
    threshold = below_ok && (!up_to_ok || imbalance(count_below) <= imbalance(count_up_to))
                    ? below_mean
                    : up_to_mean;
  }
  uint32_t left = 0;
  for (uint32_t v = 0; v < threshold; ++v) left += histogram[v];
  if (left == 0 || left == count) return false;
  uint32_t low = threshold - 1;
  while (histogram[low] == 0) --low;
  uint32_t high = threshold;
  while (histogram[high] == 0) ++high;
  Partition(rows, count, column, threshold, scratch);
  split->dim = uint8_t(dim);
  split->low = uint8_t(low);
  split->high = uint8_t(high);
  split->left_count = left;
  return true;
}

Split ForestBuilder::FallbackSplit(const NodeRows& rows, uint32_t count, Scratch* scratch) const {
  // The sampled dimensions did not separate the node: find any dimension that does.
  uint8_t lo[kDescriptorDim], hi[kDescriptorDim];
  std::memset(lo, 255, sizeof(lo));
  std::memset(hi, 0, sizeof(hi));
  for (uint32_t i = 0; i < count; ++i) {
    const uint8_t* row = rows.Row(i);
    for (size_t d = 0; d < kDescriptorDim; ++d) {
      lo[d] = std::min(lo[d], row[d]);
      hi[d] = std::max(hi[d], row[d]);
    }
  }
  uint32_t best_dim = 0, best_range = 0;
  for (uint32_t d = 0; d < kDescriptorDim; ++d) {
    if (uint32_t(hi[d] - lo[d]) > best_range) best_range = hi[d] - lo[d], best_dim = d;
  }
  Split split;
  if (best_range == 0) {
    // All rows identical: a leaf if it fits in a bucket, else cut in the middle. Both halves
    // then hold the same value, which the bounds low = high express exactly.
    if (count <= kKdLeaf) {
      split.leaf = true;
      return split;
    }
    split.dim = 0;
    split.low = split.high = rows.Row(0)[0];
    split.left_count = count / 2;
    return split;
  }
  // Midpoint of the range: both sides non-empty.
  const uint32_t sum = uint32_t(lo[best_dim]) + hi[best_dim];
  if (!TrySplit(rows, count, best_dim, sum, 2, scratch, &split)) {
    throw std::logic_error("BuildKdForest: a dimension with a value range did not split");
  }
  return split;
}

Split ForestBuilder::SplitNode(const NodeRows& rows, uint32_t count, uint64_t seed,
                               Scratch* scratch) const {
  Split split;
  if (count <= max_leaf_) {
    split.leaf = true;
    return split;
  }
  // Mean and variance (times the sample size squared, exact in integers) of every dimension.
  const uint32_t samples = std::min(count, kVarianceSample);
  uint32_t sum[kDescriptorDim] = {};
  uint32_t sum_sq[kDescriptorDim] = {};
  const uint8_t* sample[kVarianceSample];
  for (uint32_t s = 0; s < samples; ++s) {
    sample[s] = rows.Row(samples == count ? s : uint32_t(uint64_t(s) * count / samples));
    Prefetch(sample[s]);  // all sample rows in flight at once (random rows in large nodes)
    Prefetch(sample[s] + 64);
  }
  for (uint32_t s = 0; s < samples; ++s) AccumulateRow(sample[s], sum, sum_sq);
  uint64_t variance[kDescriptorDim];
  for (size_t d = 0; d < kDescriptorDim; ++d) {
    variance[d] = uint64_t(samples) * sum_sq[d] - uint64_t(sum[d]) * sum[d];
  }
  // The kRandomDims largest variances (ties to the lower dimension), zero excluded.
  uint32_t top[kRandomDims];
  uint32_t num_top = 0;
  for (uint32_t d = 0; d < kDescriptorDim; ++d) {
    if (variance[d] == 0) continue;
    if (num_top == kRandomDims && variance[d] <= variance[top[num_top - 1]]) continue;
    uint32_t j = num_top < kRandomDims ? num_top++ : kRandomDims - 1;
    while (j > 0 && variance[top[j - 1]] < variance[d]) {
      top[j] = top[j - 1];
      --j;
    }
    top[j] = d;
  }
  if (num_top > 0) {
    const uint32_t first = uint32_t((seed >> 33) % num_top);
    for (uint32_t attempt = 0; attempt < num_top; ++attempt) {
      const uint32_t dim = top[(first + attempt) % num_top];
      if (TrySplit(rows, count, dim, sum[dim], samples, scratch, &split)) return split;
    }
  }
  return FallbackSplit(rows, count, scratch);
}

void ForestBuilder::BuildSubtree(uint32_t* ind, uint64_t slot_base, uint32_t begin, uint32_t count,
                                 uint64_t seed, std::vector<KdNode>* out, Scratch* scratch) {
  struct Task {
    uint32_t begin, count;
    uint64_t seed;
    uint32_t parent;  // node whose right child this is, relative to `base`
  };
  const size_t base = out->size();
  std::vector<Task> stack{{begin, count, seed, kNoParent}};
  // The range of `ind` whose rows are in scratch->local_rows. Depth-first order finishes a
  // subtree before leaving it, so one local block at a time suffices.
  uint32_t local_begin = 0, local_count = 0;
  uint64_t done = 0;
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    const uint32_t position = uint32_t(out->size() - base);
    if (task.parent != kNoParent) (*out)[base + task.parent].index = position;
    const bool in_local = task.begin >= local_begin &&
                          uint64_t(task.begin) + task.count <= uint64_t(local_begin) + local_count;
    NodeRows rows = GlobalRows(ind + task.begin);
    if (in_local) {
      rows = NodeRows{ind + task.begin, scratch->local_ids.data() + (task.begin - local_begin),
                      scratch->local_rows.data()};
    } else if (task.count <= kLocalRows && task.count > max_leaf_) {
      constexpr uint32_t kAhead = 16;
      for (uint32_t i = 0; i < task.count; ++i) {
        if (i + kAhead < task.count) {
          Prefetch(data_ + size_t(ind[task.begin + i + kAhead]) * kDescriptorDim);
          Prefetch(data_ + size_t(ind[task.begin + i + kAhead]) * kDescriptorDim + 64);
        }
        std::memcpy(scratch->local_rows.data() + size_t(i) * kDescriptorDim,
                    data_ + size_t(ind[task.begin + i]) * kDescriptorDim, kDescriptorDim);
        scratch->local_ids[i] = i;
      }
      local_begin = task.begin;
      local_count = task.count;
      rows = NodeRows{ind + task.begin, scratch->local_ids.data(), scratch->local_rows.data()};
    }
    const Split split = SplitNode(rows, task.count, task.seed, scratch);
    if (split.leaf) {
      out->push_back(KdNode{uint32_t(slot_base + task.begin), kKdLeaf, uint8_t(task.count), 0, 0});
      done += task.count;
      if (done >= 65536) progress_.Add(done), done = 0;
      continue;
    }
    out->push_back(KdNode{0, split.dim, split.low, split.high, 0});
    // Left is popped first, so it is emitted right after its parent (preorder).
    stack.push_back(Task{task.begin + split.left_count, task.count - split.left_count,
                         ChildSeed(task.seed, 1), position});
    stack.push_back(Task{task.begin, split.left_count, ChildSeed(task.seed, 0), kNoParent});
  }
  progress_.Add(done);
}

// Runs fn(task, worker) for task in [0, num_tasks) on up to num_threads threads.
template <typename Fn>
void RunParallel(size_t num_tasks, uint32_t num_threads, Fn&& fn) {
  const uint32_t workers = uint32_t(std::max<size_t>(1, std::min<size_t>(num_threads, num_tasks)));
  std::atomic<size_t> next{0};
  std::mutex error_mutex;
  std::exception_ptr error;
  auto run = [&](uint32_t worker) {
    try {
      for (size_t task; (task = next.fetch_add(1)) < num_tasks;) fn(task, worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = num_tasks;
    }
  };
  std::vector<std::thread> threads;
  for (uint32_t w = 1; w < workers; ++w) threads.emplace_back(run, w);
  run(0);
  for (std::thread& t : threads) t.join();
  if (error) std::rethrow_exception(error);
}

// The serially split top of one tree: its nodes in preorder, with jobs standing for subtrees.
struct TopEntry {
  KdNode node{};
  int32_t job = -1;          // >= 0: this entry is the subtree built by that job
  uint32_t right_entry = 0;  // inner node: the entry of its right child
};

struct Job {
  uint32_t tree, begin, count;
  uint64_t seed;
  std::vector<KdNode> nodes;
};

// Throws std::invalid_argument where BuildKdForest cannot build.
void CheckBuildInput(std::span<const uint8_t> descriptors, const KdForestBuildOptions& options) {
  if (descriptors.size() % kDescriptorDim != 0) {
    throw std::invalid_argument("BuildKdForest: descriptor bytes (" +
                                std::to_string(descriptors.size()) + ") not a multiple of 128");
  }
  const uint64_t n = descriptors.size() / kDescriptorDim;
  const uint32_t num_trees = options.num_trees;
  if (num_trees == 0 || num_trees > kMaxKdTrees) {
    throw std::invalid_argument("BuildKdForest: num_trees must be in 1.." +
                                std::to_string(kMaxKdTrees));
  }
  if (options.max_leaf_size == 0 || options.max_leaf_size > kMaxKdLeafSize) {
    throw std::invalid_argument("BuildKdForest: max_leaf_size must be in 1.." +
                                std::to_string(kMaxKdLeafSize));
  }
  if (n * num_trees >= std::numeric_limits<uint32_t>::max()) {
    throw std::invalid_argument("BuildKdForest: " + std::to_string(n) + " descriptors x " +
                                std::to_string(num_trees) + " trees exceed 32-bit leaf slots");
  }
}

// Phase 1 for tree `tree`, whose rows are ind[0, count) and leaf slots start at `slot_base`:
// its top kJobDepth levels split serially into `top`, each subtree below them one of `jobs`.
void SplitTreeTop(ForestBuilder& builder, uint32_t tree, uint32_t* ind, uint64_t slot_base,
                  uint32_t count, uint64_t seed, Scratch* scratch, std::vector<TopEntry>* top,
                  std::vector<Job>* jobs) {
  // Iterative preorder, like BuildSubtree, stopping at kJobDepth.
  struct Task {
    uint32_t begin, count, depth;
    uint64_t seed;
    uint32_t parent;
  };
  std::vector<Task> stack{{0, count, 0, seed, kNoParent}};
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    const uint32_t entry = uint32_t(top->size());
    if (task.parent != kNoParent) (*top)[task.parent].right_entry = entry;
    if (task.depth == kJobDepth && task.count > builder.max_leaf()) {
      TopEntry job_entry;
      job_entry.job = int32_t(jobs->size());
      top->push_back(job_entry);
      jobs->push_back(Job{tree, task.begin, task.count, task.seed, {}});
      continue;
    }
    const Split split =
        builder.SplitNode(builder.GlobalRows(ind + task.begin), task.count, task.seed, scratch);
    TopEntry e;
    if (split.leaf) {
      e.node = KdNode{uint32_t(slot_base + task.begin), kKdLeaf, uint8_t(task.count), 0, 0};
      top->push_back(e);
      builder.progress().Add(task.count);
      continue;
    }
    e.node = KdNode{0, split.dim, split.low, split.high, 0};
    top->push_back(e);
    stack.push_back(Task{task.begin + split.left_count, task.count - split.left_count,
                         task.depth + 1, ChildSeed(task.seed, 1), entry});
    stack.push_back(
        Task{task.begin, split.left_count, task.depth + 1, ChildSeed(task.seed, 0), kNoParent});
  }
}

// Phase 3 for one tree: its top entries and its jobs' subtrees (freed once copied) spliced
// into one preorder run appended to forest->nodes, its root appended to forest->roots.
void AppendTree(const std::vector<TopEntry>& top, std::vector<Job>* jobs, KdForest* forest) {
  const uint32_t root = uint32_t(forest->nodes.size());
  forest->roots.push_back(root);
  std::vector<uint32_t> position(top.size());
  uint64_t cursor = root;
  for (size_t e = 0; e < top.size(); ++e) {
    position[e] = uint32_t(cursor);
    cursor += top[e].job >= 0 ? (*jobs)[top[e].job].nodes.size() : 1;
  }
  if (cursor > std::numeric_limits<uint32_t>::max()) {
    throw std::length_error("BuildKdForest: more than 2^32 nodes");
  }
  ReserveOnHugePages(&forest->nodes, cursor);
  for (size_t e = 0; e < top.size(); ++e) {
    if (top[e].job < 0) {
      KdNode node = top[e].node;
      if (node.dim != kKdLeaf) node.index = position[top[e].right_entry];
      forest->nodes.push_back(node);
      continue;
    }
    std::vector<KdNode>& sub = (*jobs)[top[e].job].nodes;
    for (KdNode node : sub) {
      if (node.dim != kKdLeaf) node.index += position[e];
      forest->nodes.push_back(node);
    }
    std::vector<KdNode>().swap(sub);
  }
}

}  // namespace

KdForest BuildKdForest(std::span<const uint8_t> descriptors, const KdForestBuildOptions& options) {
  CheckBuildInput(descriptors, options);
  const uint64_t n = descriptors.size() / kDescriptorDim;
  const uint32_t num_trees = options.num_trees;
  uint32_t num_threads = options.num_threads;
  if (num_threads == 0) num_threads = std::max(1u, std::thread::hardware_concurrency());

  KdForest forest;
  ReserveOnHugePages(&forest.leaves, n * num_trees);
  forest.leaves.resize(n * num_trees);
  for (uint32_t t = 0; t < num_trees; ++t) {
    for (uint64_t i = 0; i < n; ++i) forest.leaves[t * n + i] = uint32_t(i);
  }
  ForestBuilder builder(descriptors, options);
  std::vector<Scratch> scratch(num_threads);
  auto ensure_scratch = [&](uint32_t worker, uint32_t count) {
    Scratch& s = scratch[worker];
    if (s.column.size() < count) s.column.resize(count), s.right.resize(count);
    if (s.local_ids.size() < kLocalRows) {
      s.local_ids.resize(kLocalRows);
      s.right_ids.resize(kLocalRows);
      s.local_rows.resize(size_t(kLocalRows) * kDescriptorDim);
    }
    return &s;
  };

  // Phase 1: the top kJobDepth levels of each tree (trees in parallel).
  std::vector<std::vector<TopEntry>> tops(num_trees);
  std::vector<std::vector<Job>> tree_jobs(num_trees);
  RunParallel(num_trees, num_threads, [&](size_t t, uint32_t worker) {
    SplitTreeTop(builder, uint32_t(t), forest.leaves.data() + t * n, t * n, uint32_t(n),
                 Mix(options.seed ^ Mix(t + 1)), ensure_scratch(worker, uint32_t(n)), &tops[t],
                 &tree_jobs[t]);
  });

  // Phase 2: all subtrees of all trees, largest first for load balance.
  std::vector<Job*> jobs;
  for (auto& list : tree_jobs) {
    for (Job& job : list) jobs.push_back(&job);
  }
  std::stable_sort(jobs.begin(), jobs.end(),
                   [](const Job* a, const Job* b) { return a->count > b->count; });
  RunParallel(jobs.size(), num_threads, [&](size_t j, uint32_t worker) {
    Job& job = *jobs[j];
    Scratch* s = ensure_scratch(worker, job.count);
    builder.BuildSubtree(forest.leaves.data() + job.tree * n, job.tree * n, job.begin, job.count,
                         job.seed, &job.nodes, s);
  });
  scratch.clear();

  // Phase 3: splice each tree's top entries and job subtrees into one preorder array.
  for (uint32_t t = 0; t < num_trees; ++t) AppendTree(tops[t], &tree_jobs[t], &forest);
  if (options.progress) options.progress(1.0);
  return forest;
}

void AppendKdSubtree(std::span<const uint8_t> descriptors, std::span<uint32_t> rows,
                     uint32_t max_leaf_size, uint64_t seed, uint64_t slot_base,
                     std::vector<KdNode>* nodes) {
  KdForestBuildOptions options;
  options.max_leaf_size = max_leaf_size;
  ForestBuilder builder(descriptors, options);
  Scratch scratch;
  const auto count = uint32_t(rows.size());
  scratch.column.resize(count);
  scratch.right.resize(count);
  // A small bucket split needs a copy of its own size only.
  const uint32_t local = std::min(count, kLocalRows);
  scratch.local_ids.resize(local);
  scratch.right_ids.resize(local);
  scratch.local_rows.resize(size_t(local) * kDescriptorDim);
  std::vector<KdNode> subtree;
  builder.BuildSubtree(rows.data(), slot_base, 0, count, seed, &subtree, &scratch);
  const auto base = uint32_t(nodes->size());
  for (KdNode node : subtree) {
    if (node.dim != kKdLeaf) node.index += base;
    nodes->push_back(node);
  }
}

}  // namespace cwloc
