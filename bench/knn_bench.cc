// cwloc-knn-bench: FLANN 1.9's randomized kd-trees (the paper's matcher) against our flat
// kd-forest, in one process on the same descriptors and queries. Prints build time, index
// memory, thread-CPU microseconds per query (median of --reps passes over all queries, one
// thread; the passes of all methods interleaved), recall of the true 1st and 2nd neighbours
// (exact brute force on a query subset) and the speed ratio against FLANN.
// docs/kd_forest.md records results with the commands.
//
// Data: a COLMAP database.db (--database; query images from --query-list, else every 5th
// image), or generated SIFT-like descriptors (--synthetic N; see GenerateSynthetic).

#include <sqlite3.h>
#include <sys/mman.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <flann/flann.hpp>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "base/comma_list.h"
#include "base/split_mix64.h"
#include "base/stopwatch.h"
#include "kdtree/descriptor_distance.h"
#include "kdtree/kd_forest.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {
namespace {

struct Dataset {
  std::string description;
  std::vector<uint8_t> base;     // N x 128
  std::vector<uint8_t> queries;  // Q x 128
  size_t NumBase() const { return base.size() / kDescriptorDim; }
  size_t NumQueries() const { return queries.size() / kDescriptorDim; }
};

// ---------------------------------------------------------------------------------------------
// COLMAP database

[[noreturn]] void Fail(const std::string& message) {
  std::cerr << "cwloc-knn-bench: " << message << "\n";
  std::exit(2);
}

Dataset LoadColmapDatabase(const std::string& path, const std::string& query_list) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    Fail(path + ": cannot open as SQLite: " + (db ? sqlite3_errmsg(db) : "out of memory"));
  }
  auto prepare = [&](const char* sql) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) != SQLITE_OK) {
      Fail(path + ": " + sql + ": " + sqlite3_errmsg(db));
    }
    return stmt;
  };
  std::map<int64_t, std::string> names;
  sqlite3_stmt* stmt = prepare("SELECT image_id, name FROM images");
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    const unsigned char* name = sqlite3_column_text(stmt, 1);
    names[sqlite3_column_int64(stmt, 0)] = name ? reinterpret_cast<const char*>(name) : "";
  }
  sqlite3_finalize(stmt);

  std::set<std::string> query_names;
  if (!query_list.empty()) {
    std::ifstream in(query_list);
    if (!in) Fail(query_list + ": cannot open");
    for (std::string line; std::getline(in, line);) {
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      if (!line.empty()) query_names.insert(line);
    }
  } else {
    // Every 5th image (in name order) is a query, like the shared data sets' held-out images.
    std::vector<std::string> sorted;
    for (const auto& [id, name] : names) sorted.push_back(name);
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 2; i < sorted.size(); i += 5) query_names.insert(sorted[i]);
  }

  Dataset data;
  size_t base_images = 0, query_images = 0;
  stmt = prepare("SELECT image_id, rows, cols, data FROM descriptors ORDER BY image_id");
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    const int64_t image_id = sqlite3_column_int64(stmt, 0);
    const int64_t rows = sqlite3_column_int64(stmt, 1);
    const int64_t cols = sqlite3_column_int64(stmt, 2);
    const void* blob = sqlite3_column_blob(stmt, 3);
    const int64_t bytes = sqlite3_column_bytes(stmt, 3);
    if (rows == 0) continue;
    if (cols != 128 || rows < 0 || bytes != rows * cols || !blob) {
      Fail(path + ": descriptors of image_id " + std::to_string(image_id) +
           ": rows=" + std::to_string(rows) + " cols=" + std::to_string(cols) + " blob=" +
           std::to_string(bytes) + " bytes, expected cols=128 and rows*128 bytes of uint8");
    }
    const auto it = names.find(image_id);
    const bool is_query = it != names.end() && query_names.count(it->second);
    std::vector<uint8_t>& out = is_query ? data.queries : data.base;
    const uint8_t* p = static_cast<const uint8_t*>(blob);
    out.insert(out.end(), p, p + bytes);
    ++(is_query ? query_images : base_images);
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  if (data.base.empty() || data.queries.empty()) {
    Fail(path + ": need descriptors of both base and query images (found " +
         std::to_string(base_images) + " base and " + std::to_string(query_images) +
         " query images)");
  }
  data.description = "COLMAP SIFT from " + path + ": " + std::to_string(base_images) +
                     " base images, " + std::to_string(query_images) + " query images";
  return data;
}

// ---------------------------------------------------------------------------------------------
// Generated SIFT-like descriptors

