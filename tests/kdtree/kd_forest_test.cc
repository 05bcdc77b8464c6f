#include "kdtree/kd_forest.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

#if defined(__unix__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include "kdtree/kd_forest_builder.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// SIFT-like clustered rows: sparse non-negative centres plus noise of about `noise` per dim.
std::vector<uint8_t> ClusteredDescriptors(size_t n, size_t clusters, int noise) {
  auto& rng = test::Rng();
  std::vector<uint8_t> centres(clusters * kDescriptorDim);
  for (auto& c : centres) c = rng() % 3 == 0 ? 0 : uint8_t(rng() % 120);
  std::vector<uint8_t> out(n * kDescriptorDim);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* c = centres.data() + (rng() % clusters) * kDescriptorDim;
    for (size_t d = 0; d < kDescriptorDim; ++d) {
      const int v = int(c[d]) + int(rng() % (2 * noise + 1)) - noise;
      out[i * kDescriptorDim + d] = uint8_t(std::clamp(v, 0, 255));
    }
  }
  return out;
}

// Copies of the rows of `data` picked at random, each perturbed a little: queries whose
// nearest neighbour is (usually) the row they came from.
std::vector<uint8_t> NearbyQueries(const std::vector<uint8_t>& data, size_t count, int noise) {
  auto& rng = test::Rng();
  const size_t n = data.size() / kDescriptorDim;
  std::vector<uint8_t> out(count * kDescriptorDim);
  for (size_t q = 0; q < count; ++q) {
    const uint8_t* row = data.data() + (rng() % n) * kDescriptorDim;
    for (size_t d = 0; d < kDescriptorDim; ++d) {
      const int v = int(row[d]) + int(rng() % (2 * noise + 1)) - noise;
      out[q * kDescriptorDim + d] = uint8_t(std::clamp(v, 0, 255));
    }
  }
  return out;
}

std::vector<KdNeighbor> BruteForce(std::span<const uint8_t> data, const uint8_t* query, size_t k) {
  const size_t n = data.size() / kDescriptorDim;
  std::vector<KdNeighbor> all(n);
  const DistanceFunctions* scalar = DistanceFunctionsFor(DistanceKernel::kScalar);
  for (size_t i = 0; i < n; ++i) {
    all[i] = KdNeighbor{uint32_t(i), scalar->one(query, data.data() + i * kDescriptorDim)};
  }
  const auto less = [](const KdNeighbor& a, const KdNeighbor& b) {
    return a.distance != b.distance ? a.distance < b.distance : a.index < b.index;
  };
  std::sort(all.begin(), all.end(), less);
  all.resize(std::min(k, n));
  return all;
}

KdForest Build(const std::vector<uint8_t>& data, uint64_t seed = 7, uint32_t threads = 2,
               uint32_t trees = 4, uint32_t leaf = 8) {
  KdForestBuildOptions options;
  options.seed = seed;
  options.num_threads = threads;
  options.num_trees = trees;
  options.max_leaf_size = leaf;
  return BuildKdForest(data, options);
}

