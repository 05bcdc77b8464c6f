#include "base/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace cwloc {
namespace {

// Many short passes on one pool, as a photo's SIFT makes them: every item runs exactly once
// in every pass, on workers 0 .. threads - 1.
TEST(WorkerPool, RunsEveryItemOnceInEveryPass) {
  WorkerPool pool(3);
  EXPECT_EQ(pool.threads(), 3);
  for (size_t n : {0, 1, 2, 7, 1000}) {
    for (int pass = 0; pass < 50; ++pass) {
      std::vector<std::atomic<int>> runs(n);
      std::atomic<int> bad_worker{0};
      pool.For(n, [&](size_t i, int worker) {
        ++runs[i];
        if (worker < 0 || worker >= 3) ++bad_worker;
      });
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(runs[i], 1) << "n " << n << " item " << i;
      EXPECT_EQ(bad_worker, 0);
    }
  }
}

TEST(WorkerPool, RethrowsTheFirstErrorAndStaysUsable) {
  WorkerPool pool(2);
  EXPECT_THROW(pool.For(100,
                        [](size_t i) {
                          if (i == 10) throw std::runtime_error("item 10");
                        }),
               std::runtime_error);
  std::atomic<size_t> sum{0};
  pool.For(100, [&](size_t i) { sum += i; });
  EXPECT_EQ(sum, 4950u);
}

TEST(WorkerPool, OneThreadRunsOnTheCaller) {
  WorkerPool pool(1);
  EXPECT_EQ(pool.threads(), 1);
  std::vector<int> order;
  pool.For(5, [&](size_t i, int worker) {
    EXPECT_EQ(worker, 0);
    order.push_back(int(i));
  });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4}));
}

}  // namespace
}  // namespace cwloc
