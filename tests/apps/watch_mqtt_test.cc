// `clogscope watch --mqtt` against a real broker: mosquitto started by the test on a free localhost
// port, what it delivers read with mosquitto_sub. A rendered strand narrowing by 10 % drives the
// level to clog; the last will is seen after SIGKILL, "offline" after a clean stop.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "apps/watch_command.h"
#include "common/spawn.h"
#include "synthetic/synthetic.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/external_process.h"
#include "tests/apps/mqtt_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

using namespace mqtt_testing;  // NOLINT: the broker and subscriber of these tests
using testing::FreeLoopbackPort;

// Observers that hold the watch back until the broker has the publisher's "online" (*online says
// whether it came): a file read as fast as it decodes would otherwise be over before.
WatchObservers StartOnceOnline(Subscriber* sub, const std::string& prefix, bool* online) {
  WatchObservers observers;
  observers.on_started = [=](int) {
    *online = sub->WaitFor(Subscriber::Has(prefix + "/availability", "online"), 10);
  };
  return observers;
}

class WatchMqttTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (MosquittoBinary().empty())
      GTEST_SKIP() << "no mosquitto broker installed (Debian package "
                      "mosquitto): the MQTT tests need a real one";
  }
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::FreshDir("clogscope_mqtt_" + std::to_string(getpid())));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  // 10 s at 25 frames/s of a 400 µm strand (3 µm/px, 2 µm jitter) narrowing to 360 µm at 4 s.
  static std::string Video() {
    const fs::path video = *dir_ / "clog.avi";
    if (fs::exists(video)) return video.string();
    synthetic::SceneParams s = testing::WatchCameraScene(7);
    for (int i = 0; i < 250; ++i) s.frame_width_um.push_back(i / 25.0 >= 4.0 ? 360.0 : 400.0);
    synthetic::RenderSequence(s, 250, 25, video.string(), (*dir_ / "clog.truth.json").string());
    return video.string();
  }
  static WatchCommandOptions Options(const std::string& prefix, int port) {
    WatchCommandOptions o;
    o.live.source = Video();
    o.measure.scale_um_per_px = 3.0;
    o.live.report_every_s = 1.0;
    o.live.watch.baseline_s = 3;
    o.live.watch.window_s = 3;
    o.log_path = (*dir_ / (std::to_string(port) + ".jsonl")).string();
    o.mqtt.url = "mqtt://127.0.0.1:" + std::to_string(port) + "/" + prefix;
    return o;
  }
  static fs::path* dir_;
};
fs::path* WatchMqttTest::dir_ = nullptr;

