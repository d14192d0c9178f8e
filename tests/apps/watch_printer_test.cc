// `clogscope watch --moonraker` / `--octoprint` end to end: a real watch on a rendered strand that
// narrows by 3 %, against a stand-in that speaks the printer's documented HTTP API and records
// every call. Time is the frames' (the watch's time_s); the test holds the watch at its level
// change (the observer runs on the measuring thread) while it plays the printer's part, and waits
// on signals (the stand-in's calls, the link's events), deadlines only as a safety net.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "apps/watch_command.h"
#include "synthetic/synthetic.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/external_process.h"
#include "tests/apps/printer_stand_in.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;
using testing::PrinterStandIn;
using testing::StandInCall;
using Kind = watch::PrinterEvent::Kind;

constexpr double kDropAtS = 6.0;  // the strand narrows by 3 % here
constexpr double kSeconds = 16.0;
constexpr double kHoldoffS = 3.0;
const std::string kApiKey = "clogscope-test-key-0123456789abcdef";

using testing::FreeLoopbackPort;

// The link's events as they come (on its thread), and a wait for one.
class EventLog {
 public:
  void Add(const watch::PrinterEvent& e) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      events_.push_back(e);
    }
    added_.notify_all();
  }
  std::vector<watch::PrinterEvent> All() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return events_;
  }
  std::vector<watch::PrinterEvent> Of(Kind kind) const {
    std::vector<watch::PrinterEvent> out;
    for (const auto& e : All())
      if (e.kind == kind) out.push_back(e);
    return out;
  }
  // Until an event matching pred has come (from the start), for at most timeout_s.
  bool WaitFor(const std::function<bool(const watch::PrinterEvent&)>& pred, double timeout_s) {
    std::unique_lock<std::mutex> lock(mutex_);
    return added_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                           [&] { return std::any_of(events_.begin(), events_.end(), pred); });
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable added_;
  std::vector<watch::PrinterEvent> events_;
};

class WatchPrinterTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::FreshDir("clogscope_printer_" + std::to_string(getpid())));
    std::ofstream(*dir_ / "key") << kApiKey << "\n";
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  // 16 s at 25 frames/s of a 400 µm strand (3 µm/px, 2 µm jitter) narrowing by 3 % at 6 s.
  static std::string Video() {
    const fs::path video = *dir_ / "drop.avi";
    if (fs::exists(video)) return video.string();
    synthetic::SceneParams s = testing::WatchCameraScene(11);
    const int frames = static_cast<int>(kSeconds * 25);
    for (int i = 0; i < frames; ++i)
      s.frame_width_um.push_back(i / 25.0 >= kDropAtS ? 388.0 : 400.0);
    synthetic::RenderSequence(s, frames, 25, video.string(), (*dir_ / "drop.truth.json").string());
    return video.string();
  }
  static std::string KeyFile() { return (*dir_ / "key").string(); }
  static WatchCommandOptions Options(const std::string& name) {
    WatchCommandOptions o;
    o.measure.scale_um_per_px = 3.0;
    o.live.report_every_s = 0.5;
    o.live.watch.baseline_s = 5;
    o.live.watch.window_s = 5;
    o.log_path = (*dir_ / (name + ".jsonl")).string();
    o.printer.api_key_file = KeyFile();
    o.printer.poll_interval_s = 0.2;
    return o;
  }
  static fs::path* dir_;
};
fs::path* WatchPrinterTest::dir_ = nullptr;

