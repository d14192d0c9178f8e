#include "watch/live_watch.h"

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace clogscope::watch {
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

// A level change is told once the board (what /status, /metrics and /frame.jpg serve) shows it:
// a reader called then sees the new level, never the one before.
TEST(LiveWatchTest, ALevelChangeIsToldOnceTheBoardShowsIt) {
  std::atomic<bool> stop{false};
  WatchBoard board;
  struct Told {
    WatchLevel level, shown;
    double time_s, shown_time_s;
  };
  std::vector<Told> told;
  LiveWatchEvents events;
  events.on_level_change = [&](const WatchStatus& s, const std::optional<ClogIndex>&) {
    const WatchSnapshot shown = board.Read();
    told.push_back({s.level, shown.status.level, s.time_s, shown.status.time_s});
  };
  // Frames without pixels: nothing in view, so the watch goes to no_view once that held 2 s.
  RunLiveWatch(Options(), events, &board, &stop,
               std::make_unique<ScriptedSource>(500, Ending::kEnd));
  ASSERT_FALSE(told.empty());
  EXPECT_EQ(told.front().level, WatchLevel::kNoView);
  for (const Told& t : told) {
    EXPECT_EQ(t.shown, t.level) << WatchLevelName(t.level);
    EXPECT_EQ(t.shown_time_s, t.time_s);
  }
}

}  // namespace
}  // namespace clogscope::watch
