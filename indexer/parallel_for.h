#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace cwloc {

// Runs body(i, worker) for i in [0, n) on up to num_threads threads (worker in
// [0, num_threads) identifies the thread, for per-thread scratch), handing out indices
// dynamically because work items vary a lot in size. body must not throw.
template <typename Body>
void ParallelFor(size_t n, int num_threads, Body&& body) {
  const size_t threads = std::max<size_t>(1, std::min<size_t>(num_threads, n));
  std::atomic<size_t> next{0};
  auto worker = [&](int worker_index) {
    for (size_t i = next++; i < n; i = next++) body(i, worker_index);
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker, static_cast<int>(t));
  worker(0);
  for (auto& thread : pool) thread.join();
}

// Number of threads to use when the user asked for `requested` (0 = all cores).
inline int ResolveThreads(int requested) {
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace cwloc
