#include "watch/live_watch.h"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>

namespace clogscope::pipeline {
namespace {

// A file-like source of `frames` frames without pixels (nothing to measure), then `end`: the end
// of the file, a std::exception, or something that is not one.
enum class Ending { kEnd, kError, kNotAnException };

class ScriptedSource : public vision::FrameSource {
 public:
  ScriptedSource(int frames, Ending end)
      : FrameSource("scripted", vision::SourceKind::kVideo), frames_(frames), end_(end) {}
  vision::FrameRead Read(vision::InputFrame* out, std::string*) override {
    if (next_ == frames_) {
      if (end_ == Ending::kError) throw std::runtime_error("decoder gave up");
      if (end_ == Ending::kNotAnException) throw 42;
      return vision::FrameRead::kEnd;
    }
    out->index = next_;
    out->time_s = next_ / 25.0;
    out->error = "no pixels";
    ++next_;
    return vision::FrameRead::kFrame;
  }

 private:
  int frames_, next_ = 0;
  Ending end_;
};

LiveWatchOptions Options() {
  LiveWatchOptions o;
  o.source = "scripted";
  return o;
}

TEST(LiveWatchTest, AFilesFramesAreAllTakenThroughTheQueue) {
  std::atomic<bool> stop{false};
  const LiveWatchSummary s = RunLiveWatch(Options(), {}, nullptr, &stop,
                                          std::make_unique<ScriptedSource>(500, Ending::kEnd));
  EXPECT_EQ(s.frames, 500);  // a file's reader waits for room: none dropped
  EXPECT_EQ(s.skipped_frames, 0);
  EXPECT_EQ(s.ended_because, "the file ended");
  EXPECT_TRUE(stop);
}

TEST(LiveWatchTest, ASourceThatFailsEndsTheWatchWithItsReason) {
  std::atomic<bool> stop{false};
  const LiveWatchSummary s = RunLiveWatch(Options(), {}, nullptr, &stop,
                                          std::make_unique<ScriptedSource>(3, Ending::kError));
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.ended_because, "the source failed");
  EXPECT_EQ(s.error, "scripted: decoder gave up");
}

TEST(LiveWatchTest, AnErrorEscapingTheReaderReachesTheCaller) {
  std::atomic<bool> stop{false};
  EXPECT_THROW(RunLiveWatch(Options(), {}, nullptr, &stop,
                            std::make_unique<ScriptedSource>(3, Ending::kNotAnException)),
               int);
  EXPECT_TRUE(stop);
}

}  // namespace
}  // namespace clogscope::pipeline