// SplitMix64 with float draws.
class Rng {
 public:
  explicit Rng(uint64_t seed) : bits_(seed) {}
  uint64_t Next() { return bits_.Next(); }
  float Uniform() { return float(Next() >> 40) * 0x1.0p-24f; }  // [0, 1)
  // Sum of four uniforms, rescaled: an approximately standard normal, cheap enough for 10^9.
  float Normal() {
    const uint64_t r = Next();
    const float s =
        float(r & 0xFFFF) + float((r >> 16) & 0xFFFF) + float((r >> 32) & 0xFFFF) + float(r >> 48);
    return (s * (1.0f / 65536.0f) - 2.0f) * 1.7320508f;
  }

 private:
  SplitMix64 bits_;
};

using Vec = std::array<float, kDescriptorDim>;

// SIFT's normalization: unit L2, clamp at 0.2, unit L2 again.
void SiftNormalize(Vec& v) {
  for (int pass = 0; pass < 2; ++pass) {
    float norm = 0;
    for (float& x : v) {
      x = std::max(x, 0.0f);
      norm += x * x;
    }
    norm = std::sqrt(std::max(norm, 1e-12f));
    for (float& x : v) x = std::min(x / norm, pass == 0 ? 0.2f : 1.0f);
  }
}

void Quantize(const Vec& v, uint8_t* out) {  // COLMAP: round(512 x), clamped to 255
  for (size_t d = 0; d < kDescriptorDim; ++d) {
    out[d] = uint8_t(std::min(255.0f, 512.0f * v[d] + 0.5f));  // v >= 0
  }
}

