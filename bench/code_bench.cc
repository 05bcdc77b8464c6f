// cwloc-code-bench: how much of nearest-neighbour matching survives when an index's descriptors
// are stored as product-quantization codes (kdtree/product_quantizer.h), the first
// measurement of issue #26's compact index. For each code size it trains a quantizer on the
// index's descriptors, codes all of them, and scans them with the asymmetric distance for a
// sample of real query features; against exact brute force over the full descriptors it prints:
//   recall@1 / @10: the true nearest view is the code scan's first / among its first 10;
//   re-rank R: the code scan's first R views re-ranked by exact distance (what a compact index
//     with a short exact or finer second stage would do; R = 0: none, the ratio test on the
//     codes' asymmetric distances; "corrected": the same, each distance less the view's own
//     quantization error |x - decode(code(x))|^2, which the asymmetric distance adds to the exact
//     one on average): recall@1, and of the matches the
//     paper's ratio test (d1 < 0.7 d2) makes on exact distances, the share it still makes with
//     the same view ("kept") and the share of other matches it makes instead ("added");
//   residual R (with --residual B): the first R re-ranked by the distance to the reconstruction
//     of the code plus a B-byte code of its residual, a second stage a compact index can ship;
//   code bytes per view, training time, coding time per view, scan time per query.
//
//   cwloc-code-bench --index hj.cwl --database database.db --query-list query_list.txt
//       [--codes 8,16,32,64] [--rerank 0,10,100] [--gt-queries 2000] [--threads 2]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

#include "app/database/database_queries.h"
#include "base/comma_list.h"
#include "base/parallel_for.h"
#include "base/split_mix64.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "kdtree/descriptor_distance.h"
#include "kdtree/product_quantizer.h"

namespace cwloc {
namespace {

constexpr double kRatio = 0.7;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

struct Neighbors {
  uint32_t first = 0, second = 0;
  float d1 = 0, d2 = 0;  // squared distances
};

bool PassesRatio(const Neighbors& n) { return n.d1 < kRatio * kRatio * n.d2; }

// Keeps the two nearest of the views offered.
void Offer(uint32_t view, float distance, Neighbors* n) {
  if (distance < n->d1) {
    *n = {view, n->first, distance, n->d1};
  } else if (distance < n->d2) {
    n->second = view;
    n->d2 = distance;
  }
}

// The command line.
struct BenchFlags {
  std::string index_path, database, query_list, codes_text = "8,16,32,64", rerank_text = "0,10,100";
  uint32_t gt_queries = 2000, threads = 2, iterations = 15, train = 50000, residual = 0;
  uint64_t seed = 0;
};

void AddFlags(CLI::App* app, BenchFlags* f) {
  app->add_option("--index", f->index_path, "cwloc index whose descriptors are coded")->required();
  app->add_option("--database", f->database, "COLMAP database.db with the query features")
      ->required();
  app->add_option("--query-list", f->query_list, "query image names, one per line")->required();
  app->add_option("--codes", f->codes_text, "code bytes per view (subspaces), comma-separated");
  app->add_option("--rerank", f->rerank_text, "exact re-rank depths, comma-separated");
  app->add_option("--residual", f->residual,
                  "bytes of a second code of what the first leaves (0: none); its columns re-rank "
                  "the first R by the distance to both codes' reconstruction");
  app->add_option("--gt-queries", f->gt_queries, "query features sampled (exact ground truth)");
  app->add_option("--train", f->train, "descriptors k-means trains on");
  app->add_option("--iterations", f->iterations, "k-means iterations");
  app->add_option("--threads", f->threads, "threads for ground truth and scans");
  app->add_option("--seed", f->seed, "sampling and k-means seed");
}

// What every code size is measured on: the index's descriptors, the sampled query features
// and their exact nearest views.
struct Workload {
  std::vector<uint8_t> base;     // num_views x 128
  std::vector<uint8_t> queries;  // nq x 128
  std::vector<Neighbors> truth;  // per query
  size_t truth_pass = 0;         // queries whose exact neighbours pass the ratio test

