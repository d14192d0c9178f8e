#include "common/work_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace clogscope {
namespace {

// Waits (without sleeping) until `n` pushes are blocked on the full queue.
template <typename T>
void UntilPushersWait(const BoundedQueue<T>& q, size_t n) {
  while (q.waiting_pushers() < n) std::this_thread::yield();
}

TEST(BoundedQueueTest, ItemsArriveInTheOrderPushedAcrossThreads) {
  constexpr int kItems = 20000;
  BoundedQueue<int> q(4);
  std::thread producer([&] {
    CloseOnExit<int> close(&q);
    for (int i = 0; i < kItems; ++i) ASSERT_TRUE(q.Push(i));
  });
  std::vector<int> got;
  int v = -1;
  while (q.Pop(&v)) got.push_back(v);
  producer.join();
  std::vector<int> expected(kItems);
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(got, expected);
}

TEST(BoundedQueueTest, HoldsNoMoreThanItsCapacityAndAFullPushWaitsForRoom) {
  BoundedQueue<int> q(2);
  EXPECT_TRUE(q.TryPush(1));
  EXPECT_TRUE(q.TryPush(2));
  EXPECT_FALSE(q.TryPush(3));  // full
  EXPECT_EQ(q.size(), 2u);
  std::atomic<bool> pushed{false};
  std::thread producer([&] {
    EXPECT_TRUE(q.Push(3));
    pushed = true;
  });
  UntilPushersWait(q, 1);
  EXPECT_FALSE(pushed);  // still waiting: the queue is full
  EXPECT_EQ(q.size(), 2u);
  int v = 0;
  ASSERT_TRUE(q.Pop(&v));
  EXPECT_EQ(v, 1);
  producer.join();  // the pop made room
  EXPECT_TRUE(pushed);
  EXPECT_EQ(q.size(), 2u);
  ASSERT_TRUE(q.Pop(&v));
  EXPECT_EQ(v, 2);
  ASSERT_TRUE(q.Pop(&v));
  EXPECT_EQ(v, 3);
  EXPECT_EQ(q.dropped(), 0);
}

TEST(BoundedQueueTest, DropOldestKeepsTheNewestAndCountsTheRest) {
  BoundedQueue<int> q(2, QueueFull::kDropOldest);
  for (int i = 1; i <= 5; ++i) EXPECT_TRUE(q.Push(i));  // never waits
  EXPECT_EQ(q.dropped(), 3);
  q.Close();
  std::vector<int> got;
  int v = 0;
  while (q.Pop(&v)) got.push_back(v);
  EXPECT_EQ(got, (std::vector<int>{4, 5}));
}

TEST(BoundedQueueTest, CloseLetsTheConsumerDrainThenEnds) {
  BoundedQueue<std::string> q(3);
  ASSERT_TRUE(q.Push("a"));
  ASSERT_TRUE(q.Push("b"));
  q.Close();
  EXPECT_FALSE(q.Push("c"));  // refused after Close
  std::string s;
  bool ended = true;
  ASSERT_TRUE(q.PopFor(&s, std::chrono::seconds(0), &ended));
  EXPECT_EQ(s, "a");
  EXPECT_FALSE(ended);
  ASSERT_TRUE(q.Pop(&s));
  EXPECT_EQ(s, "b");
  EXPECT_FALSE(q.PopFor(&s, std::chrono::seconds(0), &ended));
  EXPECT_TRUE(ended);
}

TEST(BoundedQueueTest, PopForTellsATimeOutFromTheEnd) {
  BoundedQueue<int> q(1);
  int v = 0;
  bool ended = true;
  EXPECT_FALSE(q.PopFor(&v, std::chrono::seconds(0), &ended));
  EXPECT_FALSE(ended);  // nothing yet, but more may come
}

TEST(BoundedQueueTest, CancelWakesAWaitingProducerAndAWaitingConsumer) {
  BoundedQueue<int> full(1);
  ASSERT_TRUE(full.Push(1));
  bool push_result = true;
  std::thread producer([&] { push_result = full.Push(2); });
  UntilPushersWait(full, 1);
  full.Cancel();
  producer.join();
  EXPECT_FALSE(push_result);
  EXPECT_EQ(full.size(), 0u);  // what was queued is dropped

  BoundedQueue<int> empty(1);
  std::atomic<bool> waiting{false};
  bool pop_result = true;
  std::thread consumer([&] {
    int v = 0;
    waiting = true;
    pop_result = empty.Pop(&v);
  });
  while (!waiting) std::this_thread::yield();
  empty.Cancel();  // wakes the Pop whether it is already waiting or not yet
  consumer.join();
  EXPECT_FALSE(pop_result);
}

TEST(BoundedQueueTest, ZeroCapacityIsAContractViolation) {
  EXPECT_THROW(BoundedQueue<int>(0), std::invalid_argument);
}

TEST(WorkersTest, AnExceptionInAThreadReachesTheCallerAndTheOthersFinish) {
  std::atomic<int> finished{0};
  Workers w(3, [&](int k) {
    if (k == 1) throw std::runtime_error("thread 1 failed");
    ++finished;
  });
  try {
    w.Join();
    FAIL() << "Join did not rethrow";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "thread 1 failed");
  }
  EXPECT_EQ(finished, 2);
  EXPECT_TRUE(w.failed());
}