TEST_F(WatchPrinterTest, MoonrakerWebcamIsWatchedAThreePercentDropPausesOnceAndAResumeIsHeldOff) {
  PrinterStandIn moonraker(PrinterStandIn::Flavor::kMoonraker, kApiKey, "printing");
  ASSERT_GT(moonraker.port(), 0);
  // A disabled camera first: the first enabled one is watched. A file:// URL: the recording on
  // this host (a live stream would drop frames to keep up, and the times with them).
  moonraker.SetWebcams(json::array(
      {{{"name", "door"}, {"enabled", false}, {"stream_url", "/webcam2/?action=stream"}},
       {{"name", "nozzle"},
        {"enabled", true},
        {"stream_url", "file://" + Video()},
        {"snapshot_url", ""}}}));
  moonraker.SetNotifiers(json::array({{{"name", "phone"}, {"events", {"paused", "error"}}}}));

  WatchCommandOptions o = Options("moonraker");
  o.printer.moonraker_url = moonraker.url() + "/";
  o.printer.pause.pause_level = watch::WatchLevel::kWarn;
  o.printer.pause.holdoff_s = kHoldoffS;
  o.printer.notify_macro = "CLOGSCOPE_ALERT";
  EventLog events;
  WatchObservers observers;
  observers.on_printer = [&](const watch::PrinterEvent& e) { events.Add(e); };
  double warn_at_s = -1, pause_latency_ms = 0;
  bool pause_arrived = false, paused_seen = false, resumed = false;
  observers.on_level_change = [&](const watch::WatchStatus& s) {
    if (s.level != watch::WatchLevel::kWarn || warn_at_s >= 0) return;
    // The watch waits here, at s.time_s, while the printer plays its part.
    warn_at_s = s.time_s;
    const auto told = Clock::now();
    const auto pause = [](const std::vector<StandInCall>& calls) {
      return std::any_of(calls.begin(), calls.end(),
                         [](const StandInCall& c) { return c.path == "/printer/print/pause"; });
    };
    pause_arrived = moonraker.WaitFor(pause, 10);
    if (!pause_arrived) return;
    // From the level change told to the request received (negative when the link's thread sent
    // it before the measuring thread got here: the level goes to the link first).
    pause_latency_ms = std::chrono::duration<double, std::milli>(
                           moonraker.CallsTo("POST", "/printer/print/pause")[0].at - told)
                           .count();
    // The link sees "paused", then someone resumes.
    paused_seen = events.WaitFor(
        [](const auto& e) {
          return e.kind == Kind::kState && e.state == watch::PrintState::kPaused;
        },
        10);
    moonraker.SetState("printing");
    resumed = events.WaitFor([](const auto& e) { return e.kind == Kind::kResumed; }, 10);
  };
  std::atomic<bool> stop{false};
  const WatchReport r = WatchNozzle(o, &stop, observers);

  // The webcam was asked for and the recording watched whole.
  const std::vector<StandInCall> calls = moonraker.Calls();
  ASSERT_FALSE(calls.empty());
  EXPECT_EQ(calls.front().path, "/printer/objects/query");  // armed before the first frame
  EXPECT_EQ(moonraker.CallsTo("GET", "/server/webcams/list").size(), 1u);
  EXPECT_EQ(r.summary.frames, static_cast<long long>(kSeconds * 25));
  EXPECT_EQ(r.summary.ended_because, "the file ended");
  // Every call carried the key.
  for (const StandInCall& c : calls) EXPECT_EQ(c.api_key, kApiKey) << c.method << " " << c.path;

  // Paused within 5 s of the drop (the frames' time), the request there while the watch was held
  // at that time.
  ASSERT_GE(warn_at_s, 0) << "no warn";
  ASSERT_TRUE(pause_arrived) << "no pause reached the stand-in";
  std::cout << "3 % drop at " << kDropAtS << " s -> pause requested at " << warn_at_s
            << " s of the frames' time (" << warn_at_s - kDropAtS << " s after the drop); the "
            << "request reached Moonraker " << pause_latency_ms << " ms after the level change\n";
  EXPECT_GT(warn_at_s, kDropAtS);
  EXPECT_LE(warn_at_s - kDropAtS, 5.0);
  EXPECT_LT(pause_latency_ms, 1000);
  EXPECT_TRUE(paused_seen);
  ASSERT_TRUE(resumed);

  // The resume at warn_at_s: nothing within the hold-off, though the strand stayed narrow; once
  // after it (re-armed).
  const auto sent = events.Of(Kind::kPauseSent);
  const auto resumes = events.Of(Kind::kResumed);
  ASSERT_EQ(resumes.size(), 1u);
  EXPECT_DOUBLE_EQ(resumes[0].time_s, warn_at_s);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_DOUBLE_EQ(sent[0].time_s, warn_at_s);
  EXPECT_GE(sent[1].time_s, resumes[0].time_s + kHoldoffS);
  EXPECT_LE(sent[1].time_s, kSeconds);  // at a frame past it (the link follows every state)
  std::cout << "resumed at " << resumes[0].time_s << " s; paused again at " << sent[1].time_s
            << " s (hold-off " << kHoldoffS << " s)\n";
  EXPECT_EQ(moonraker.CallsTo("POST", "/printer/print/pause").size(), 2u);
  EXPECT_TRUE(events.Of(Kind::kPauseFailed).empty());

  // The notifiers were looked at, and the macro ran after each pause with the level and time.
  EXPECT_EQ(moonraker.CallsTo("GET", "/server/notifiers/list").size(), 1u);
  const auto scripts = moonraker.CallsTo("POST", "/printer/gcode/script");
  ASSERT_EQ(scripts.size(), 2u);
  const json script = json::parse(scripts[0].body);
  EXPECT_EQ(script["script"].get<std::string>().rfind("CLOGSCOPE_ALERT LEVEL=warn TIME_S=", 0), 0u)
      << script;
  EXPECT_NE(script["script"].get<std::string>().find("DRIFT_PCT=-"), std::string::npos) << script;
}