TEST_F(WatchMqttTest, ABrokerGetsDiscoveryOnlineTheStateTheClogAndOfflineOnACleanStop) {
  Broker broker(*dir_, FreeLoopbackPort());
  ASSERT_TRUE(broker.WaitReady(10));
  const std::string prefix = "test/clean";
  Subscriber sub(*dir_, "clean", broker.port(), {prefix + "/#", "homeassistant/+/test_clean/#"});
  ASSERT_TRUE(sub.WaitSubscribed(prefix + "/probe", 10));

  WatchCommandOptions o = Options(prefix, broker.port());
  bool online = false;
  WatchObservers observers = StartOnceOnline(&sub, prefix, &online);
  double clog_told_unix_s = 0;
  observers.on_level_change = [&](const watch::WatchStatus& s) {
    if (s.level == watch::WatchLevel::kClog && clog_told_unix_s == 0) clog_told_unix_s = UnixNow();
  };
  std::atomic<bool> stop{false};
  const WatchReport r = WatchNozzle(o, &stop, observers);
  ASSERT_TRUE(online);
  EXPECT_EQ(r.summary.final_level, watch::WatchLevel::kClog);
  // A clean stop says "offline" itself (WatchNozzle waited for the broker's acknowledgement).
  ASSERT_TRUE(sub.WaitFor(Subscriber::Has(prefix + "/availability", "offline"), 0.5));
  const std::vector<Received> all = sub.Messages();

  // "online" first, then the discovery configs, then the states.
  const auto index = [&](const std::function<bool(const Received&)>& pred) {
    for (size_t i = 0; i < all.size(); ++i)
      if (pred(all[i])) return static_cast<long>(i);
    return -1L;
  };
  const long online_at =
      index([&](const Received& m) { return m.topic == prefix + "/availability"; });
  const long config_at =
      index([&](const Received& m) { return m.topic.rfind("homeassistant/", 0) == 0; });
  const long state_at = index([&](const Received& m) { return m.topic == prefix + "/state"; });
  ASSERT_GE(online_at, 0);
  EXPECT_EQ(all[online_at].payload, "online");
  EXPECT_LT(online_at, config_at);
  EXPECT_LT(config_at, state_at);
  std::set<std::string> configs;
  for (const Received& m : all) {
    if (m.topic.rfind("homeassistant/", 0) != 0) continue;
    configs.insert(m.topic);
    const json j = json::parse(m.payload);
    EXPECT_EQ(j["availability_topic"], prefix + "/availability") << m.topic;
    EXPECT_EQ(j["device"]["identifiers"][0], "clogscope_test_clean") << m.topic;
  }
  EXPECT_EQ(configs, (std::set<std::string>{"homeassistant/binary_sensor/test_clean/clog/config",
                                            "homeassistant/sensor/test_clean/diameter/config",
                                            "homeassistant/sensor/test_clean/level/config",
                                            "homeassistant/sensor/test_clean/drift/config",
                                            "homeassistant/camera/test_clean/frame/config"}));

  // The states: ok with the strand's 0.4 mm, then clog at 0.36 mm.
  const std::vector<Received> states = On(all, prefix + "/state");
  ASSERT_GE(states.size(), 3u);
  const json first = json::parse(states.front().payload), last = json::parse(states.back().payload);
  EXPECT_EQ(first["level"], "ok");
  EXPECT_EQ(last["level"], "clog");
  EXPECT_EQ(last["clog"], true);
  EXPECT_NEAR(last["diameter_mm"].get<double>(), 0.360, 0.003);
  EXPECT_NEAR(last["baseline_mm"].get<double>(), 0.400, 0.003);
  EXPECT_LT(last["drift_pct"].get<double>(), -5.0);
  EXPECT_GT(last["diameter_ci95_mm"].get<double>(), 0.0);
  EXPECT_EQ(On(all, prefix + "/level").back().payload, "clog");
  EXPECT_NEAR(std::stod(On(all, prefix + "/diameter_mm").back().payload), 0.360, 0.003);
  // The level change to clog reached the subscriber soon after the watch told it.
  ASSERT_GT(clog_told_unix_s, 0);
  double clog_seen_unix_s = 0;
  for (const Received& m : states)
    if (json::parse(m.payload)["level"] == "clog") {
      clog_seen_unix_s = m.unix_s;
      break;
    }
  ASSERT_GT(clog_seen_unix_s, 0);
  std::cout << "level change to clog, told by the watch -> received by mosquitto_sub: "
            << (clog_seen_unix_s - clog_told_unix_s) * 1e3 << " ms\n";
  EXPECT_LT(clog_seen_unix_s - clog_told_unix_s, 0.5);
  // The camera's picture: JPEG bytes.
  const std::vector<Received> frames = On(all, prefix + "/frame");
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames.back().payload.substr(0, 2), "\xff\xd8");
  EXPECT_EQ(On(all, prefix + "/availability").back().payload, "offline");

  // What stays on the broker for a newcomer (Home Assistant starting later): all retained.
  Subscriber later(*dir_, "clean_retained", broker.port(),
                   {prefix + "/#", "homeassistant/+/test_clean/#"}, {"--retained-only"});
  ASSERT_TRUE(later.WaitFor([](const auto& m) { return m.size() >= 10; }, 10));
  std::map<std::string, std::string> retained;
  for (const Received& m : later.Messages()) {
    EXPECT_TRUE(m.retained) << m.topic;
    retained[m.topic] = m.payload;
  }
  EXPECT_EQ(retained.size(), 10u);  // 5 configs, state, level, diameter_mm, frame, availability
  EXPECT_EQ(retained[prefix + "/availability"], "offline");
  EXPECT_EQ(retained[prefix + "/level"], "clog");
  EXPECT_EQ(json::parse(retained[prefix + "/state"])["level"], "clog");
}

TEST_F(WatchMqttTest, ABrokerStartedLateIsFoundAndTheLastWillSaysOfflineAfterSigkill) {
  const int port = FreeLoopbackPort();
  const std::string prefix = "test/kill";
  const fs::path err = *dir_ / "kill.err";
  SpawnOptions run;
  run.argv = {CLOGSCOPE_BINARY,
              "watch",
              Video(),
              "--realtime",
              "--scale-um-per-px",
              "3",
              "--report-s",
              "0.5",
              "--log",
              (*dir_ / "kill.jsonl").string(),
              "--mqtt",
              "mqtt://127.0.0.1:" + std::to_string(port) + "/" + prefix};
  run.stderr_path = err.string();
  std::string why;
  pid_t pid = Spawn(run, &why);
  ASSERT_GT(pid, 0) << why;
  // No broker yet: a warning, and the watch goes on.
  GrowingFile log(err);
  const bool warned = log.WaitFor(
      [](const std::string& t) { return t.find("cannot connect") != std::string::npos; }, 10);
  Broker broker(*dir_, port);
  ASSERT_TRUE(broker.WaitReady(10));
  Subscriber sub(*dir_, "kill", port, {prefix + "/#"});
  ASSERT_TRUE(sub.WaitSubscribed(prefix + "/probe", 10));
  EXPECT_TRUE(warned) << log.Text();
  // Found within the back-off (1 s, then 2 s, …), and a state published.
  ASSERT_TRUE(sub.WaitFor(Subscriber::Has(prefix + "/availability", "online"), 15)) << log.Text();
  ASSERT_TRUE(sub.WaitFor([&](const auto& all) { return !On(all, prefix + "/state").empty(); }, 10))
      << log.Text();
  EXPECT_NE(
      log.Text().find("publishing to mqtt://127.0.0.1:" + std::to_string(port) + "/" + prefix),
      std::string::npos)
      << log.Text();
  Stop(&pid, SIGKILL);
  // The broker sees the connection drop and publishes the last will.
  ASSERT_TRUE(sub.WaitFor(
      [&](const auto& all) {
        const auto a = On(all, prefix + "/availability");
        return !a.empty() && a.back().payload == "offline";
      },
      10));
}

