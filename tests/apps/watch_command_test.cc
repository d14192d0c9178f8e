// `clogscope watch` end to end: a rendered clog sequence read from a file and served as a real
// HTTP MJPEG stream by FFmpeg, the JSON lines, /status, /metrics, /frame.jpg, the alert command,
// and bad input.
#include "apps/watch_command.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "apps/watch_outputs.h"
#include "common/spawn.h"
#include "synthetic/synthetic.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/http_test_client.h"

extern char** environ;

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using testing::FreshDir;
using testing::RunCli;
using testing::WatchCameraScene;

constexpr double kDropAtS = 12.0;  // the strand narrows by 3 % here
constexpr double kSeconds = 20.0;

// A listening TCP socket on a free loopback port (closed at destruction).
struct Listener {
  int fd = -1;
  int port = 0;
  Listener() {
    fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a));
    listen(fd, 4);
    socklen_t len = sizeof(a);
    getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    port = ntohs(a.sin_port);
  }
  ~Listener() { close(fd); }
};

int FreePort() { return Listener().port; }

// Whether something listens on 127.0.0.1:`port`, read from /proc/net/tcp (no connection made: a
// server that takes one client, as `ffmpeg -listen 1`, must not spend it on the question).
bool Listens(int port) {
  std::ifstream tcp("/proc/net/tcp");
  std::string line;
  std::getline(tcp, line);  // header
  char want[32];
  std::snprintf(want, sizeof want, "0100007F:%04X", port);
  while (std::getline(tcp, line)) {
    std::istringstream fields(line);
    std::string slot, local, remote, state;
    fields >> slot >> local >> remote >> state;
    if (local == want && state == "0A") return true;  // TCP_LISTEN
  }
  return false;
}

class WatchCommandTest : public ::testing::Test {
 protected:
  // 20 s at 25 frames/s of a 400 µm strand (3 µm/px, 2 µm jitter per frame) on 640×360 frames:
  // a purge blob at 3 s for 2 s, something passing in front at 7 s for 0.5 s, and a 3 % narrowing
  // at 12 s.
  static void SetUpTestSuite() {
    dir_ = new fs::path(FreshDir("clogscope_watch_" + std::to_string(getpid())));
  }
  static std::string Video() {
    const fs::path video = *dir_ / "seq.avi";
    if (fs::exists(video)) return video.string();
    synthetic::SceneParams s = WatchCameraScene(5);
    s.purge_start_s = 3;
    s.occlusion_start_s = {7};
    const int frames = static_cast<int>(kSeconds * 25);
    for (int i = 0; i < frames; ++i)
      s.frame_width_um.push_back(i / 25.0 >= kDropAtS ? 388.0 : 400.0);
    synthetic::RenderSequence(s, frames, 25, video.string(), (*dir_ / "seq.truth.json").string());
    return video.string();
  }
  // Ten small frames: enough for the options to be checked against a real file.
  static std::string TinyVideo() {
    const fs::path video = *dir_ / "tiny.avi";
    synthetic::SceneParams s;
    s.width_px = 160;
    s.height_px = 120;
    s.tip_x_px = 80;
    s.tip_y_px = 30;
    s.strand_width_um = 120;
    synthetic::RenderSequence(s, 10, 25, video.string(), (*dir_ / "tiny.truth.json").string());
    return video.string();
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }

  static WatchCommandOptions Options(const std::string& source) {
    WatchCommandOptions o;
    o.live.source = source;
    o.measure.scale_um_per_px = 3.0;
    o.live.report_every_s = 1.0;
    return o;
  }
  static std::vector<nlohmann::json> Lines(const fs::path& log) {
    std::vector<nlohmann::json> out;
    std::ifstream in(log);
    for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
    return out;
  }
  static fs::path* dir_;
};
fs::path* WatchCommandTest::dir_ = nullptr;