// A copy of an array placed so that it ends exactly where an inaccessible page begins: any
// read past the end faults instead of silently returning garbage.
template <typename T>
class Guarded {
 public:
  explicit Guarded(std::span<const T> src) : size_(src.size()) {
#if defined(__unix__)
    const size_t page = size_t(sysconf(_SC_PAGESIZE));
    const size_t bytes = src.size_bytes();
    body_ = (bytes + page - 1) / page * page;
    void* p =
        mmap(nullptr, body_ + page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    EXPECT_NE(p, MAP_FAILED);
    base_ = static_cast<uint8_t*>(p);
    EXPECT_EQ(mprotect(base_ + body_, page, PROT_NONE), 0);
    data_ = reinterpret_cast<T*>(base_ + body_ - bytes);
#else
    storage_.resize(src.size());
    data_ = storage_.data();
#endif
    if (!src.empty()) std::memcpy(static_cast<void*>(data_), src.data(), src.size_bytes());
  }
  ~Guarded() {
#if defined(__unix__)
    munmap(base_, body_ + size_t(sysconf(_SC_PAGESIZE)));
#endif
  }
  Guarded(const Guarded&) = delete;
  Guarded& operator=(const Guarded&) = delete;
  T* data() { return data_; }
  T& operator[](size_t i) { return data_[i]; }
  size_t size() const { return size_; }
  std::span<const T> span() const { return {data_, size_}; }

 private:
  size_t size_;
  T* data_ = nullptr;
#if defined(__unix__)
  uint8_t* base_ = nullptr;
  size_t body_ = 0;
#else
  std::vector<T> storage_;
#endif
};

// A forest whose every array sits against a guard page; tests corrupt the copies.
struct GuardedForest {
  GuardedForest(const KdForest& forest, const std::vector<uint8_t>& data)
      : nodes(std::span<const KdNode>(forest.nodes)),
        roots(std::span<const uint32_t>(forest.roots)),
        leaves(std::span<const uint32_t>(forest.leaves)),
        descriptors(std::span<const uint8_t>(data)) {}
  KdForestView View() const {
    return KdForestView{nodes.span(), roots.span(), leaves.span(), descriptors.span()};
  }
  Guarded<KdNode> nodes;
  Guarded<uint32_t> roots;
  Guarded<uint32_t> leaves;
  Guarded<uint8_t> descriptors;
};

size_t FirstInner(std::span<const KdNode> nodes, size_t from = 0) {
  for (size_t i = from; i < nodes.size(); ++i) {
    if (nodes[i].dim != kKdLeaf) return i;
  }
  return nodes.size();
}
size_t FirstLeaf(std::span<const KdNode> nodes, size_t from = 0) {
  for (size_t i = from; i < nodes.size(); ++i) {
    if (nodes[i].dim == kKdLeaf) return i;
  }
  return nodes.size();
}

TEST(KdForest, LayoutIsFixed) {
  static_assert(std::is_trivially_copyable_v<KdNode>);
  static_assert(std::is_standard_layout_v<KdNode>);
  EXPECT_EQ(sizeof(KdNode), 8u);
}

TEST(KdForest, ExhaustiveBudgetEqualsBruteForce) {
  std::vector<uint8_t> data = ClusteredDescriptors(3000, 40, 20);
  // Exact duplicates make distance ties, which must resolve by index like the brute force.
  for (size_t i = 0; i < 200; ++i) {
    std::memcpy(data.data() + (2000 + i) * kDescriptorDim, data.data() + i * kDescriptorDim,
                kDescriptorDim);
  }
  const KdForest forest = Build(data);
  const KdForestView view = forest.View(data);
  std::string error;
  ASSERT_TRUE(ValidateKdForest(view, &error)) << error;
  std::vector<uint8_t> queries = NearbyQueries(data, 40, 10);
  const std::vector<uint8_t> far = ClusteredDescriptors(20, 5, 60);
  queries.insert(queries.end(), far.begin(), far.end());
  queries.insert(queries.end(), data.begin(), data.begin() + 10 * kDescriptorDim);  // exact rows
  KdForestSearcher searcher(view);
  KdSearchOptions options;
  options.max_checks = 3000;
  for (size_t k : {1, 6, 25}) {
    std::vector<KdNeighbor> out(k);
    for (size_t q = 0; q < queries.size() / kDescriptorDim; ++q) {
      const uint8_t* query = queries.data() + q * kDescriptorDim;
      const KdSearchResult r = searcher.Search(query, options, out);
      ASSERT_FALSE(r.corrupt);
      ASSERT_EQ(r.num_neighbors, k);
      EXPECT_EQ(r.checks, 3000u);  // every descriptor exactly once
      const std::vector<KdNeighbor> expected = BruteForce(data, query, k);
      ASSERT_EQ(std::vector<KdNeighbor>(out.begin(), out.end()), expected) << "query " << q;
    }
  }
  // Asking for more neighbours than there are descriptors returns them all.
  const std::vector<uint8_t> small(data.begin(), data.begin() + 5 * kDescriptorDim);
  const KdForest small_forest = Build(small);
  KdForestSearcher small_searcher(small_forest.View(small));
  std::vector<KdNeighbor> out(9);
  const KdSearchResult r = small_searcher.Search(queries.data(), KdSearchOptions{}, out);
  EXPECT_EQ(r.num_neighbors, 5u);
  EXPECT_EQ(std::vector<KdNeighbor>(out.begin(), out.begin() + 5),
            BruteForce(small, queries.data(), 5));
}

// The compact index's rows: product-quantization codes the leaves decode. For every code size
// and budget, a search over the codes returns exactly what a search over the decoded rows does.
TEST(KdForest, CodedRowsSearchLikeTheirDecodedDescriptors) {
  auto& rng = test::Rng();
  std::vector<uint8_t> codebook(DescriptorCodes::kCodebookBytes);
  for (auto& byte : codebook) byte = uint8_t(rng() % 3 == 0 ? 0 : rng() % 120);
  const size_t n = 2000;
  for (const uint32_t code_bytes : {4u, 8u, 16u, 32u, 64u}) {
    SCOPED_TRACE(std::to_string(code_bytes) + "-byte codes");
    std::vector<uint8_t> codes(n * code_bytes);
    for (auto& byte : codes) byte = uint8_t(rng() % 256);
    const DescriptorCodes coded{codebook, codes, code_bytes};
    ASSERT_EQ(coded.NumRows(), n);
    std::vector<uint8_t> decoded(n * kDescriptorDim);
    for (size_t row = 0; row < n; ++row) coded.Decode(row, &decoded[row * kDescriptorDim]);
    // Decoding is the centroid lookup, part by part.
    const uint32_t dims = kDescriptorDim / code_bytes;
    for (uint32_t s = 0; s < code_bytes; ++s) {
      EXPECT_EQ(decoded[s * dims + dims - 1],
                codebook[(size_t{s} * 256 + codes[s]) * dims + dims - 1]);
    }
    const KdForest forest = Build(decoded);
    KdForestView with_codes = forest.View(decoded);
    with_codes.descriptors = {};
    with_codes.codes = coded;
    std::string error;
    ASSERT_TRUE(ValidateKdForest(with_codes, &error)) << error;
    KdForestSearcher decoded_searcher(forest.View(decoded));
    KdForestSearcher code_searcher(with_codes);
    const std::vector<uint8_t> queries = NearbyQueries(decoded, 30, 10);
    for (const uint32_t checks : {64u, 384u, 4000u}) {
      KdSearchOptions options;
      options.max_checks = checks;
      std::vector<KdNeighbor> expected(6), got(6);
      for (size_t q = 0; q < 30; ++q) {
        const uint8_t* query = &queries[q * kDescriptorDim];
        const KdSearchResult a = decoded_searcher.Search(query, options, expected);
        const KdSearchResult b = code_searcher.Search(query, options, got);
        ASSERT_EQ(a.num_neighbors, b.num_neighbors);
        EXPECT_EQ(a.checks, b.checks);
        EXPECT_EQ(expected, got) << "query " << q << ", " << checks << " checks";
      }
    }
  }
  // A codebook of the wrong size or a code size that does not split 128 is named.
  std::vector<uint8_t> codes(100 * 12);
  const KdForestView bad{{}, {}, {}, {}, DescriptorCodes{codebook, codes, 12}};
  std::string error;
  EXPECT_FALSE(ValidateKdForest(bad, &error));
  EXPECT_EQ(error, "kd-forest codes: 12-byte codes over 1200 bytes with a 32768-byte codebook");
}

// A position prior's row filter: only allowed rows come back, exactly the brute-force nearest
// among them with an exhaustive budget, and a small budget is never exceeded by skipped rows.
TEST(KdForest, AllowedRowsFilterTheResultsWithinTheSameBudget) {
  const std::vector<uint8_t> data = ClusteredDescriptors(3000, 40, 20);
  const KdForest forest = Build(data);
  KdForestSearcher searcher(forest.View(data));
  std::vector<uint64_t> allowed(3000 / 64 + 1, 0);
  std::vector<uint8_t> allowed_data;  // the allowed rows alone, for the brute force
  std::vector<uint32_t> allowed_rows;
  for (uint32_t row = 0; row < 3000; ++row) {
    if (row % 7 != 3) continue;  // one row in seven
    allowed[row / 64] |= uint64_t{1} << (row % 64);
    allowed_rows.push_back(row);
    allowed_data.insert(allowed_data.end(), data.begin() + row * kDescriptorDim,
                        data.begin() + (row + 1) * kDescriptorDim);
  }
  const std::vector<uint8_t> queries = NearbyQueries(data, 30, 10);
  KdSearchOptions options;
  options.allowed_rows = allowed;
  std::vector<KdNeighbor> out(6);
  for (size_t q = 0; q < queries.size() / kDescriptorDim; ++q) {
    const uint8_t* query = queries.data() + q * kDescriptorDim;
    options.max_checks = 3000;
    KdSearchResult r = searcher.Search(query, options, out);
    ASSERT_EQ(r.num_neighbors, 6u);
    std::vector<KdNeighbor> expected = BruteForce(allowed_data, query, 6);
    for (KdNeighbor& n : expected) n.index = allowed_rows[n.index];
    EXPECT_EQ(std::vector<KdNeighbor>(out.begin(), out.end()), expected) << "query " << q;

    options.max_checks = 64;
    r = searcher.Search(query, options, out);
    EXPECT_LE(r.checks, 64u + 255u);  // at most one bucket past the budget
    for (uint32_t i = 0; i < r.num_neighbors; ++i) EXPECT_EQ(out[i].index % 7, 3u);
  }
}

TEST(KdForest, EveryKernelGivesTheSameExactResults) {
  const std::vector<uint8_t> data = ClusteredDescriptors(1500, 20, 30);
  const KdForest forest = Build(data);
  const std::vector<uint8_t> queries = NearbyQueries(data, 30, 15);
  KdSearchOptions options;
  options.max_checks = 128;
  std::vector<std::vector<KdNeighbor>> reference;
  for (DistanceKernel kernel : kAllDistanceKernels) {
    const DistanceFunctions* f = DistanceFunctionsFor(kernel);
    if (!f) continue;
    KdForestSearcher searcher(forest.View(data), *f);
    for (size_t q = 0; q < 30; ++q) {
      std::vector<KdNeighbor> out(6);
      searcher.Search(queries.data() + q * kDescriptorDim, options, out);
      if (kernel == DistanceKernel::kScalar) {
        reference.push_back(out);
      } else {
        EXPECT_EQ(out, reference[q]) << f->name << " query " << q;
      }
    }
  }
}

TEST(KdForest, RecallAtTheDefaultBudget) {
  // 40k rows in 400 clusters; queries are noisy copies of base rows, a bit farther from their
  // source than the rows of a cluster are from each other (so the nearest is any of them).
  constexpr int kQueryNoise = 40;
  const std::vector<uint8_t> data = ClusteredDescriptors(40000, 400, 25);
  const KdForest forest = Build(data);
  KdForestSearcher searcher(forest.View(data));
  const size_t num_queries = 300;
  const std::vector<uint8_t> queries = NearbyQueries(data, num_queries, kQueryNoise);
  std::vector<std::vector<KdNeighbor>> truth;
  for (size_t q = 0; q < num_queries; ++q) {
    truth.push_back(BruteForce(data, queries.data() + q * kDescriptorDim, 2));
  }
  // The default budget, and FLANN's strict best-first order (interleave 1) at the same budget.
  for (uint32_t interleave : {KdSearchOptions{}.interleave, 1u}) {
    KdSearchOptions options;
    options.interleave = interleave;
    size_t hits1 = 0, hits2 = 0;
    uint64_t checks = 0;
    std::vector<KdNeighbor> out(6);
    for (size_t q = 0; q < num_queries; ++q) {
      const KdSearchResult r = searcher.Search(queries.data() + q * kDescriptorDim, options, out);
      ASSERT_EQ(r.num_neighbors, 6u);
      checks += r.checks;
      for (const KdNeighbor& n : out) {
        hits1 += n.index == truth[q][0].index;
        hits2 += n.index == truth[q][1].index;
      }
    }
    const double recall1 = double(hits1) / num_queries, recall2 = double(hits2) / num_queries;
    std::cout << "interleave " << interleave << ": recall@1 " << recall1 << ", recall@2 " << recall2
              << ", checks/query " << double(checks) / num_queries << "\n";
    EXPECT_EQ(checks, num_queries * options.max_checks);
    EXPECT_GE(recall1, 0.93);
    EXPECT_GE(recall2, 0.85);
  }
}

// SearchBatch(queries) must give every query exactly what Search gives it alone: neighbours,
// checks and the corrupt flag. Returns how many queries differed (0 is a pass); `found` counts
// the neighbours returned, so that a batch returning nothing cannot pass by matching nothing.
size_t BatchMismatches(KdForestSearcher& searcher, const std::vector<uint8_t>& queries,
                       const KdSearchOptions& options, size_t k, uint32_t width,
                       size_t* found = nullptr) {
  const size_t nq = queries.size() / kDescriptorDim;
  std::vector<const uint8_t*> pointers(nq);
  for (size_t q = 0; q < nq; ++q) pointers[q] = queries.data() + q * kDescriptorDim;
  // Poisoned outputs: stale entries would show.
  std::vector<KdNeighbor> batch(nq * k, KdNeighbor{0xDEADBEEF, 0xDEADBEEF});
  std::vector<std::span<KdNeighbor>> outs(nq);
  for (size_t q = 0; q < nq; ++q) outs[q] = {batch.data() + q * k, k};
  std::vector<KdSearchResult> results(nq, KdSearchResult{77, 77, true});
  searcher.SearchBatch(pointers, options, outs, results, width);
  size_t mismatches = 0;
  std::vector<KdNeighbor> alone(k);
  for (size_t q = 0; q < nq; ++q) {
    const KdSearchResult r = searcher.Search(pointers[q], options, alone);
    const KdSearchResult& b = results[q];
    const bool same = r.num_neighbors == b.num_neighbors && r.checks == b.checks &&
                      r.corrupt == b.corrupt &&
                      std::equal(alone.begin(), alone.begin() + r.num_neighbors, outs[q].begin());
    mismatches += !same;
    if (found) *found += b.num_neighbors;
  }
  return mismatches;
}

TEST(KdForest, BatchEqualsOneAtATime) {
  const std::vector<uint8_t> data = ClusteredDescriptors(6000, 60, 20);
  const KdForest forest = Build(data);
  KdForestSearcher searcher(forest.View(data));
  // 60 near and 20 far queries: each of the 216 combinations below still runs batches of every
  // width (150 near took 32 s under qemu and 36 s under ASan).
  std::vector<uint8_t> queries = NearbyQueries(data, 60, 15);
  const std::vector<uint8_t> far = ClusteredDescriptors(20, 5, 60);
  queries.insert(queries.end(), far.begin(), far.end());
  // Exhaustive searches are slow: fewer of them (the last 8 near and the 20 far).
  const std::vector<uint8_t> few(queries.end() - 28 * kDescriptorDim, queries.end());
  std::vector<uint64_t> allowed(6000 / 64 + 1, 0);
  for (uint32_t row = 0; row < 6000; row += 3) allowed[row / 64] |= uint64_t{1} << (row % 64);
  for (uint32_t width : {1u, 3u, 8u}) {
    for (size_t k : {1, 2, 6}) {
      for (uint32_t budget : {32u, 256u, 6000u}) {  // 6000 >= N: exhaustive, exact
        for (uint32_t interleave : {1u, 4u}) {
          for (bool filter : {false, true}) {
            for (bool skip : {false, true}) {
              KdSearchOptions options;
              options.max_checks = budget;
              options.interleave = interleave;
              options.skip_range_checks = skip;
              if (filter) options.allowed_rows = allowed;
              const std::vector<uint8_t>& qs = budget >= 6000 ? few : queries;
              size_t found = 0;
              EXPECT_EQ(BatchMismatches(searcher, qs, options, k, width, &found), 0u)
                  << "width " << width << " k " << k << " budget " << budget << " interleave "
                  << interleave << " filter " << filter << " skip " << skip;
              // A filtered search may spend its budget before it finds k.
              if (filter) {
                EXPECT_GT(found, 0u);
              } else {
                EXPECT_EQ(found, k * qs.size() / kDescriptorDim);
              }
            }
          }
        }
      }
    }
  }
  // Fewer queries than the width, a single one, and none.
  KdSearchOptions options;
  const std::vector<uint8_t> two(queries.begin(), queries.begin() + 2 * kDescriptorDim);
  EXPECT_EQ(BatchMismatches(searcher, two, options, 6, 8), 0u);
  const std::vector<uint8_t> one(queries.begin(), queries.begin() + kDescriptorDim);
  EXPECT_EQ(BatchMismatches(searcher, one, options, 6, 8), 0u);
  EXPECT_EQ(BatchMismatches(searcher, {}, options, 6, 8), 0u);
  // Sizes that do not match are refused.
  std::vector<const uint8_t*> pointers(2, queries.data());
  std::vector<KdNeighbor> buffer(6);
  std::vector<std::span<KdNeighbor>> outs(1, std::span<KdNeighbor>(buffer));
  std::vector<KdSearchResult> results(2);
  EXPECT_THROW(searcher.SearchBatch(pointers, options, outs, results), std::invalid_argument);
}

TEST(KdForest, BuildIsDeterministic) {
  const std::vector<uint8_t> data = ClusteredDescriptors(30000, 100, 20);
  const KdForest a = Build(data, 5, 1);
  const KdForest b = Build(data, 5, 2);
  const KdForest c = Build(data, 5, 3);
  const KdForest d = Build(data, 6, 2);
  const auto same = [](const KdForest& x, const KdForest& y) {
    return x.roots == y.roots && x.leaves == y.leaves && x.nodes.size() == y.nodes.size() &&
           std::memcmp(x.nodes.data(), y.nodes.data(), x.nodes.size() * sizeof(KdNode)) == 0;
  };
  EXPECT_TRUE(same(a, b));
  EXPECT_TRUE(same(a, c));
  EXPECT_FALSE(same(a, d));
  // The trees differ from each other (random split dimensions).
  EXPECT_NE(std::vector<uint32_t>(a.leaves.begin(), a.leaves.begin() + 30000),
            std::vector<uint32_t>(a.leaves.begin() + 30000, a.leaves.begin() + 60000));
}

TEST(KdForest, ProgressReachesOne) {
  const std::vector<uint8_t> data = ClusteredDescriptors(20000, 50, 20);
  KdForestBuildOptions options;
  std::vector<double> reported;
  options.progress = [&](double f) { reported.push_back(f); };
  BuildKdForest(data, options);
  ASSERT_FALSE(reported.empty());
  EXPECT_TRUE(std::is_sorted(reported.begin(), reported.end()));
  EXPECT_DOUBLE_EQ(reported.back(), 1.0);
}

TEST(KdForest, DegenerateInputs) {
  std::string error;
  // Empty, one row, fewer rows than a bucket, and many identical rows (no dimension separates
  // them: buckets up to 255, larger groups cut in the middle).
  for (size_t n : {0, 1, 7}) {
    const std::vector<uint8_t> data = ClusteredDescriptors(n, 1, 3);
    const KdForest forest = Build(data);
    ASSERT_TRUE(ValidateKdForest(forest.View(data), &error)) << n << ": " << error;
    KdForestSearcher searcher(forest.View(data));
    std::vector<KdNeighbor> out(3);
    const uint8_t query[kDescriptorDim] = {};
    const KdSearchResult r = searcher.Search(query, KdSearchOptions{}, out);
    EXPECT_FALSE(r.corrupt);
    EXPECT_EQ(r.num_neighbors, std::min<size_t>(n, 3));
  }
  std::vector<uint8_t> same(1000 * kDescriptorDim, 17);
  same.resize(1003 * kDescriptorDim, 40);  // three different rows at the end
  const KdForest forest = Build(same);
  ASSERT_TRUE(ValidateKdForest(forest.View(same), &error)) << error;
  KdForestSearcher searcher(forest.View(same));
  std::vector<KdNeighbor> out(4);
  KdSearchOptions options;
  options.max_checks = 2000;
  const KdSearchResult r = searcher.Search(same.data() + 1000 * kDescriptorDim, options, out);
  ASSERT_EQ(r.num_neighbors, 4u);
  EXPECT_EQ(out[0], (KdNeighbor{1000, 0}));
  EXPECT_EQ(out[2], (KdNeighbor{1002, 0}));
  EXPECT_EQ(out[3], (KdNeighbor{0, 128u * 23u * 23u}));
}

class CorruptForest : public testing::Test {
 protected:
  void SetUp() override {
    data_ = ClusteredDescriptors(2000, 30, 20);
    forest_ = Build(data_);
    queries_ = NearbyQueries(data_, 5, 10);
  }
  // An exhaustive search reaches every node, so it must run into the corruption and report it
  // (and return no neighbours); a budgeted one may miss it but must then return real ones.
  bool SearchesReportCorrupt(GuardedForest& g) {
    KdForestSearcher searcher(g.View());
    std::vector<KdNeighbor> out(6);
    bool all = true;
    const size_t n = data_.size() / kDescriptorDim;
    for (uint32_t budget : {128u, 100000u}) {
      KdSearchOptions options;
      options.max_checks = budget;
      for (size_t q = 0; q < 5; ++q) {
        const uint8_t* query = queries_.data() + q * kDescriptorDim;
        const KdSearchResult r = searcher.Search(query, options, out);
        if (budget > n) all &= r.corrupt;
        if (r.corrupt) {
          all &= r.num_neighbors == 0;
          continue;
        }
        for (uint32_t j = 0; j < r.num_neighbors; ++j) {
          all &= out[j].index < n &&
                 out[j].distance == SquaredL2(query, data_.data() + out[j].index * kDescriptorDim);
        }
      }
    }
    return all;
  }
  std::string Validate(GuardedForest& g) {
    std::string error;
    return ValidateKdForest(g.View(), &error) ? std::string("(valid)") : error;
  }