// A three-level hierarchy imitating what makes SIFT matching hard: motifs (repeated structure:
// windows, bricks) -> 3D points (instances of a motif) -> views (re-detections of a point).
// A motif is a sparse non-negative histogram (35% zero bins, exponential magnitudes). Each
// point adds noise of L2 norm ~0.55 to its motif, each view ~0.30 to its point (unit domain;
// x512 in uint8 units, so two views of a point are ~200 apart, like true SIFT matches, and
// points of one motif ~300). Base descriptors are 2..6 views of each point; queries are new
// views, 70% of base points and 30% of unseen points of the same motifs (distractors).
Dataset GenerateSynthetic(size_t num_base, size_t num_queries, uint64_t seed, uint32_t threads) {
  constexpr float kPointNoise = 0.55f / 11.3137f;  // per dimension: norm / sqrt(128)
  constexpr float kViewNoise = 0.30f / 11.3137f;
  constexpr size_t kPointsPerMotif = 20;
  Dataset data;
  // Points and their view counts, decided serially (cheap); descriptors in parallel.
  Rng rng(seed);
  std::vector<uint32_t> point_views;
  size_t total = 0;
  while (total < num_base) {
    const uint32_t views = 2 + uint32_t(rng.Next() % 5);
    point_views.push_back(uint32_t(std::min<size_t>(views, num_base - total)));
    total += point_views.back();
  }
  const size_t num_points = point_views.size();
  const size_t num_new_points = num_queries * 3 / 10 + 1;
  const size_t num_all_points = num_points + num_new_points;
  const size_t num_motifs = num_all_points / kPointsPerMotif + 1;
  std::vector<size_t> first_view(num_points + 1, 0);
  for (size_t p = 0; p < num_points; ++p) first_view[p + 1] = first_view[p] + point_views[p];

  auto motif = [&](size_t m, Vec& v) {
    Rng r(seed ^ (0x6d6f746966ULL + m * 0x100000001b3ULL));
    for (float& x : v) x = r.Uniform() < 0.35f ? 0.0f : -std::log(1.0f - r.Uniform());
    SiftNormalize(v);
  };
  auto point = [&](size_t p, Vec& v) {
    Rng r(seed ^ (0x706f696e74ULL + p * 0x9e3779b97f4a7c15ULL));
    motif(r.Next() % num_motifs, v);
    for (float& x : v) x += kPointNoise * r.Normal();
    SiftNormalize(v);
  };
  auto view = [&](const Vec& point_vec, uint64_t view_seed, uint8_t* out) {
    Rng r(view_seed);
    Vec v = point_vec;
    for (float& x : v) x += kViewNoise * r.Normal();
    SiftNormalize(v);
    Quantize(v, out);
  };

  data.base.resize(num_base * kDescriptorDim);
  data.queries.resize(num_queries * kDescriptorDim);
  std::atomic<size_t> next{0};
  constexpr size_t kChunk = 4096;
  auto work = [&] {
    Vec pv;
    for (size_t begin; (begin = next.fetch_add(kChunk)) < num_points;) {
      for (size_t p = begin; p < std::min(num_points, begin + kChunk); ++p) {
        point(p, pv);
        for (size_t i = first_view[p]; i < first_view[p + 1]; ++i) {
          view(pv, seed ^ (0x76696577ULL + i * 0xd6e8feb86659fd93ULL),
               data.base.data() + i * kDescriptorDim);
        }
      }
    }
  };
  std::vector<std::thread> pool;
  for (uint32_t t = 1; t < std::max(1u, threads); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  Rng qrng(seed ^ 0x7175657279ULL);
  Vec pv;
  for (size_t q = 0; q < num_queries; ++q) {
    const bool seen = qrng.Uniform() < 0.7f;
    const size_t p = seen ? qrng.Next() % num_points : num_points + qrng.Next() % num_new_points;
    point(p, pv);
    view(pv, qrng.Next(), data.queries.data() + q * kDescriptorDim);
  }
  // Base rows stay grouped by point, as an index groups them by image.
  data.description = "generated SIFT-like: " + std::to_string(num_base) + " base (" +
                     std::to_string(num_points) + " points, " + std::to_string(num_motifs) +
                     " motifs), " + std::to_string(num_queries) + " queries";
  return data;
}

// ---------------------------------------------------------------------------------------------
// Ground truth and measurement

struct TrueNeighbors {
  uint32_t first, second;
};

std::vector<TrueNeighbors> BruteForce(const Dataset& data, size_t num_queries, uint32_t threads) {
  std::vector<TrueNeighbors> truth(num_queries);
  const DistanceFunctions& dist = BestDistanceFunctions();
  std::atomic<size_t> next{0};
  auto work = [&] {
    const size_t n = data.NumBase();
    for (size_t q; (q = next.fetch_add(1)) < num_queries;) {
      const uint8_t* query = data.queries.data() + q * kDescriptorDim;
      std::pair<uint32_t, uint32_t> best{UINT32_MAX, 0}, second{UINT32_MAX, 0};
      for (size_t i = 0; i < n; ++i) {
        const std::pair<uint32_t, uint32_t> c{
            dist.one(query, data.base.data() + i * kDescriptorDim), uint32_t(i)};
        if (c < second) {
          second = c;
          if (second < best) std::swap(best, second);
        }
      }
      truth[q] = TrueNeighbors{best.second, second.second};
    }
  };
  std::vector<std::thread> pool;
  for (uint32_t t = 1; t < std::max(1u, threads); ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  return truth;
}

struct Row {
  std::string method;
  double build_s = 0;
  double memory_mb = 0;
  double us_per_query = 0;
  double recall1 = 0, recall2 = 0;
  double checks = 0;         // mean distance computations per query (ours)
  double us_unchecked = -1;  // same search without the range checks
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// CPU time of this thread: on a shared machine it leaves out the time other processes hold
// the core (their cache pollution still counts).
double ThreadSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// CPU time of all threads of the process.
double ProcessCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// One timed pass of `search(i)` for i < calls (a query each, or a batch each) over
// num_queries queries: thread-CPU µs per query.
template <typename Search>
double TimeQueries(size_t calls, size_t num_queries, Search&& search) {
  const double start = ThreadSeconds();
  for (size_t i = 0; i < calls; ++i) search(i);
  return (ThreadSeconds() - start) * 1e6 / double(num_queries);
}

void Recall(const std::vector<TrueNeighbors>& truth, const std::vector<uint32_t>& found, int k,
            Row* row) {
  size_t hits1 = 0, hits2 = 0;
  for (size_t q = 0; q < truth.size(); ++q) {
    const uint32_t* f = found.data() + q * k;
    hits1 += std::find(f, f + k, truth[q].first) != f + k;
    hits2 += std::find(f, f + k, truth[q].second) != f + k;
  }
  row->recall1 = double(hits1) / double(truth.size());
  row->recall2 = double(hits2) / double(truth.size());
}

void PrintTable(const std::vector<Row>& rows, double flann_us) {
  std::printf("\n| %-34s | %8s | %9s | %9s | %8s | %8s | %8s | %9s | %9s |\n", "method", "build s",
              "index MB", "us/query", "recall@1", "recall@2", "dist/q", "vs FLANN", "unchecked");
  std::printf("|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n", std::string(36, '-').c_str(),
              std::string(10, '-').c_str(), std::string(11, '-').c_str(),
              std::string(11, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(10, '-').c_str(),
              std::string(11, '-').c_str(), std::string(11, '-').c_str());
  for (const Row& r : rows) {
    char ratio[32] = "-";
    if (flann_us > 0) std::snprintf(ratio, sizeof(ratio), "%.2fx", flann_us / r.us_per_query);
    char unchecked[32] = "-";
    if (r.us_unchecked > 0) std::snprintf(unchecked, sizeof(unchecked), "%.2f", r.us_unchecked);
    char checks[32] = "-";
    if (r.checks > 0) std::snprintf(checks, sizeof(checks), "%.0f", r.checks);
    std::printf("| %-34s | %8.2f | %9.1f | %9.2f | %8.4f | %8.4f | %8s | %9s | %9s |\n",
                r.method.c_str(), r.build_s, r.memory_mb, r.us_per_query, r.recall1, r.recall2,
                checks, ratio, unchecked);
  }
}

// The command line.
struct BenchFlags {
  std::string database, query_list, checks_text = "64,128,256", kernel_name;
  size_t synthetic = 2000000, num_queries = 20000, gt_queries = 2000;
  uint32_t trees = 4, leaf_size = 8, threads = 0, flann_checks = 128, interleave = 4;
  std::string batch_text = "0";
  size_t batch_chunk = 256;
  int k = 6, reps = 3;
  uint64_t seed = 1;
  bool no_flann = false, build_only = false, hugepages = false;
};

void AddFlags(CLI::App* app, BenchFlags* f) {
  app->add_option("--database", f->database, "COLMAP database.db to read SIFT descriptors from");
  app->add_option("--query-list", f->query_list,
                  "image names (one a line) whose descriptors are the queries; default: every "
                  "5th image of --database");
  app->add_option("--synthetic,--base-size", f->synthetic,
                  "number of generated base descriptors when no --database is given");
  app->add_option("--queries", f->num_queries, "query descriptors timed (a random subset)");
  app->add_option("--gt-queries", f->gt_queries,
                  "queries with brute-force ground truth for recall");
  app->add_option("--trees", f->trees, "trees in both forests");
  app->add_option("--leaf-size", f->leaf_size, "our forest's maximum leaf bucket");
  app->add_option("--checks", f->checks_text, "our forest's check budgets, comma-separated");
  app->add_option("--flann-checks", f->flann_checks, "FLANN's checks (the paper: 128)");
  app->add_option("-k", f->k, "neighbours per query (the paper: k+1 = 6)");
  app->add_option("--reps", f->reps, "timed repetitions (median is reported)");
  app->add_option("--threads", f->threads,
                  "threads for our build, data generation and brute force "
                  "(0 = all cores; searches are single-threaded)");
  app->add_option("--seed", f->seed, "seed for data generation, query sampling and our build");
  app->add_option("--kernel", f->kernel_name,
                  "distance kernel: scalar, avx2, avx512, avx512vnni, neon, neon-dotprod");
  app->add_option("--interleave", f->interleave,
                  "descents our search keeps in flight (1 = FLANN order)");
  app->add_option("--batch", f->batch_text,
                  "also time our forest with SearchBatch at these widths (searches in flight), "
                  "comma-separated; 0 or 1 = one at a time only");
  app->add_option("--batch-chunk", f->batch_chunk,
                  "queries per SearchBatch call (the localizer's forward matching calls it with "
                  "as many queries as the width)");
  app->add_flag("--no-flann", f->no_flann, "skip FLANN");
  app->add_flag("--hugepages", f->hugepages,
                "put the base descriptors on transparent huge pages (both methods)");
  app->add_flag("--build-only", f->build_only, "only build our forest and report time and memory");
}

// --kernel's distance functions, else the best this CPU has.
const DistanceFunctions* KernelNamed(const std::string& kernel_name) {
  if (kernel_name.empty()) return &BestDistanceFunctions();
  const std::map<std::string, DistanceKernel> kernels{
      {"scalar", DistanceKernel::kScalar}, {"avx2", DistanceKernel::kAvx2},
      {"avx512", DistanceKernel::kAvx512}, {"avx512vnni", DistanceKernel::kAvx512Vnni},
      {"neon", DistanceKernel::kNeon},     {"neon-dotprod", DistanceKernel::kNeonDotProd}};
  const auto it = kernels.find(kernel_name);
  if (it == kernels.end()) Fail("unknown --kernel " + kernel_name);
  const DistanceFunctions* distance = DistanceFunctionsFor(it->second);
  if (!distance) Fail("this CPU does not support --kernel " + kernel_name);
  return distance;
}

// Keeps a random subset of `count` queries, in random order (the localizer shuffles its
// features too).
void PickQueries(size_t count, uint64_t seed, Dataset* data) {
  std::vector<size_t> order(data->NumQueries());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(seed));
  order.resize(std::min(order.size(), count));
  std::vector<uint8_t> picked(order.size() * kDescriptorDim);
  for (size_t i = 0; i < order.size(); ++i) {
    std::memcpy(picked.data() + i * kDescriptorDim,
                data->queries.data() + order[i] * kDescriptorDim, kDescriptorDim);
  }
  data->queries.swap(picked);
}

using HugeBuffer = std::unique_ptr<uint8_t, std::function<void(uint8_t*)>>;

// A copy of `bytes` on transparent huge pages: a random row then costs no page walk (the index
// file is mapped with 4 KB pages unless copied like this).
HugeBuffer OnHugePages(std::span<const uint8_t> bytes) {
  constexpr size_t k2M = size_t(1) << 21;
  const size_t size = (bytes.size() + k2M - 1) / k2M * k2M;
  void* p = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) Fail("mmap for --hugepages failed");
  if (madvise(p, size, MADV_HUGEPAGE) != 0) std::printf("madvise(MADV_HUGEPAGE) failed\n");
  HugeBuffer huge = {static_cast<uint8_t*>(p), [size](uint8_t* q) { munmap(q, size); }};
  std::memcpy(huge.get(), bytes.data(), bytes.size());
  return huge;
}

// Our forest over `base`, its build's seconds in `build_s`; prints its build, checksum and
// validation.
KdForest BuildOurForest(std::span<const uint8_t> base, const BenchFlags& flags, double* build_s) {
  KdForestBuildOptions build_options;
  build_options.num_trees = flags.trees;
  build_options.max_leaf_size = flags.leaf_size;
  build_options.seed = flags.seed;
  build_options.num_threads = flags.threads;
  Stopwatch stopwatch;
  const double build_cpu_start = ProcessCpuSeconds();
  KdForest forest = BuildKdForest(base, build_options);
  *build_s = stopwatch.Seconds();
  const double build_cpu_s = ProcessCpuSeconds() - build_cpu_start;
  uint64_t checksum = 0xcbf29ce484222325ULL;  // FNV-1a of the arrays: same data+seed, same forest
  auto hash = [&checksum](const void* p, size_t bytes) {
    for (size_t i = 0; i < bytes; ++i) {
      checksum = (checksum ^ static_cast<const uint8_t*>(p)[i]) * 0x100000001b3ULL;
    }
  };
  hash(forest.nodes.data(), forest.nodes.size() * sizeof(KdNode));
  hash(forest.leaves.data(), forest.leaves.size() * sizeof(uint32_t));
  hash(forest.roots.data(), forest.roots.size() * sizeof(uint32_t));
  const size_t n = base.size() / kDescriptorDim;
  std::printf(
      "our build: %.2f s wall, %.2f s CPU, %zu nodes, %.1f MB (%.2f bytes/descriptor), "
      "checksum %016llx\n",
      *build_s, build_cpu_s, forest.nodes.size(), double(forest.MemoryBytes()) / 1e6,
      double(forest.MemoryBytes()) / double(std::max<size_t>(n, 1)),
      static_cast<unsigned long long>(checksum));
  stopwatch.Restart();
  std::string error;
  if (!ValidateKdForest(forest.View(base), &error)) Fail("our forest does not validate: " + error);
  std::printf("ValidateKdForest: %.3f s\n", stopwatch.Seconds());
  return forest;
}

// The methods compared, each a row plus a search function; the timed passes of all methods are
// interleaved (rep 1 of each, rep 2 of each, ...) so that load drift on a shared machine hits
// them alike, and the median pass is reported.
struct Methods {
  std::vector<Row> rows;
  std::vector<std::function<void(size_t)>> timed;
  std::vector<size_t> timed_calls;  // calls of timed[m] per pass
  // rows[checked_row[i]] times in timed[unchecked_row[i] - 1], without the range checks in
  // timed[unchecked_row[i]].
  std::vector<size_t> checked_row, unchecked_row;
};

// FLANN's index and the buffers of one query's search.
struct FlannSearch {
  std::unique_ptr<flann::Index<flann::L2<unsigned char>>> index;
  std::vector<size_t> indices;
  std::vector<float> dists;
};

// FLANN's row: builds its index over `base` and measures its recall.
void AddFlann(const BenchFlags& flags, std::span<const uint8_t> base, const Dataset& data,
              const std::vector<TrueNeighbors>& truth, size_t nq, FlannSearch* flann,
              Methods* methods) {
  const int k = flags.k;
  const size_t gt_queries = truth.size();
  const flann::SearchParams flann_params{int(flags.flann_checks)};
  flann->indices.resize(k);
  flann->dists.resize(k);
  Row row;
  row.method = "FLANN 1.9 kd " + std::to_string(flags.trees) + " trees, " +
               std::to_string(flags.flann_checks) + " checks";
  const size_t n = base.size() / kDescriptorDim;
  flann::Matrix<unsigned char> dataset(const_cast<uint8_t*>(base.data()), n, kDescriptorDim);
  flann->index = std::make_unique<flann::Index<flann::L2<unsigned char>>>(
      dataset, flann::KDTreeIndexParams(int(flags.trees)));
  Stopwatch stopwatch;
  flann->index->buildIndex();
  row.build_s = stopwatch.Seconds();
  // FLANN's pools plus its array of row pointers (the descriptors themselves are shared).
  row.memory_mb = (double(flann->index->usedMemory()) + double(n) * sizeof(void*)) / 1e6;
  std::printf("FLANN build: %.2f s\n", row.build_s);
  std::fflush(stdout);
  auto search = [&data, flann, k, flann_params](size_t q) {
    flann::Matrix<unsigned char> query(
        const_cast<uint8_t*>(data.queries.data()) + q * kDescriptorDim, 1, kDescriptorDim);
    flann::Matrix<size_t> idx(flann->indices.data(), 1, k);
    flann::Matrix<float> dst(flann->dists.data(), 1, k);
    flann->index->knnSearch(query, idx, dst, k, flann_params);
  };
  std::vector<uint32_t> f(gt_queries * k);
  for (size_t q = 0; q < gt_queries; ++q) {
    search(q);
    for (int j = 0; j < k; ++j) f[q * k + j] = uint32_t(flann->indices[j]);
  }
  Recall(truth, f, k, &row);
  methods->rows.push_back(row);
  methods->timed.push_back(search);
  methods->timed_calls.push_back(nq);
}

// Our searches one at a time, per budget: what the batched searches must equal.
struct AloneResults {
  std::vector<std::vector<KdNeighbor>> neighbors;
  std::vector<std::vector<KdSearchResult>> results;
};

// Our forest's rows, a budget each: its recall and checks, timed with and without the range
// checks.
void AddOurForest(const BenchFlags& flags, const std::vector<uint32_t>& budgets, double build_s,
                  const KdForest& forest, KdForestSearcher& searcher, std::vector<KdNeighbor>& out,
                  const Dataset& data, const std::vector<TrueNeighbors>& truth, size_t nq,
                  AloneResults* alone, Methods* methods) {
  const int k = flags.k;
  const size_t gt_queries = truth.size();
  alone->neighbors.resize(budgets.size());
  alone->results.resize(budgets.size());
  for (size_t b = 0; b < budgets.size(); ++b) {
    Row row;
    row.method = "flat kd-forest " + std::to_string(flags.trees) + " trees, " +
                 std::to_string(budgets[b]) + " checks";
    row.build_s = build_s;
    row.memory_mb = double(forest.MemoryBytes()) / 1e6;
    KdSearchOptions options;
    options.max_checks = budgets[b];
    options.interleave = flags.interleave;
    std::vector<uint32_t> f(gt_queries * k, UINT32_MAX);
    uint64_t total_checks = 0;
    alone->neighbors[b].resize(nq * k);
    alone->results[b].resize(nq);
    for (size_t q = 0; q < nq; ++q) {
      const KdSearchResult r =
          searcher.Search(data.queries.data() + q * kDescriptorDim, options, out);
      if (r.corrupt) Fail("search reported a corrupt forest");
      std::copy(out.begin(), out.end(), alone->neighbors[b].begin() + q * k);
      alone->results[b][q] = r;
      total_checks += r.checks;
      if (q < gt_queries) {
        for (uint32_t j = 0; j < r.num_neighbors; ++j) f[q * k + j] = out[j].index;
      }
    }
    row.checks = double(total_checks) / double(nq);
    Recall(truth, f, k, &row);
    methods->checked_row.push_back(methods->rows.size());
    methods->rows.push_back(row);
    methods->timed.push_back([&searcher, &out, &data, options](size_t q) {
      searcher.Search(data.queries.data() + q * kDescriptorDim, options, out);
    });
    methods->timed_calls.push_back(nq);
    KdSearchOptions unchecked = options;
    unchecked.skip_range_checks = true;
    methods->unchecked_row.push_back(methods->timed.size());
    methods->timed.push_back([&searcher, &out, &data, unchecked](size_t q) {
      searcher.Search(data.queries.data() + q * kDescriptorDim, unchecked, out);
    });
    methods->timed_calls.push_back(nq);
  }
}

// SearchBatch's calls: `chunk` queries per call into a reused output buffer, as a caller would.
struct BatchBuffers {
  BatchBuffers(const Dataset& data, size_t nq, size_t batch_chunk, int k)
      : query_ptrs(nq),
        chunk(std::min(batch_chunk, std::max<size_t>(nq, 1))),
        num_chunks((nq + chunk - 1) / chunk),
        out(chunk * k),
        spans(chunk),
        results(chunk) {
    for (size_t q = 0; q < nq; ++q) query_ptrs[q] = data.queries.data() + q * kDescriptorDim;
    for (size_t i = 0; i < chunk; ++i) spans[i] = {out.data() + i * k, size_t(k)};
  }

  std::vector<const uint8_t*> query_ptrs;
  size_t chunk, num_chunks;
  std::vector<KdNeighbor> out;
  std::vector<std::span<KdNeighbor>> spans;
  std::vector<KdSearchResult> results;
};

// Batched: the same searches, `width` in flight, checked bit for bit against the
// one-at-a-time results; a row per width and budget.
void AddBatched(const BenchFlags& flags, const std::vector<uint32_t>& widths,
                const std::vector<uint32_t>& budgets, KdForestSearcher& searcher, size_t nq,
                const AloneResults& alone, BatchBuffers& batch, Methods* methods) {
  const int k = flags.k;
  const size_t chunk = batch.chunk, num_chunks = batch.num_chunks;
  for (const uint32_t width : widths) {
    for (size_t b = 0; b < budgets.size(); ++b) {
      // Recall and checks: equal to the one-at-a-time row.
      Row row = methods->rows[methods->checked_row[b]];
      row.method =
          "  batch " + std::to_string(width) + " x " + std::to_string(budgets[b]) + " checks";
      KdSearchOptions options;
      options.max_checks = budgets[b];
      options.interleave = flags.interleave;
      auto run = [&searcher, &batch, nq, chunk, width](const KdSearchOptions& o, size_t c) {
        const size_t begin = c * chunk, count = std::min(chunk, nq - begin);
        searcher.SearchBatch(std::span(batch.query_ptrs).subspan(begin, count), o,
                             std::span<const std::span<KdNeighbor>>(batch.spans).first(count),
                             std::span(batch.results).first(count), width);
      };
      for (const bool skip : {false, true}) {
        KdSearchOptions o = options;
        o.skip_range_checks = skip;
        for (size_t c = 0; c < num_chunks; ++c) {
          run(o, c);
          for (size_t i = 0; i < std::min(chunk, nq - c * chunk); ++i) {
            const size_t q = c * chunk + i;
            const KdSearchResult& r = batch.results[i];
            const KdSearchResult& a = alone.results[b][q];
            if (r.num_neighbors != a.num_neighbors || r.checks != a.checks ||
                r.corrupt != a.corrupt ||
                !std::equal(batch.spans[i].begin(), batch.spans[i].begin() + r.num_neighbors,
                            alone.neighbors[b].begin() + q * k)) {
              Fail("batch " + std::to_string(width) + ", " + std::to_string(budgets[b]) +
                   " checks: query " + std::to_string(q) + " differs from its search alone");
            }
          }
        }
      }
      methods->checked_row.push_back(methods->rows.size());
      methods->rows.push_back(row);
      methods->timed.push_back([run, options](size_t c) { run(options, c); });
      methods->timed_calls.push_back(num_chunks);
      KdSearchOptions unchecked = options;
      unchecked.skip_range_checks = true;
      methods->unchecked_row.push_back(methods->timed.size());
      methods->timed.push_back([run, unchecked](size_t c) { run(unchecked, c); });
      methods->timed_calls.push_back(num_chunks);
    }
  }
}

// Times every method's passes, interleaved, and prints the table and what the range checks
// cost.
void TimeAndReport(int reps, size_t nq, bool with_flann, Methods* methods) {
  std::vector<Row>& rows = methods->rows;
  std::vector<std::vector<double>> times(methods->timed.size());
  for (int r = 0; r < reps; ++r) {
    for (size_t m = 0; m < methods->timed.size(); ++m) {
      times[m].push_back(TimeQueries(methods->timed_calls[m], nq, methods->timed[m]));
    }
  }
  double flann_us = 0;
  if (with_flann) rows[0].us_per_query = flann_us = Median(times[0]);
  std::vector<std::string> check_costs;
  for (size_t b = 0; b < methods->checked_row.size(); ++b) {
    const std::vector<double>& with = times[methods->unchecked_row[b] - 1];
    const std::vector<double>& without = times[methods->unchecked_row[b]];
    Row& row = rows[methods->checked_row[b]];
    row.us_per_query = Median(with);
    row.us_unchecked = Median(without);
    // Passes of one repetition ran back to back: their ratio is robust to load drift.
    std::vector<double> ratios;
    for (int r = 0; r < reps; ++r) ratios.push_back(with[r] / without[r] - 1);
    std::sort(ratios.begin(), ratios.end());
    char text[160];
    std::snprintf(text, sizeof(text), "%s: %+.1f%% (per-pass range %+.1f%% .. %+.1f%%)",
                  row.method.c_str(), 100 * Median(ratios), 100 * ratios.front(),
                  100 * ratios.back());
    check_costs.push_back(text);
  }
  PrintTable(rows, flann_us);
  std::printf("\ncost of the range checks (median over passes of checked / unchecked - 1):\n");
  for (const std::string& line : check_costs) std::printf("  %s\n", line.c_str());
}

int Main(int argc, char** argv) {
  CLI::App app{"Compare FLANN's randomized kd-trees with cwloc's flat kd-forest (kNN of SIFT)"};
  BenchFlags flags;
  AddFlags(&app, &flags);
  CLI11_PARSE(app, argc, argv);
  if (flags.threads == 0) flags.threads = std::max(1u, std::thread::hardware_concurrency());
  const std::vector<uint32_t> budgets = ParseCommaList(flags.checks_text);
  std::vector<uint32_t> batch_widths;
  for (uint32_t w : ParseCommaList(flags.batch_text)) {
    if (w > 1) batch_widths.push_back(w);
  }
  flags.batch_chunk = std::max<size_t>(flags.batch_chunk, 1);
  if (flags.k < 2) Fail("-k must be at least 2 (recall@2)");
  const DistanceFunctions* distance = KernelNamed(flags.kernel_name);

  Stopwatch stopwatch;
  const size_t wanted_queries = std::max(flags.num_queries, flags.gt_queries);
  Dataset data = flags.database.empty()
                     ? GenerateSynthetic(flags.synthetic, wanted_queries, flags.seed, flags.threads)
                     : LoadColmapDatabase(flags.database, flags.query_list);
  std::printf("data: %s (%.1f s)\n", data.description.c_str(), stopwatch.Seconds());
  PickQueries(wanted_queries, flags.seed, &data);
  const size_t n = data.NumBase();
  const size_t nq = std::min(flags.num_queries, data.NumQueries());
  const size_t gt_queries = std::min(flags.gt_queries, data.NumQueries());
  std::printf(
      "base %zu descriptors (%.1f MB), %zu timed queries, %zu with ground truth; "
      "k=%d, %u trees, leaf <= %u, distance kernel %s, build threads %u\n",
      n, double(data.base.size()) / 1e6, nq, gt_queries, flags.k, flags.trees, flags.leaf_size,
      std::string(distance->name).c_str(), flags.threads);

  // The matrix both indexes search.
  HugeBuffer huge;
  if (flags.hugepages) huge = OnHugePages(data.base);
  const std::span<const uint8_t> base =
      huge ? std::span<const uint8_t>(huge.get(), data.base.size()) : data.base;
  double build_s = 0;
  const KdForest forest = BuildOurForest(base, flags, &build_s);
  if (flags.build_only) return 0;

  stopwatch.Restart();
  const std::vector<TrueNeighbors> truth = BruteForce(data, gt_queries, flags.threads);
  std::printf("brute force ground truth: %.1f s\n", stopwatch.Seconds());

  Methods methods;
  FlannSearch flann;
  if (!flags.no_flann) AddFlann(flags, base, data, truth, nq, &flann, &methods);
  KdForestSearcher searcher(forest.View(base), *distance);
  std::vector<KdNeighbor> out(flags.k);
  AloneResults alone;
  AddOurForest(flags, budgets, build_s, forest, searcher, out, data, truth, nq, &alone, &methods);
  BatchBuffers batch(data, nq, flags.batch_chunk, flags.k);
  AddBatched(flags, batch_widths, budgets, searcher, nq, alone, batch, &methods);
  if (!batch_widths.empty()) {
    std::printf("batched searches (chunks of %zu queries) equal one-at-a-time: checked\n",
                batch.chunk);
  }
  TimeAndReport(flags.reps, nq, !flags.no_flann, &methods);
  return 0;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) { return cwloc::Main(argc, argv); }
