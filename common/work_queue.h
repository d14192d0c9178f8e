#pragma once

// The tool's one way to hand work between threads: a bounded blocking queue (BoundedQueue), a set
// of threads whose exceptions reach the caller (Workers), and a parallel loop over numbered items
// built on them (ParallelFor). Used by `measure` (a reader thread decoding ahead of measurement),
// `run` (steps measured in parallel) and `watch` (a reader thread feeding the measuring thread).
//
// Errors: nothing thrown in a worker ends the process. Workers catches every exception of its
// threads and Join() rethrows the first one on the caller's thread, after all have finished.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace clogscope {

// What a full queue does with another item.
enum class QueueFull {
  kWait,        // Push waits for room (every item is delivered)
  kDropOldest,  // the oldest item is dropped and counted (a live feed wants now, not a backlog)
};

// A first-in, first-out queue of at most `capacity` items between producer and consumer threads.
// Close() says no more items will come: consumers take what is left, then Pop returns false.
// Cancel() also drops what is left and wakes every waiting Push and Pop (they return false).
template <typename T>
class BoundedQueue {
 public:
  // Throws std::invalid_argument when capacity is 0.
  explicit BoundedQueue(size_t capacity, QueueFull when_full = QueueFull::kWait)
      : capacity_(capacity), when_full_(when_full) {
    if (capacity == 0) throw std::invalid_argument("BoundedQueue: capacity must be at least 1");
  }

  // Adds `item` at the back, waiting for room (kWait) or dropping the oldest (kDropOldest).
  // False, with the item not queued, when the queue is closed or cancelled.
  bool Push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    ++waiting_pushers_;
    if (when_full_ == QueueFull::kWait)
      room_.wait(lock, [&] { return items_.size() < capacity_ || closed_; });
    --waiting_pushers_;
    if (closed_) return false;
    while (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped_;
    }
    items_.push_back(std::move(item));
    ready_.notify_one();
    return true;
  }

  // Adds `item` only when there is room now; false when full, closed or cancelled.
  bool TryPush(T item) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_ || items_.size() >= capacity_) return false;
    items_.push_back(std::move(item));
    ready_.notify_one();
    return true;
  }

  // Takes the front item, waiting for one. False when the queue is closed and empty, or cancelled.
  bool Pop(T* out) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return !items_.empty() || closed_; });
    return TakeFront(out);
  }

  // As Pop, waiting at most `timeout`. False also on time-out; *ended tells the two apart (true:
  // closed and empty, or cancelled — nothing more will come).
  template <typename Rep, typename Period>
  bool PopFor(T* out, std::chrono::duration<Rep, Period> timeout, bool* ended) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return !items_.empty() || closed_; });
    *ended = items_.empty() && closed_;
    return TakeFront(out);
  }

  // No more items: waiting pushes fail, consumers take what is left.
  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    ready_.notify_all();
    room_.notify_all();
  }

  // Close() and drop the items still queued (they are not counted as dropped).
  void Cancel() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    items_.clear();
    ready_.notify_all();
    room_.notify_all();
  }

  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  // Items dropped by kDropOldest so far.
  long long dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  // Pushes waiting for room now (a readiness signal for tests and monitoring).
  size_t waiting_pushers() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return waiting_pushers_;
  }

 private:
  bool TakeFront(T* out) {
    if (items_.empty()) return false;
    *out = std::move(items_.front());
    items_.pop_front();
    room_.notify_one();
    return true;
  }

  mutable std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<T> items_;
  size_t capacity_;
  QueueFull when_full_;
  bool closed_ = false;
  long long dropped_ = 0;
  size_t waiting_pushers_ = 0;
};

// Closes a queue when it goes out of scope, however its producer ends (returns or throws), so the
// consumer never waits for items that will not come.
template <typename T>
class CloseOnExit {
 public:
  explicit CloseOnExit(BoundedQueue<T>* queue) : queue_(queue) {}
  ~CloseOnExit() { queue_->Close(); }
  CloseOnExit(const CloseOnExit&) = delete;
  CloseOnExit& operator=(const CloseOnExit&) = delete;

 private:
  BoundedQueue<T>* queue_;
};

// `threads` threads, each running body(k) for its number k = 0 … threads−1. An exception thrown
// by a body is caught on its thread; Join() waits for all and rethrows the first one caught.
// Destroyed without Join(), it waits for the threads and drops their exceptions (so a caller that
// is itself unwinding never reaches std::terminate).
class Workers {
 public:
  // Throws std::invalid_argument when threads < 1.
  Workers(int threads, std::function<void(int)> body);
  ~Workers();
  Workers(const Workers&) = delete;
  Workers& operator=(const Workers&) = delete;

  // Waits for every thread; rethrows the first exception a body threw. Once only.
  void Join();
  // True once a body has thrown (the others may stop early on it).
  bool failed() const { return failed_.load(); }

 private:
  std::function<void(int)> body_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};
};

// Runs body(i) for i = 0 … count−1 on `threads` threads (at most count), taking items in order.
// No new item is started once `cancel` (optional) is true or a body has thrown; the first
// exception is rethrown here after every thread has finished. threads < 1 means one per core.
void ParallelFor(size_t count, int threads, const std::function<void(size_t)>& body,
                 const std::atomic<bool>* cancel = nullptr);

}  // namespace clogscope
