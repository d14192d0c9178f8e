#include "vision/scene/batch.h"

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "vision/scene/track.h"

namespace clogscope::vision {

int MeasureFrames(FrameSource& source, const StrandMeasureOptions& options,
                  const std::function<void(InputFrame&, StrandMeasurement&)>& on_frame,
                  const std::function<bool()>& stop) {
  constexpr size_t kQueueDepth = 8;
  std::mutex mu;
  std::condition_variable cv;
  std::deque<InputFrame> queue;
  bool done = false, cancelled = false;
  std::exception_ptr reader_error;

  std::thread reader([&] {
    try {
      while (true) {
        InputFrame f;
        if (!source.Next(&f)) break;
        std::unique_lock<std::mutex> lock(mu);
        cv.wait(lock, [&] { return queue.size() < kQueueDepth || cancelled; });
        if (cancelled) break;
        queue.push_back(std::move(f));
        cv.notify_all();
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mu);
      reader_error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mu);
    done = true;
    cv.notify_all();
  });

  int count = 0;
  std::exception_ptr consumer_error;
  StrandTracker tracker(options);
  try {
    while (true) {
      InputFrame f;
      {
        std::unique_lock<std::mutex> lock(mu);
        cv.wait(lock, [&] { return !queue.empty() || done; });
        if (queue.empty()) break;
        f = std::move(queue.front());
        queue.pop_front();
        cv.notify_all();
      }
      StrandMeasurement m;
      if (f.image.empty()) {
        m.status = FrameStatus::kUnreadable;
        m.detail = f.error;
      } else {
        m = tracker.Measure(f.image);
        if (!f.error.empty() && m.detail.empty()) m.detail = f.error;  // e.g. damaged but decoded
      }
      on_frame(f, m);
      ++count;
      if (stop && stop()) break;
    }
  } catch (...) {
    consumer_error = std::current_exception();
  }
  {
    std::lock_guard<std::mutex> lock(mu);
    cancelled = true;
    cv.notify_all();
  }
  reader.join();
  if (consumer_error) std::rethrow_exception(consumer_error);
  if (reader_error) std::rethrow_exception(reader_error);
  return count;
}

}  // namespace clogscope::vision