TEST_F(WatchPrinterTest, OctoPrintIsPausedOnceOnClog) {
  PrinterStandIn octoprint(PrinterStandIn::Flavor::kOctoPrint, kApiKey, "Printing");
  ASSERT_GT(octoprint.port(), 0);
  WatchCommandOptions o = Options("octoprint");
  o.live.source = Video();
  o.printer.octoprint_url = octoprint.url();
  // Thresholds that make the 3 % drop a clog: the default pause level.
  o.live.watch.warn_drift_pct = -1;
  o.live.watch.clog_drift_pct = -2;
  EventLog events;
  WatchObservers observers;
  observers.on_printer = [&](const watch::PrinterEvent& e) { events.Add(e); };
  double clog_at_s = -1;
  observers.on_level_change = [&](const watch::WatchStatus& s) {
    if (s.level != watch::WatchLevel::kClog || clog_at_s >= 0) return;
    clog_at_s = s.time_s;
    octoprint.WaitFor(
        [](const auto& calls) {
          return std::any_of(calls.begin(), calls.end(),
                             [](const StandInCall& c) { return c.method == "POST"; });
        },
        10);
  };
  std::atomic<bool> stop{false};
  WatchNozzle(o, &stop, observers);

  ASSERT_GE(clog_at_s, 0) << "no clog";
  std::cout << "OctoPrint: 3 % drop at " << kDropAtS << " s -> clog and pause at " << clog_at_s
            << " s\n";
  EXPECT_LE(clog_at_s - kDropAtS, 5.0);
  const auto posts = octoprint.CallsTo("POST", "/api/job");
  ASSERT_EQ(posts.size(), 1u);  // once: the printer stays paused, the level stays clog
  const json body = json::parse(posts[0].body);
  EXPECT_EQ(body, (json{{"command", "pause"}, {"action", "pause"}}));
  EXPECT_EQ(posts[0].api_key, kApiKey);
  EXPECT_EQ(octoprint.state(), "Paused");
  const auto sent = events.Of(Kind::kPauseSent);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_DOUBLE_EQ(sent[0].time_s, clog_at_s);
  EXPECT_FALSE(octoprint.CallsTo("GET", "/api/job").empty());
}

TEST_F(WatchPrinterTest, AnIdleOrAbsentPrinterIsNeverPausedAndNeverStopsTheWatch) {
  // Standby: disarmed, the clog told but nothing sent.
  PrinterStandIn moonraker(PrinterStandIn::Flavor::kMoonraker, kApiKey, "standby");
  WatchCommandOptions o = Options("idle");
  o.live.source = Video();
  o.printer.moonraker_url = moonraker.url();
  o.printer.pause.pause_level = watch::WatchLevel::kWarn;
  std::atomic<bool> stop{false};
  WatchReport r = WatchNozzle(o, &stop);
  EXPECT_GE(r.summary.level_changes, 1);
  EXPECT_FALSE(moonraker.CallsTo("GET", "/printer/objects/query").empty());
  EXPECT_TRUE(moonraker.CallsTo("POST", "/printer/print/pause").empty());

  // Nothing listening: a warning, and the whole file watched.
  o.printer.moonraker_url = "http://127.0.0.1:" + std::to_string(FreeLoopbackPort());
  EventLog events;
  WatchObservers observers;
  observers.on_printer = [&](const watch::PrinterEvent& e) { events.Add(e); };
  stop = false;
  r = WatchNozzle(o, &stop, observers);
  EXPECT_EQ(r.summary.frames, static_cast<long long>(kSeconds * 25));
  EXPECT_TRUE(events.Of(Kind::kPauseSent).empty());
}

TEST_F(WatchPrinterTest, AWrongKeyIsToldWithoutShowingAnyKey) {
  PrinterStandIn moonraker(PrinterStandIn::Flavor::kMoonraker, "the-printer-expects-this-key",
                           "printing");
  const testing::RunResult r =
      testing::RunCli("watch " + Video() + " --scale-um-per-px 3 --duration-s 0.2 --moonraker " +
                          moonraker.url() + " --printer-api-key-file " + KeyFile(),
                      *dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("unauthorized"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(kApiKey), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find(kApiKey), std::string::npos);
  ASSERT_FALSE(moonraker.Calls().empty());
  EXPECT_EQ(moonraker.Calls()[0].api_key, kApiKey);  // sent, never shown
}

TEST_F(WatchPrinterTest, BadPrinterOptionsGetOneLineNamingTheOption) {
  const std::string video = Video();
  const std::string url = "--moonraker http://127.0.0.1:" + std::to_string(FreeLoopbackPort());
  const std::vector<std::pair<std::string, std::string>> cases = {
      {video + " --moonraker ftp://printer", "--moonraker 'ftp://printer'"},
      {video + " --moonraker http://pi:s3cret@printer", "--printer-api-key-file"},
      {video + " " + url + " --octoprint http://octopi", "--moonraker and --octoprint"},
      {video + " " + url + " --pause-level no_view", "--pause-level no_view"},
      {video + " " + url + " --pause-holdoff-s -1", "--pause-holdoff-s"},
      {video + " " + url + " --printer-api-key-file /nonexistent/key",
       "--printer-api-key-file /nonexistent/key: cannot be read"},
      {video + " --webcam nozzle", "--webcam goes with --moonraker"},
      {video + " --octoprint http://octopi --webcam nozzle", "--webcam goes with --moonraker"},
      {video + " " + url + " --moonraker-notify-macro 'A;B'", "--moonraker-notify-macro"},
      {"", "no source"},
      {url, "--moonraker http://127.0.0.1"},  // no webcam to be had: nothing listens
  };
  for (const auto& [args, expected] : cases) {
    const testing::RunResult r = testing::RunCli("watch --scale-um-per-px 3 " + args, *dir_);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.err.find("s3cret"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace clogscope::apps