TEST(WorkersTest, EachThreadGetsItsOwnNumber) {
  std::mutex mu;
  std::multiset<int> seen;
  Workers w(4, [&](int k) {
    std::lock_guard<std::mutex> lock(mu);
    seen.insert(k);
  });
  w.Join();
  EXPECT_EQ(seen, (std::multiset<int>{0, 1, 2, 3}));
  EXPECT_FALSE(w.failed());
}

TEST(WorkersTest, DestroyedWithoutJoinWaitsAndDoesNotTerminate) {
  std::atomic<bool> ran{false};
  {
    Workers w(1, [&](int) {
      ran = true;
      throw std::runtime_error("dropped");
    });
  }
  EXPECT_TRUE(ran);
}

TEST(ParallelForTest, EveryItemRunsOnceWhateverTheThreads) {
  for (int threads : {1, 2, 7}) {
    std::vector<std::atomic<int>> runs(100);
    ParallelFor(runs.size(), threads, [&](size_t i) { ++runs[i]; });
    for (size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(runs[i], 1) << i << " on " << threads;
  }
  ParallelFor(0, 2, [](size_t) { FAIL() << "no item to run"; });
}

TEST(ParallelForTest, OneThreadTakesItemsInOrderAndStopsAtTheFirstError) {
  std::vector<size_t> ran;
  EXPECT_THROW(ParallelFor(10, 1,
                           [&](size_t i) {
                             ran.push_back(i);
                             if (i == 3) throw std::invalid_argument("item 3");
                           }),
               std::invalid_argument);
  EXPECT_EQ(ran, (std::vector<size_t>{0, 1, 2, 3}));  // nothing started after the failure
}

TEST(ParallelForTest, CancellationStopsTakingNewItems) {
  std::atomic<bool> cancel{false};
  std::vector<size_t> ran;
  ParallelFor(
      10, 1,
      [&](size_t i) {
        ran.push_back(i);
        if (i == 2) cancel = true;
      },
      &cancel);
  EXPECT_EQ(ran, (std::vector<size_t>{0, 1, 2}));
  // Cancelled before the start: nothing runs.
  ran.clear();
  ParallelFor(
      10, 3, [&](size_t i) { ran.push_back(i); }, &cancel);
  EXPECT_TRUE(ran.empty());
}

TEST(ParallelForTest, WorkersRunAtTheSameTime) {
  // Two items that each wait for the other to start: finishes only when both run concurrently.
  std::mutex mu;
  std::condition_variable cv;
  int started = 0;
  ParallelFor(2, 2, [&](size_t) {
    std::unique_lock<std::mutex> lock(mu);
    ++started;
    cv.notify_all();
    cv.wait(lock, [&] { return started == 2; });
  });
  EXPECT_EQ(started, 2);
}

}  // namespace
}  // namespace clogscope