  uint32_t num_views() const { return uint32_t(base.size() / 128); }
  size_t nq() const { return queries.size() / 128; }
  const uint8_t* Query(size_t i) const { return &queries[i * 128]; }
  const uint8_t* View(size_t v) const { return &base[v * 128]; }
};

std::vector<uint8_t> IndexDescriptors(const Index& index) {
  const uint32_t num_views = index.num_views();
  std::vector<uint8_t> base(size_t{num_views} * 128);
  uint8_t scratch[128];
  for (uint32_t v = 0; v < num_views; ++v)
    std::copy_n(index.ViewDescriptor(v, scratch), 128, &base[size_t{v} * 128]);
  return base;
}

// A seeded sample of every listed query's features.
std::vector<uint8_t> SampledQueries(const BenchFlags& flags) {
  std::vector<uint8_t> all_queries;
  const DatabaseQueries queries(flags.database);
  std::ifstream list(flags.query_list);
  for (std::string line; std::getline(list, line);) {
    const std::string name = line.substr(0, line.find(' '));
    if (name.empty()) continue;
    const Query query = queries.Load(name);
    all_queries.insert(all_queries.end(), query.descriptors.begin(), query.descriptors.end());
  }
  std::vector<uint32_t> order(all_queries.size() / 128);
  std::iota(order.begin(), order.end(), 0u);
  SplitMix64 rng(flags.seed);
  rng.Shuffle(std::span<uint32_t>(order));
  order.resize(std::min<size_t>(order.size(), flags.gt_queries));
  std::vector<uint8_t> sampled(order.size() * 128);
  for (size_t i = 0; i < order.size(); ++i)
    std::copy_n(&all_queries[size_t{order[i]} * 128], 128, &sampled[i * 128]);
  return sampled;
}

// Exact brute force: every query's two nearest views.
void FindExactNeighbors(uint32_t threads, Workload* w) {
  w->truth.resize(w->nq());
  ParallelFor(w->nq(), static_cast<int>(threads), [&](size_t i) {
    Neighbors n{0, 0, 1e30f, 1e30f};
    for (uint32_t v = 0; v < w->num_views(); ++v)
      Offer(v, static_cast<float>(SquaredL2(w->Query(i), w->View(v))), &n);
    w->truth[i] = n;
  });
  w->truth_pass = std::count_if(w->truth.begin(), w->truth.end(), PassesRatio);
}

void PrintHeader(const std::vector<uint32_t>& reranks, const std::vector<uint32_t>& residual_depths,
                 uint32_t residual) {
  std::printf("| code bytes / view | recall@1 | recall@10 |");
  for (const uint32_t r : reranks) std::printf(" re-rank %u: recall@1, matches kept, added |", r);
  std::printf(" corrected: recall@1, matches kept, added |");
  for (const uint32_t r : residual_depths)
    std::printf(" residual %u B, first %u: recall@1, kept, added |", residual, r);
  std::printf(" train s | code us / view | scan ms / query |\n|---|---|---|");
  for (size_t r = 0; r <= reranks.size() + residual_depths.size(); ++r) std::printf("---|");
  std::printf("---|---|---|\n");
}

// The views coded with m bytes each, and each view's quantization error
// |x - decode(code(x))|^2.
struct CodedViews {
  ProductQuantizer pq;
  std::vector<uint8_t> codes;
  std::vector<float> code_error;
  double train_seconds, code_us;
};

ProductQuantizerOptions QuantizerOptions(const BenchFlags& flags, uint32_t m) {
  ProductQuantizerOptions options;
  options.num_subspaces = m;
  options.iterations = flags.iterations;
  options.max_training = flags.train;
  options.seed = flags.seed;
  return options;
}

CodedViews EncodeViews(const Workload& w, const BenchFlags& flags, uint32_t m) {
  const uint32_t threads = flags.threads;
  auto start = std::chrono::steady_clock::now();
  ProductQuantizer pq = ProductQuantizer::Train(w.base, QuantizerOptions(flags, m));
  const double train_seconds = Seconds(start);
  start = std::chrono::steady_clock::now();
  std::vector<uint8_t> codes(size_t{w.num_views()} * m);
  std::vector<float> code_error(w.num_views());
  ParallelFor(w.num_views(), static_cast<int>(threads), [&](size_t v) {
    pq.Encode(&w.base[v * 128], &codes[v * m]);
    float decoded[128];
    pq.Decode(&codes[v * m], decoded);
    float sum = 0;
    for (int d = 0; d < 128; ++d)
      sum += (w.base[v * 128 + d] - decoded[d]) * (w.base[v * 128 + d] - decoded[d]);
    code_error[v] = sum;
  });
  const double code_us = Seconds(start) * 1e6 * threads / w.num_views();
  return CodedViews{std::move(pq), std::move(codes), std::move(code_error), train_seconds, code_us};
}

// The second code: of x - decode(code(x)), trained on those residuals; returns each view's
// reconstruction from both codes.
std::vector<float> ResidualReconstruction(const Workload& w, const BenchFlags& flags, uint32_t m,
                                          const CodedViews& coded) {
  const uint32_t num_views = w.num_views();
  const int threads = static_cast<int>(flags.threads);
  const ProductQuantizer& pq = coded.pq;
  std::vector<float> residuals(size_t{num_views} * 128);
  ParallelFor(num_views, threads, [&](size_t v) {
    pq.Decode(&coded.codes[v * m], &residuals[v * 128]);
    for (int d = 0; d < 128; ++d)
      residuals[v * 128 + d] = w.base[v * 128 + d] - residuals[v * 128 + d];
  });
  ProductQuantizerOptions second = QuantizerOptions(flags, m);
  second.num_subspaces = flags.residual;
  const ProductQuantizer fine = ProductQuantizer::Train(residuals, second);
  std::vector<float> reconstruction(size_t{num_views} * 128);
  ParallelFor(num_views, threads, [&](size_t v) {
    uint8_t fine_code[128];
    fine.Encode(&residuals[v * 128], fine_code);
    float first[128];
    pq.Decode(&coded.codes[v * m], first);
    fine.Decode(fine_code, &reconstruction[v * 128]);
    for (int d = 0; d < 128; ++d) reconstruction[v * 128 + d] += first[d];
  });
  return reconstruction;
}

// Per query, what the code scan found: the true nearest view first, among the first 10, and
// per column (each re-rank depth, the corrected distance, each residual depth) the true view
// first and the ratio test's matches kept and added.
struct ScanHits {
  std::vector<int> hit1, hit10;
  std::vector<std::vector<int>> rerank_hit, kept, added;
  double scan_ms = 0;
};

ScanHits ScanCodes(const Workload& w, uint32_t m, const CodedViews& coded,
                   const std::vector<float>& reconstruction, const std::vector<uint32_t>& reranks,
                   const std::vector<uint32_t>& residual_depths, uint32_t threads) {
  const ProductQuantizer& pq = coded.pq;
  const uint32_t num_views = w.num_views();
  const size_t nq = w.nq();
  const uint32_t max_rerank =
      std::max<uint32_t>(10, *std::max_element(reranks.begin(), reranks.end()));
  ScanHits hits;
  hits.hit1.resize(nq);
  hits.hit10.resize(nq);
  // Index reranks.size(): the corrected asymmetric distance.
  const size_t columns = reranks.size() + 1 + residual_depths.size();
  hits.rerank_hit.assign(columns, std::vector<int>(nq));
  hits.kept.assign(columns, std::vector<int>(nq));
  hits.added.assign(columns, std::vector<int>(nq));
  const auto start = std::chrono::steady_clock::now();
  ParallelFor(nq, static_cast<int>(threads), [&](size_t i) {
    std::vector<float> table(size_t{m} * 256);
    pq.DistanceTable(w.Query(i), table.data());
    std::vector<std::pair<float, uint32_t>> scored(num_views);
    for (uint32_t v = 0; v < num_views; ++v)
      scored[v] = {pq.Distance(table.data(), &coded.codes[size_t{v} * m]), v};
    const uint32_t depth = std::min(max_rerank, num_views);
    std::partial_sort(scored.begin(), scored.begin() + depth, scored.end());
    hits.hit1[i] = scored[0].second == w.truth[i].first;
    hits.hit10[i] = std::any_of(scored.begin(), scored.begin() + std::min(10u, depth),
                                [&](const auto& s) { return s.second == w.truth[i].first; });
    for (size_t r = 0; r < columns; ++r) {
      const bool corrected = r == reranks.size();
      const bool fine = r > reranks.size();
      Neighbors n{0, 0, 1e30f, 1e30f};
      if (r < reranks.size() && reranks[r] == 0)
        n = {scored[0].second, scored[1].second, scored[0].first, scored[1].first};
      const uint32_t count = corrected ? num_views
                             : fine    ? std::min(residual_depths[r - reranks.size() - 1], depth)
                                       : std::min(reranks[r], depth);
      for (uint32_t j = 0; j < count; ++j) {
        const uint32_t v = corrected ? j : scored[j].second;
        float d = 0;
        if (corrected) {
          d = std::max(
              0.0f, pq.Distance(table.data(), &coded.codes[size_t{v} * m]) - coded.code_error[v]);
        } else if (fine) {
          for (int k = 0; k < 128; ++k) {
            const float diff = w.Query(i)[k] - reconstruction[size_t{v} * 128 + k];
            d += diff * diff;
          }
        } else {
          d = static_cast<float>(SquaredL2(w.Query(i), w.View(v)));
        }
        Offer(v, d, &n);
      }
      hits.rerank_hit[r][i] = n.first == w.truth[i].first;
      const bool exact = PassesRatio(w.truth[i]), coded_pass = PassesRatio(n);
      hits.kept[r][i] = exact && coded_pass && n.first == w.truth[i].first;
      hits.added[r][i] = coded_pass && !hits.kept[r][i];
    }
  });
  hits.scan_ms = Seconds(start) * 1e3 * threads / nq;
  return hits;
}

void PrintRow(uint32_t m, const Workload& w, const CodedViews& coded, const ScanHits& hits) {
  const size_t nq = w.nq();
  const auto share = [&](const std::vector<int>& v, size_t of) {
    return double(std::accumulate(v.begin(), v.end(), 0)) / double(std::max<size_t>(of, 1));
  };
  std::printf("| %u | %.3f | %.3f |", m, share(hits.hit1, nq), share(hits.hit10, nq));
  for (size_t r = 0; r < hits.rerank_hit.size(); ++r) {
    std::printf(" %.3f, %.3f, %.3f |", share(hits.rerank_hit[r], nq),
                share(hits.kept[r], w.truth_pass), share(hits.added[r], w.truth_pass));
  }
  std::printf(" %.1f | %.2f | %.2f |\n", coded.train_seconds, coded.code_us, hits.scan_ms);
  std::fflush(stdout);
}

int Main(int argc, char** argv) {
  CLI::App app{"Product-quantization codes of an index's descriptors against exact matching"};
  BenchFlags flags;
  AddFlags(&app, &flags);
  CLI11_PARSE(app, argc, argv);
  const std::vector<uint32_t> code_sizes = ParseCommaList(flags.codes_text);
  const std::vector<uint32_t> reranks = ParseCommaList(flags.rerank_text);

  Workload w;
  w.base = IndexDescriptors(Index::Open(flags.index_path));
  w.queries = SampledQueries(flags);
  std::printf("%u views in %s, %zu query features sampled\n", w.num_views(),
              flags.index_path.c_str(), w.nq());
  const auto start = std::chrono::steady_clock::now();
  FindExactNeighbors(flags.threads, &w);
  std::printf("exact brute force: %.1f s; %zu of %zu pass the ratio test %.1f\n\n", Seconds(start),
              w.truth_pass, w.nq(), kRatio);

  std::vector<uint32_t> residual_depths;
  for (const uint32_t r : reranks) {
    if (flags.residual > 0 && r > 0) residual_depths.push_back(r);
  }
  PrintHeader(reranks, residual_depths, flags.residual);
  for (const uint32_t m : code_sizes) {
    const CodedViews coded = EncodeViews(w, flags, m);
    std::vector<float> reconstruction;
    if (flags.residual > 0) reconstruction = ResidualReconstruction(w, flags, m, coded);
    PrintRow(m, w, coded,
             ScanCodes(w, m, coded, reconstruction, reranks, residual_depths, flags.threads));
  }
  return 0;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  return cwloc::RunTool("cwloc-code-bench", [&] { return cwloc::Main(argc, argv); });
}
