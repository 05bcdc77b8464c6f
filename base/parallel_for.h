#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace cwloc {

// Number of threads to use when the user asked for `requested` (0 or less = all cores).
inline int ResolveThreads(int requested) {
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

namespace parallel_internal {

// Items [0, n) handed out one at a time to body(i) or body(i, worker); the first exception is
// kept and stops the handing out.
template <typename Body>
class Items {
 public:
  Items(size_t n, Body& body) : n_(n), body_(body) {}
  void Work(int worker) {
    for (size_t i; (i = next_.fetch_add(1)) < n_;) {
      try {
        if constexpr (std::is_invocable_v<Body&, size_t, int>) {
          body_(i, worker);
        } else {
          body_(i);
        }
      } catch (...) {
        std::lock_guard lock(error_mutex_);
        if (!error_) error_ = std::current_exception();
        next_ = n_;
      }
    }
  }
  void RethrowError() {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  const size_t n_;
  Body& body_;
  std::atomic<size_t> next_{0};
  std::exception_ptr error_;
  std::mutex error_mutex_;
};

}  // namespace parallel_internal

// Runs body(i) or body(i, worker) for i in [0, n) on up to `threads` threads (0 = all cores);
// worker in [0, threads) identifies the thread, for per-thread scratch. Items are handed out
// one at a time because they vary a lot in size, so results must depend on i only, never on
// which thread ran it. The first exception is rethrown once all threads have stopped.
template <typename Body>
void ParallelFor(size_t n, int threads, Body&& body) {
  const int workers =
      static_cast<int>(std::min<size_t>(size_t(ResolveThreads(threads)), std::max<size_t>(n, 1)));
  parallel_internal::Items<Body> items(n, body);
  std::vector<std::thread> pool;
  for (int t = 1; t < workers; ++t) pool.emplace_back([&items, t] { items.Work(t); });
  items.Work(0);
  for (auto& thread : pool) thread.join();
  items.RethrowError();
}

// ParallelFor on threads started once and kept: for work made of many short parallel passes
// (a photo's SIFT makes hundreds), where starting threads for each would cost more than some
// passes. The calling thread is worker 0; For is called from one thread at a time.
class WorkerPool {
 public:
  explicit WorkerPool(int threads) {
    for (int t = 1; t < ResolveThreads(threads); ++t)
      workers_.emplace_back([this, t] { Serve(t); });
  }
  ~WorkerPool() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
      generation_.fetch_add(1, std::memory_order_release);  // ends the workers' spinning
    }
    wake_.notify_all();
    for (auto& worker : workers_) worker.join();
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return int(workers_.size()) + 1; }

  // As ParallelFor(n, threads(), body).
  template <typename Body>
  void For(size_t n, Body&& body) {
    parallel_internal::Items<Body> items(n, body);
    if (n > 1 && !workers_.empty()) {
      Run([&items](int worker) { items.Work(worker); });
    } else {
      items.Work(0);
    }
    items.RethrowError();
  }

 private:
  // Every worker runs `job` once, as the caller does; returns when all have.
  void Run(const std::function<void(int)>& job) {
    {
      std::lock_guard lock(mutex_);
      job_ = &job;
      unfinished_.store(workers_.size(), std::memory_order_relaxed);
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    job(0);
    SpinUntil([this] { return unfinished_.load(std::memory_order_acquire) == 0; });
    std::unique_lock lock(mutex_);
    finished_.wait(lock, [this] { return unfinished_.load(std::memory_order_acquire) == 0; });
    job_ = nullptr;
  }

  void Serve(int worker) {
    uint64_t seen = 0;
    for (;;) {
      SpinUntil([&] { return generation_.load(std::memory_order_acquire) != seen; });
      std::unique_lock lock(mutex_);
      wake_.wait(lock,
                 [&] { return stop_ || generation_.load(std::memory_order_relaxed) != seen; });
      if (stop_) return;
      seen = generation_.load(std::memory_order_relaxed);
      const std::function<void(int)>* job = job_;
      lock.unlock();
      (*job)(worker);
      if (unfinished_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        std::lock_guard finished_lock(mutex_);
        finished_.notify_one();
      }
    }
  }

  // Passes come back to back (a photo's SIFT runs hundreds, some a few microseconds long):
  // waiting a little before sleeping spares the wake-up, which costs more than such a pass.
  template <typename Done>
  static void SpinUntil(Done done) {
    for (int i = 0; i < 4000 && !done(); ++i) {
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#elif defined(__aarch64__)
      asm volatile("yield");
#endif
    }
  }

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  const std::function<void(int)>* job_ = nullptr;
  std::atomic<size_t> unfinished_{0};
  // Changed under the lock; spinning workers also read it without the lock.
  std::atomic<uint64_t> generation_{0};
  bool stop_ = false;
};

}  // namespace cwloc
