#include "common/work_queue.h"

#include <algorithm>

namespace clogscope {

Workers::Workers(int threads, std::function<void(int)> body) : body_(std::move(body)) {
  if (threads < 1) throw std::invalid_argument("Workers: need at least one thread");
  threads_.reserve(threads);
  for (int k = 0; k < threads; ++k) {
    threads_.emplace_back([this, k] {
      try {
        body_(k);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
        failed_ = true;
      }
    });
  }
}

Workers::~Workers() {
  for (auto& t : threads_)
    if (t.joinable()) t.join();
}

void Workers::Join() {
  for (auto& t : threads_)
    if (t.joinable()) t.join();
  std::exception_ptr error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::swap(error, error_);
  }
  if (error) std::rethrow_exception(error);
}

void ParallelFor(size_t count, int threads, const std::function<void(size_t)>& body,
                 const std::atomic<bool>* cancel) {
  if (count == 0) return;
  if (threads < 1) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = static_cast<int>(std::min<size_t>(threads, count));
  std::atomic<size_t> next{0};
  // A body's exception ends its thread and raises workers.failed(): the others take no new item.
  Workers workers(threads, [&](int) {
    while (!workers.failed() && !(cancel && cancel->load())) {
      const size_t i = next++;
      if (i >= count) return;
      body(i);
    }
  });
  workers.Join();
}

}  // namespace clogscope