  std::vector<uint8_t> data_;
  KdForest forest_;
  std::vector<uint8_t> queries_;
};

TEST_F(CorruptForest, ChildIndexOutOfRange) {
  GuardedForest g(forest_, data_);
  const size_t root = g.roots[0];
  g.nodes[root].index = uint32_t(g.nodes.size());
  EXPECT_NE(Validate(g).find("right child"), std::string::npos) << Validate(g);
  EXPECT_TRUE(SearchesReportCorrupt(g));
}

TEST_F(CorruptForest, ChildIndexPointingBackwards) {
  GuardedForest g(forest_, data_);
  const size_t inner = FirstInner(g.nodes.span(), g.roots[1]);
  g.nodes[inner].index = uint32_t(inner);  // a cycle
  EXPECT_NE(Validate(g).find("right child"), std::string::npos) << Validate(g);
  EXPECT_TRUE(SearchesReportCorrupt(g));
}

TEST_F(CorruptForest, LeafRangeOutOfBounds) {
  GuardedForest g(forest_, data_);
  // The last leaf of the last tree, pushed past the end of the leaves array.
  size_t leaf = g.nodes.size() - 1;
  while (g.nodes[leaf].dim != kKdLeaf) --leaf;
  g.nodes[leaf].index = uint32_t(g.leaves.size() - 2);
  g.nodes[leaf].low = 8;
  EXPECT_NE(Validate(g).find("leaf bucket"), std::string::npos) << Validate(g);
  EXPECT_TRUE(SearchesReportCorrupt(g));
}

TEST_F(CorruptForest, ViewIndexNotBelowN) {
  GuardedForest g(forest_, data_);
  const size_t leaf = FirstLeaf(g.nodes.span(), g.roots[2]);
  g.leaves[g.nodes[leaf].index] = 2000;  // == N: one row past the descriptor matrix
  EXPECT_NE(Validate(g).find("not a descriptor index"), std::string::npos) << Validate(g);
  EXPECT_TRUE(SearchesReportCorrupt(g));
  g.leaves[g.nodes[leaf].index] = 0xFFFFFFFFu;
  EXPECT_TRUE(SearchesReportCorrupt(g));
}

TEST_F(CorruptForest, BadSplitDimensionAndRoot) {
  {
    GuardedForest g(forest_, data_);
    g.nodes[FirstInner(g.nodes.span())].dim = 200;
    EXPECT_NE(Validate(g).find("split dimension"), std::string::npos) << Validate(g);
    EXPECT_TRUE(SearchesReportCorrupt(g));
  }
  {
    GuardedForest g(forest_, data_);
    g.roots[3] = uint32_t(g.nodes.size());
    EXPECT_NE(Validate(g).find("roots[3]"), std::string::npos) << Validate(g);
    EXPECT_TRUE(SearchesReportCorrupt(g));
  }
}

TEST_F(CorruptForest, ValidateRejectsSharingAndDuplicates) {
  {
    GuardedForest g(forest_, data_);
    const size_t leaf = FirstLeaf(g.nodes.span());
    g.leaves[g.nodes[leaf].index] = g.leaves[g.nodes[leaf].index + 1];
    EXPECT_NE(Validate(g).find("appears twice"), std::string::npos) << Validate(g);
  }
  {
    GuardedForest g(forest_, data_);
    const size_t leaf = FirstLeaf(g.nodes.span());
    g.nodes[leaf].index += 1;  // buckets overlap
    EXPECT_NE(Validate(g).find("tile"), std::string::npos) << Validate(g);
  }
}

TEST(KdForestCorrupt, SharedSubtreesCannotExplodeTheSearch) {
  // A hand-made DAG: node i has children i+1 and i+2, so there are ~fib(60) root-to-leaf
  // paths. A tree walk would never finish; the search must stop and report corruption.
  constexpr uint32_t kChain = 60;
  std::vector<KdNode> nodes;
  for (uint32_t i = 0; i < kChain; ++i) nodes.push_back(KdNode{i + 2, 0, 0, 0, 0});
  nodes.push_back(KdNode{0, kKdLeaf, 1, 0, 0});
  nodes.push_back(KdNode{0, kKdLeaf, 1, 0, 0});
  const std::vector<uint32_t> roots{0}, leaves{0};
  const std::vector<uint8_t> data(kDescriptorDim, 0);
  const KdForestView view{nodes, roots, leaves, data};
  std::string error;
  EXPECT_FALSE(ValidateKdForest(view, &error));
  KdForestSearcher searcher(view);
  std::vector<KdNeighbor> out(1);
  for (uint32_t budget : {128u, 1000u}) {
    KdSearchOptions options;
    options.max_checks = budget;
    out.resize(budget == 128 ? 2 : 1);  // 2 can never be filled: the walk goes on and on
    const KdSearchResult r = searcher.Search(data.data(), options, out);
    EXPECT_TRUE(r.corrupt);
  }
}

TEST_F(CorruptForest, RandomByteFlipsNeverReadOutOfBounds) {
  // Each round flips a few random bytes anywhere in the forest's arrays. The arrays sit against
  // guard pages, so an out-of-bounds read would crash this test. A search either reports
  // corruption or returns real neighbours (indices < N with their true distances).
  auto& rng = test::Rng();
  const size_t n = data_.size() / kDescriptorDim;
  size_t corrupt_searches = 0, ok_searches = 0;
  for (int round = 0; round < 150; ++round) {
    GuardedForest g(forest_, data_);
    auto* node_bytes = reinterpret_cast<uint8_t*>(g.nodes.data());
    auto* leaf_bytes = reinterpret_cast<uint8_t*>(g.leaves.data());
    auto* root_bytes = reinterpret_cast<uint8_t*>(g.roots.data());
    const int flips = 1 + int(rng() % 8);
    for (int f = 0; f < flips; ++f) {
      const uint8_t value = uint8_t(rng());
      switch (rng() % 6) {
        case 0:
          root_bytes[rng() % (g.roots.size() * 4)] = value;
          break;
        case 1:
        case 2:
          leaf_bytes[rng() % (g.leaves.size() * 4)] = value;
          break;
        default:
          node_bytes[rng() % (g.nodes.size() * sizeof(KdNode))] = value;
      }
    }
    std::string error;
    const bool valid = ValidateKdForest(g.View(), &error);  // must not crash either
    KdForestSearcher searcher(g.View());
    std::vector<KdNeighbor> out(6);
    for (uint32_t budget : {64u, 5000u}) {
      KdSearchOptions options;
      options.max_checks = budget;
      for (size_t q = 0; q < 2; ++q) {
        const uint8_t* query = queries_.data() + q * kDescriptorDim;
        const KdSearchResult r = searcher.Search(query, options, out);
        if (r.corrupt) {
          ++corrupt_searches;
          EXPECT_EQ(r.num_neighbors, 0u);
          EXPECT_FALSE(valid) << "the search found a problem that validation missed";
          continue;
        }
        ++ok_searches;
        ASSERT_LE(r.num_neighbors, 6u);
        for (uint32_t j = 0; j < r.num_neighbors; ++j) {
          ASSERT_LT(out[j].index, n);
          ASSERT_EQ(out[j].distance,
                    SquaredL2(query, data_.data() + out[j].index * kDescriptorDim));
          if (j > 0) {
            ASSERT_LE(out[j - 1].distance, out[j].distance);
          }
        }
      }
    }
  }
  std::cout << corrupt_searches << " searches reported corruption, " << ok_searches
            << " returned (valid) neighbours\n";
  EXPECT_GT(corrupt_searches, 0u);
}

TEST_F(CorruptForest, BatchReportsCorruptionPerQueryLikeAlone) {
  // Some queries of a batch run into the damage and some do not (a budgeted search may miss
  // it): each must get the flag it gets alone.
  const std::vector<uint8_t> queries = NearbyQueries(data_, 60, 10);
  auto check = [&](GuardedForest& g, const char* what) {
    KdForestSearcher searcher(g.View());
    for (uint32_t budget : {64u, 128u, 100000u}) {
      for (uint32_t width : {1u, 3u, 8u}) {
        KdSearchOptions options;  // range-checked: unchecked reads of a corrupt forest are unsafe
        options.max_checks = budget;
        EXPECT_EQ(BatchMismatches(searcher, queries, options, 6, width), 0u)
            << what << " budget " << budget << " width " << width;
      }
    }
  };
  size_t corrupt = 0, clean = 0;
  auto count = [&](GuardedForest& g) {
    KdForestSearcher searcher(g.View());
    KdSearchOptions options;
    options.max_checks = 64;
    std::vector<KdNeighbor> out(6);
    for (size_t q = 0; q < 60; ++q) {
      (searcher.Search(queries.data() + q * kDescriptorDim, options, out).corrupt ? corrupt
                                                                                  : clean)++;
    }
  };
  {
    GuardedForest g(forest_, data_);
    g.nodes[g.roots[0]].index = uint32_t(g.nodes.size());
    check(g, "child out of range");
  }
  {
    GuardedForest g(forest_, data_);
    const size_t leaf = FirstLeaf(g.nodes.span(), g.roots[2]);
    g.leaves[g.nodes[leaf].index] = 2000;
    check(g, "view index");
    count(g);
  }
  {
    GuardedForest g(forest_, data_);
    g.roots[3] = uint32_t(g.nodes.size());
    check(g, "root");
  }
  // The view-index damage is met by some budgeted searches and missed by others: the batch
  // mixes both kinds.
  EXPECT_GT(corrupt, 0u);
  EXPECT_GT(clean, 0u);
}

}  // namespace
}  // namespace cwloc
