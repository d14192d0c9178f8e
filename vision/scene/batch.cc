#include "vision/scene/batch.h"

#include "common/work_queue.h"
#include "vision/scene/track.h"

namespace clogscope::vision {

int MeasureFrames(FrameSource& source, const StrandMeasureOptions& options,
                  const std::function<void(InputFrame&, StrandMeasurement&)>& on_frame,
                  const std::function<bool()>& stop) {
  constexpr size_t kQueueDepth = 8;
  BoundedQueue<InputFrame> queue(kQueueDepth);
  // The reader decodes ahead; the queue closes however it ends, so measuring never waits for
  // frames that will not come.
  Workers reader(1, [&](int) {
    CloseOnExit<InputFrame> close(&queue);
    InputFrame f;
    while (source.Next(&f)) {
      if (!queue.Push(std::move(f))) return;  // measuring stopped
      f = InputFrame{};
    }
  });

  int count = 0;
  StrandTracker tracker(options);
  tracker.SetEncoder(source.encoder());
  try {
    InputFrame f;
    while (queue.Pop(&f)) {
      StrandMeasurement m;
      if (f.image.empty()) {
        m.status = FrameStatus::kUnreadable;
        m.detail = f.error;
      } else {
        m = tracker.Measure(f);
        if (!f.error.empty() && m.detail.empty()) m.detail = f.error;  // e.g. damaged but decoded
      }
      on_frame(f, m);
      ++count;
      if (stop && stop()) break;
    }
  } catch (...) {
    // Measuring's own error wins: the reader, woken, is waited for as `reader` goes and its
    // error, if any, dropped.
    queue.Cancel();
    throw;
  }
  queue.Cancel();  // a reader still reading (stopped early) ends at its next push
  reader.Join();   // the reader's error, after the frames it read were measured
  return count;
}

}  // namespace clogscope::vision