TEST_F(WatchCommandTest, AFileRaisesWarnWithinFiveSecondsOfAThreePercentDropAndRunsTheCommand) {
  const fs::path log = *dir_ / "file.jsonl", alerts = *dir_ / "alerts.txt";
  WatchCommandOptions o = Options(Video());
  o.log_path = log.string();
  o.extruder = "direct-pla";
  o.on_alert = "echo \"$CLOGSCOPE_LEVEL $CLOGSCOPE_PREVIOUS_LEVEL $CLOGSCOPE_DRIFT_PCT\" >> " +
               alerts.string();
  std::atomic<bool> stop{false};
  const WatchReport r = WatchNozzle(o, &stop);
  EXPECT_EQ(r.summary.ended_because, "the file ended");
  EXPECT_EQ(r.summary.frames, 500);
  EXPECT_TRUE(r.alert_failures.empty());
  // Exactly one level change, to warn, 2–5 s after the drop (the hold is 2 s): the purge blob and
  // the occlusion raised nothing.
  const auto lines = Lines(log);
  std::vector<nlohmann::json> changes;
  for (const auto& j : lines)
    if (j["event"] == "level") changes.push_back(j);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0]["level"], "warn");
  const double t = changes[0]["time_s"];
  EXPECT_GT(t, kDropAtS + 2.0);
  EXPECT_LE(t, kDropAtS + 5.0);
  // The last line: the drift of the narrowed strand within its CI of −3 %, and the clog index.
  const nlohmann::json& last = lines.back();
  EXPECT_EQ(last["event"], "stop");
  EXPECT_NEAR(last["baseline"]["um"].get<double>(), 400.0, 1.0);
  const double drift = last["drift"]["recent_pct"], ci = last["drift"]["recent_ci95_pct"];
  EXPECT_NEAR(drift, -3.0, std::max(ci, 0.3));
  EXPECT_GT(last["clog_index"]["back_pressure_ratio"].get<double>(), 1.0);
  EXPECT_GT(lines.size(), 18u);  // a status line every second
  // The alert command ran once with the state in its environment.
  std::ifstream in(alerts);
  std::string level, previous;
  double env_drift = 0;
  in >> level >> previous >> env_drift;
  EXPECT_EQ(level, "warn");
  EXPECT_EQ(previous, "ok");
  EXPECT_LT(env_drift, -2.0);
}

TEST_F(WatchCommandTest, AnHttpMjpegStreamFromFfmpegIsWatchedAndServed) {
  // FFmpeg serves the sequence at its frame rate as multipart JPEG over HTTP, as mjpg-streamer
  // and ustreamer do; it starts sending when the watch connects.
  const int stream_port = FreePort();
  const std::string url = "http://127.0.0.1:" + std::to_string(stream_port) + "/stream.mjpg";
  std::vector<std::string> args = {"ffmpeg", "-nostdin", "-loglevel", "error", "-re", "-i",
                                   Video(),  "-c:v",     "mjpeg",     "-q:v",  "2",   "-f",
                                   "mpjpeg", "-listen",  "1",         url};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t ffmpeg = 0;
  ASSERT_EQ(posix_spawnp(&ffmpeg, "ffmpeg", nullptr, nullptr, argv.data(), environ), 0);
  // Until it listens (or gives up): its socket in LISTEN, not a guessed time.
  const auto listen_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!Listens(stream_port) && std::chrono::steady_clock::now() < listen_deadline)
    std::this_thread::yield();
  ASSERT_TRUE(Listens(stream_port)) << "ffmpeg never listened on " << stream_port;

  const fs::path log = *dir_ / "stream.jsonl";
  WatchCommandOptions o = Options(url);
  o.log_path = log.string();
  o.http = "127.0.0.1:0";
  o.live.duration_s = kSeconds + 5;  // past the stream's end: the source drops
  o.live.source_options.read_timeout_s = 2;
  // At every level change the watch has published the new state and waits for its observer, so a
  // real HTTP client (the server answers on its own threads) reads /status while it holds that
  // state: no polling, and no later change can slip in. At warn it reads the rest too.
  int http_port = 0;
  std::set<std::string> seen;  // the levels /status reported: at each change and the one before
  nlohmann::json warn_status;
  std::string metrics, jpeg;
  WatchObservers observers;
  observers.on_started = [&](int port) { http_port = port; };
  observers.on_level_change = [&](const watch::WatchStatus& s) {
    ASSERT_NE(http_port, 0) << "no HTTP port reported";
    const testing::HttpReply res = testing::Get(http_port, "/status");
    ASSERT_EQ(res.status, 200) << "no /status at " << s.time_s << " s";
    const auto j = nlohmann::json::parse(res.body);
    EXPECT_EQ(j["level"], watch::WatchLevelName(s.level));
    seen.insert(j["previous_level"].get<std::string>());
    seen.insert(j["level"].get<std::string>());
    if (j["level"] == "warn" && warn_status.is_null()) {
      warn_status = j;
      metrics = testing::Get(http_port, "/metrics").body;
      if (const auto f = testing::Get(http_port, "/frame.jpg"); f.status == 200) jpeg = f.body;
    }
  };
  std::atomic<bool> stop{false};
  WatchReport report;
  try {
    report = WatchNozzle(o, &stop, observers);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the watch failed: " << e.what();
  }
  kill(ffmpeg, SIGTERM);
  waitpid(ffmpeg, nullptr, 0);

  EXPECT_TRUE(seen.count("ok"));
  ASSERT_FALSE(warn_status.is_null()) << "never saw warn on /status";
  EXPECT_EQ(warn_status["source_kind"], "stream");
  EXPECT_NEAR(warn_status["baseline"]["um"].get<double>(), 400.0, 1.5);
  EXPECT_NE(metrics.find("clogscope_level{level=\"warn\"} 1"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("# TYPE clogscope_frames_total counter"), std::string::npos);
  ASSERT_GT(jpeg.size(), 1000u);
  EXPECT_EQ(static_cast<unsigned char>(jpeg[0]), 0xFF);
  EXPECT_EQ(static_cast<unsigned char>(jpeg[1]), 0xD8);
  // The warn came within 5 s of the drop on the stream's clock (it starts within a second of
  // the watch's), and once the stream ended the watch said no_view while trying to reconnect.
  const auto lines = Lines(log);
  double warn_t = -1;
  for (const auto& j : lines)
    if (j["event"] == "level" && j["level"] == "warn" && warn_t < 0) warn_t = j["time_s"];
  EXPECT_GT(warn_t, kDropAtS + 2.0);
  EXPECT_LE(warn_t, kDropAtS + 5.0 + 1.0);
  EXPECT_EQ(report.summary.final_level, watch::WatchLevel::kNoView);
  EXPECT_EQ(lines.back()["reason"], "the source is down (reconnecting)");
  EXPECT_GT(report.summary.frames, 450);
  std::cout << "stream: " << report.summary.frames << " frames, latency median "
            << report.summary.latency_median_ms << " ms, p95 " << report.summary.latency_p95_ms
            << " ms, warn at " << warn_t << " s\n";
}

