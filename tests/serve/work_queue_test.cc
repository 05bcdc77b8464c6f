// The query workers' bounded queue (serve/work_queue.h): work runs, a full queue turns work
// away at once, work whose deadline passes in the queue is taken out, and the queue finishes
// what it holds when it is destroyed.
#include "serve/work_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <thread>

namespace cwloc {
namespace {

using Clock = WorkQueue::Clock;

void WaitFor(const std::function<bool()>& condition) {
  while (!condition()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

const Clock::time_point kNoDeadline = Clock::now() + std::chrono::hours(1);

TEST(WorkQueueTest, RunsWorkAndTurnsAwayWhatFindsTheQueueFullOrWaitsPastItsDeadline) {
  WorkQueue queue(/*threads=*/1, /*capacity=*/1);
  int ran = 0;
  EXPECT_EQ(queue.Run([&] { ++ran; }, kNoDeadline), WorkQueue::Outcome::kDone);
  EXPECT_EQ(ran, 1);

  // The only worker is kept busy until `release` is set.
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  auto blocker = std::async(std::launch::async,
                            [&] { return queue.Run([&] { released.wait(); }, kNoDeadline); });
  WaitFor([&] { return queue.busy() == 1; });

  // Waiting past its deadline: taken out of the queue, never run.
  std::atomic<bool> late_ran{false};
  EXPECT_EQ(queue.Run([&] { late_ran = true; }, Clock::now() + std::chrono::milliseconds(20)),
            WorkQueue::Outcome::kExpired);
  EXPECT_EQ(queue.queued(), 0u);

  // One waits in the queue; the next finds it full at once.
  std::atomic<bool> queued_ran{false};
  auto queued = std::async(std::launch::async,
                           [&] { return queue.Run([&] { queued_ran = true; }, kNoDeadline); });
  WaitFor([&] { return queue.queued() == 1; });
  EXPECT_EQ(queue.Run([] {}, kNoDeadline), WorkQueue::Outcome::kQueueFull);

  release.set_value();
  EXPECT_EQ(blocker.get(), WorkQueue::Outcome::kDone);
  EXPECT_EQ(queued.get(), WorkQueue::Outcome::kDone);
  EXPECT_TRUE(queued_ran);
  EXPECT_FALSE(late_ran);
  // A worker is busy until its task's done() returns, just after Run() is woken: the workers
  // come free (a test that hangs here fails on ctest's timeout).
  WaitFor([&] { return queue.busy() == 0; });
}

TEST(WorkQueueTest, EveryThreadRunsWork) {
  WorkQueue queue(/*threads=*/3, /*capacity=*/3);
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::vector<std::future<WorkQueue::Outcome>> running;
  for (int i = 0; i < 3; ++i) {
    running.push_back(std::async(std::launch::async,
                                 [&] { return queue.Run([&] { released.wait(); }, kNoDeadline); }));
  }
  WaitFor([&] { return queue.busy() == 3; });  // three at once, none waiting
  EXPECT_EQ(queue.queued(), 0u);
  release.set_value();
  for (auto& outcome : running) EXPECT_EQ(outcome.get(), WorkQueue::Outcome::kDone);
}

}  // namespace
}  // namespace cwloc