TEST_F(WatchMqttTest, ADeadBrokerNeitherStopsNorDelaysTheWatch) {
  // Nothing listens on the port (refused at once), or nothing answers at all (a black hole).
  for (const std::string& host :
       {"127.0.0.1:" + std::to_string(FreeLoopbackPort()), std::string("10.255.255.1:1883")}) {
    WatchCommandOptions o = Options("test/dead", 0);
    o.mqtt.url = "mqtt://" + host + "/test/dead";
    o.live.duration_s = 0.5;  // of the file's frames, however many are read by then
    std::atomic<bool> stop{false};
    const auto t0 = Clock::now();
    const WatchReport r = WatchNozzle(o, &stop);
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    std::cout << "mqtt://" << host << ": the watch ended " << seconds - r.summary.seconds
              << " s after its last frame\n";
    EXPECT_GT(r.summary.frames, 0) << host;
    EXPECT_LT(seconds - r.summary.seconds, 2.0) << host;
  }
  // A broker that hangs while connected: "offline" is never acknowledged.
  Broker broker(*dir_, FreeLoopbackPort());
  ASSERT_TRUE(broker.WaitReady(10));
  const std::string prefix = "test/hung";
  Subscriber sub(*dir_, "hung", broker.port(), {prefix + "/#"});
  ASSERT_TRUE(sub.WaitSubscribed(prefix + "/probe", 10));
  WatchCommandOptions o = Options(prefix, broker.port());
  bool online = false;
  WatchObservers observers = StartOnceOnline(&sub, prefix, &online);
  observers.on_level_change = [&](const watch::WatchStatus&) { broker.Pause(); };
  std::atomic<bool> stop{false};
  const auto t0 = Clock::now();
  const WatchReport r = WatchNozzle(o, &stop, observers);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  ASSERT_TRUE(online);
  std::cout << "a hung broker: the watch ended " << seconds - r.summary.seconds
            << " s after its last frame\n";
  EXPECT_GE(r.summary.level_changes, 1);
  EXPECT_LT(seconds - r.summary.seconds, 2.0);
}

TEST_F(WatchMqttTest, TheCredentialsFileLogsIn) {
  const fs::path passwords = *dir_ / "passwords", credentials = *dir_ / "credentials";
  SpawnOptions passwd;
  passwd.argv = {"mosquitto_passwd", "-b", "-c", passwords.string(), "farm", "s3cret:x"};
  std::string why;
  const pid_t p = Spawn(passwd, &why);
  ASSERT_TRUE(p > 0 && WaitForExit(p, &why)) << why;
  std::ofstream(credentials) << "farm:s3cret:x\n";
  Broker broker(*dir_, FreeLoopbackPort(),
                "allow_anonymous false\npassword_file " + passwords.string() + "\n");
  ASSERT_TRUE(broker.WaitReady(10));
  const std::string prefix = "test/login";
  Subscriber sub(*dir_, "login", broker.port(), {prefix + "/#"}, {},
                 {"-u", "farm", "-P", "s3cret:x"});
  ASSERT_TRUE(sub.WaitSubscribed(prefix + "/probe", 10));
  WatchCommandOptions o = Options(prefix, broker.port());
  o.mqtt.credentials_file = credentials.string();
  o.live.duration_s = 0.1;
  bool online = false;
  WatchObservers observers = StartOnceOnline(&sub, prefix, &online);
  std::atomic<bool> stop{false};
  WatchNozzle(o, &stop, observers);
  EXPECT_TRUE(online);
}

TEST_F(WatchMqttTest, BadMqttOptionsGetOneLineNamingTheOption) {
  const std::string video = Video();
  const auto run = [&](const std::string& args) {
    return testing::RunCli("watch " + video + " --scale-um-per-px 3 " + args, *dir_);
  };
  std::vector<std::pair<std::string, std::string>> cases = {
      {"--mqtt http://127.0.0.1/x", "--mqtt 'http://127.0.0.1/x'"},
      {"--mqtt mqtts://127.0.0.1/x", "mqtts"},
      {"--mqtt mqtt://127.0.0.1:0/x", "port"},
      {"--mqtt mqtt://farm:s3cret@127.0.0.1/x", "--mqtt-credentials-file"},
      {"--mqtt mqtt://127.0.0.1/x --mqtt-credentials-file /nonexistent/credentials",
       "--mqtt-credentials-file /nonexistent/credentials: cannot be read"},
      {"--mqtt-credentials-file /nonexistent/credentials",
       "--mqtt-credentials-file goes with --mqtt"}};
  for (const auto& [args, expected] : cases) {
    const testing::RunResult r = run(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(expected), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.find("s3cret"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace clogscope::apps