// Until `file` holds `text` (bounded): the text's position, or npos.
size_t WaitForText(const fs::path& file, const std::string& text, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(timeout_s));
  for (;;) {
    std::ifstream in(file);
    const std::string content((std::istreambuf_iterator<char>(in)), {});
    if (const size_t at = content.find(text); at != std::string::npos) return at;
    if (std::chrono::steady_clock::now() > deadline) return std::string::npos;
    std::this_thread::yield();
  }
}

// Ctrl-C ends the watch within 2 s whatever its HTTP clients do: half a request sent and then
// nothing, or a picture asked for and never read. The port the server chose (--http HOST:0) is
// told on standard error and in the JSON lines, and the test takes it from there.
TEST_F(WatchCommandTest, SigintEndsTheWatchWithinTwoSecondsWhateverClientsDo) {
  const fs::path log = *dir_ / "sigint.jsonl", err = *dir_ / "sigint.err";
  fs::remove(log);
  SpawnOptions run;
  run.argv = {CLOGSCOPE_BINARY, "watch",       Video(), "--realtime", "--scale-um-per-px", "3",
              "--http",         "127.0.0.1:0", "--log", log.string(), "--report-s",        "0.5"};
  run.stderr_path = err.string();
  run.stdout_path = (*dir_ / "sigint.out").string();
  std::string why;
  const pid_t pid = Spawn(run, &why);
  ASSERT_GT(pid, 0) << why;
  const std::string serving = "on http://127.0.0.1:";
  const size_t at = WaitForText(err, serving, 60);
  if (at == std::string::npos) kill(pid, SIGKILL);
  ASSERT_NE(at, std::string::npos) << ReadFile(err.string());
  const int port = std::stoi(ReadFile(err.string()).substr(at + serving.size()));
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  // The first JSON line says where /status is.
  ASSERT_NE(WaitForText(log, "\"http\":\"" + url + "\"", 60), std::string::npos)
      << ReadFile(log.string());

  std::vector<testing::TestSocket> slow;
  for (int i = 0; i < 20; ++i) {
    slow.emplace_back(port, "127.0.0." + std::to_string(2 + i / 10));
    slow.back().Send("GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ");
  }
  testing::TestSocket reader(port, "127.0.0.1", /*receive_bytes=*/4096);
  reader.Send("GET /frame.jpg HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_EQ(testing::Get(port, "/status").status, 200);  // served while they are held

  const auto t0 = std::chrono::steady_clock::now();
  kill(pid, SIGINT);
  int status = 0;
  pid_t done = 0;
  while ((done = waitpid(pid, &status, WNOHANG)) == 0 &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10))
    std::this_thread::yield();
  const double exit_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (done == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  std::cout << "exit after SIGINT with 21 clients held: " << exit_s * 1e3 << " ms\n";
  ASSERT_EQ(done, pid) << "still running 10 s after SIGINT";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << ReadFile(err.string());
  EXPECT_LT(exit_s, 2.0);
  EXPECT_EQ(Lines(log).back()["event"], "stop");
}

// A camera's password is in no message: the error that ends the watch names the URL without it,
// and the alert command's CLOGSCOPE_SOURCE too.
TEST_F(WatchCommandTest, ACameraPasswordIsShownNowhere) {
  const testing::RunResult r = RunCli(
      "watch http://admin:s3cret@127.0.0.1:" + std::to_string(FreePort()) + "/x --open-timeout-s 2",
      *dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("http://admin:***@127.0.0.1:"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("s3cret"), std::string::npos) << r.err;

  const fs::path env = *dir_ / "alert_env.txt";
  std::string why;
  {
    AlertCommand alert("printf %s \"$CLOGSCOPE_SOURCE\" > " + env.string());
    watch::WatchStatus s;
    ASSERT_TRUE(alert.Run(s, std::nullopt, "rtsp://admin:s3cret@cam.local/stream1", "{}", &why))
        << why;
    EXPECT_TRUE(alert.Reap(/*wait=*/true).empty());
  }
  EXPECT_EQ(ReadFile(env.string()), "rtsp://admin:***@cam.local/stream1");
}

TEST_F(WatchCommandTest, BadInputGetsOneLineNamingTheProblem) {
  const fs::path d = *dir_;
  const std::string video = TinyVideo();
  std::vector<std::string> errors;  // every one must be one line
  const auto run = [&](const std::string& args) {
    const testing::RunResult r = RunCli(args, d);
    errors.push_back(r.err);
    return r;
  };
  auto r = run("watch /nonexistent/video.avi --scale-um-per-px 3");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("/nonexistent/video.avi"), std::string::npos) << r.err;
  // Nothing listens on the port: refused at once.
  r = run("watch http://127.0.0.1:" + std::to_string(FreePort()) + "/x --open-timeout-s 2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot open"), std::string::npos) << r.err;
  {
    // Something listens but never sends a frame.
    Listener silent;
    r = run("watch tcp://127.0.0.1:" + std::to_string(silent.port) + " --open-timeout-s 1.5");
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("--open-timeout-s"), std::string::npos) << r.err;
    // The HTTP port is taken.
    r = run("watch " + video + " --http 127.0.0.1:" + std::to_string(silent.port));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("--http"), std::string::npos) << r.err;
  }
  // The token file: missing, or given without --http.
  r = run("watch " + video + " --http 127.0.0.1:0 --http-token-file /nonexistent/token");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--http-token-file /nonexistent/token"), std::string::npos) << r.err;
  r = run("watch " + video + " --http-token-file /nonexistent/token");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--http-token-file goes with --http"), std::string::npos) << r.err;
  r = run("watch " + video + " --http 127.0.0.1:99999");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--http '127.0.0.1:99999'"), std::string::npos) << r.err;
  r = run("watch " + video + " --warn-pct -3 --clog-pct -2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--clog-pct"), std::string::npos) << r.err;
  r = run("watch " + video + " --baseline-um 400");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--baseline-um"), std::string::npos) << r.err;
  r = run("watch " + video + " --extruder direct-pla");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--extruder"), std::string::npos) << r.err;
  for (const std::string& e : errors) EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
}

}  // namespace
}  // namespace clogscope::apps
