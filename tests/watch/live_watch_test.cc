#include "watch/live_watch.h"

#include <gtest/gtest.h>

#include <memory>
#include <nlohmann/json.hpp>
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

// A watch of `source` to its end; the JSON of its last line (the stop line) in *last.
LiveWatchSummary WatchToTheEnd(const LiveWatchOptions& o, LiveWatchEvents events,
                               std::unique_ptr<vision::FrameSource> source, nlohmann::json* last) {
  std::atomic<bool> stop{false};
  events.on_line = [&](const std::string& line) { *last = nlohmann::json::parse(line); };
  const LiveWatchSummary s = RunLiveWatch(o, events, nullptr, &stop, std::move(source));
  EXPECT_TRUE(stop);
  return s;
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

// Whatever the reader throws, the watch ends with its stop line and the reason (exit 1 in the
// command), never std::terminate.
TEST(LiveWatchTest, AnythingThrownInTheReaderEndsTheWatchWithAStopLine) {
  nlohmann::json last;
  const LiveWatchSummary s = WatchToTheEnd(
      Options(), {}, std::make_unique<ScriptedSource>(3, Ending::kNotAnException), &last);
  EXPECT_EQ(s.ended_because, "the source failed");
  EXPECT_EQ(s.error, "scripted: an unknown error while reading");
  EXPECT_EQ(last["event"], "stop");
}

// An error on the measuring thread (here the level-change callback) ends the watch the same way.
TEST(LiveWatchTest, AnErrorOnTheMeasuringThreadEndsTheWatchWithAStopLine) {
  LiveWatchEvents events;
  events.on_level_change = [](const WatchStatus&, const std::optional<ClogIndex>&) {
    throw std::runtime_error("the alert could not be told");
  };
  // Frames without pixels: no_view once that held 2 s, and the callback throws.
  nlohmann::json last;
  const LiveWatchSummary s =
      WatchToTheEnd(Options(), events, std::make_unique<ScriptedSource>(500, Ending::kEnd), &last);
  EXPECT_EQ(s.ended_because, "the watch failed");
  EXPECT_EQ(s.error, "scripted: the watch failed: the alert could not be told");
  EXPECT_EQ(last["event"], "stop");
}

// A source's name that is not UTF-8 (a path in Latin-1) cannot stop the JSON lines.
TEST(LiveWatchTest, ASourceNameThatIsNotUtf8StillGivesJsonLines) {
  LiveWatchOptions o = Options();
  o.source = "caf\xe9";
  nlohmann::json last;
  const LiveWatchSummary s =
      WatchToTheEnd(o, {}, std::make_unique<ScriptedSource>(3, Ending::kEnd), &last);
  EXPECT_EQ(s.ended_because, "the file ended");
  EXPECT_EQ(last["event"], "stop");
  EXPECT_EQ(last["source"], "caf\xef\xbf\xbd");  // U+FFFD in place of the stray byte
}

// A camera's password is in no line, warning or error of the watch; where /status is served is in
// every line.
TEST(LiveWatchTest, ACameraPasswordIsShownInNoLineWarningOrError) {
  LiveWatchOptions o = Options();
  o.source = "rtsp://admin:s3cret@cam.local/stream1?token=abc123";
  o.http_url = "http://127.0.0.1:8090";
  std::vector<std::string> told;  // every line and warning
  LiveWatchEvents events;
  events.on_warning = [&](const std::string& message) { told.push_back(message); };
  std::atomic<bool> stop{false};
  events.on_line = [&](const std::string& line) { told.push_back(line); };
  const LiveWatchSummary s =
      RunLiveWatch(o, events, nullptr, &stop, std::make_unique<ScriptedSource>(3, Ending::kError));
  told.push_back(s.error);
  ASSERT_GE(told.size(), 3u);
  for (const std::string& t : told) {
    EXPECT_EQ(t.find("s3cret"), std::string::npos) << t;
    EXPECT_EQ(t.find("abc123"), std::string::npos) << t;
  }
  EXPECT_EQ(s.error, "rtsp://admin:***@cam.local/stream1?token=***: decoder gave up");
  const nlohmann::json last = nlohmann::json::parse(told[told.size() - 2]);
  EXPECT_EQ(last["source"], "rtsp://admin:***@cam.local/stream1?token=***");
  EXPECT_EQ(last["http"], "http://127.0.0.1:8090");
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
