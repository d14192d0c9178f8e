// `watch --config`: two cameras in one process on two rendered clips, one narrowing by 3 %, the
// other steady. Only the narrowing one goes to clog, and /status, /metrics (promtool-clean) and
// MQTT (a real mosquitto, read back with mosquitto_sub) say so under its name, with the rendered
// diameters; a camera that fails or never delivers does not stop the others, and a stop ends
// every camera with its stop line.
#include "apps/watch_farm.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "common/atomic_file.h"
#include "common/spawn.h"
#include "common/version.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/external_process.h"
#include "tests/apps/http_test_client.h"
#include "tests/apps/mqtt_test_util.h"
#include "tests/apps/watch_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace mqtt_testing;  // NOLINT: the broker and subscriber

constexpr double kScaleUmPerPx = testing::kClipScaleUmPerPx;
constexpr double kNarrowAtS = 4.0;
constexpr double kBaselineUm = 400.0, kNarrowedUm = 388.0;  // −3 %
constexpr double kToleranceUm = kScaleUmPerPx;              // 1 px
constexpr double kDriftTolerance = 0.005;                   // 0.5 % of the diameter
constexpr double kWindowS = 1.0;                            // the state's window

// The true mean diameter, µm, of the clip's frames in its last window.
double LastWindowTruthUm(const std::vector<synthetic::FrameTruth>& truths) {
  const double end_s = truths.back().time_s;
  return testing::TruthMean(truths, end_s - kWindowS + 1e-6, end_s);
}

// The JSON lines of a log.
std::vector<json> Lines(const fs::path& log) {
  std::vector<json> out;
  std::ifstream in(log);
  for (std::string line; std::getline(in, line);) out.push_back(json::parse(line));
  return out;
}

class WatchFarmTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::FreshDir("clogscope_farm"));
    truths_ = new std::map<std::string, std::vector<synthetic::FrameTruth>>;
    // 10 s at 25 frames/s of a 400 µm strand (3 µm/px, 2 µm jitter), different scenes.
    for (const auto& [name, narrowed_um, seed] :
         {std::tuple{"narrowing", kNarrowedUm, 11}, std::tuple{"steady", kBaselineUm, 12}}) {
      synthetic::SceneParams s = testing::WatchCameraScene(seed);
      for (int i = 0; i < 250; ++i)
        s.frame_width_um.push_back(i / 25.0 >= kNarrowAtS ? narrowed_um : kBaselineUm);
      (*truths_)[name] =
          synthetic::RenderSequence(s, 250, 25, (*dir_ / (std::string(name) + ".avi")).string(),
                                    (*dir_ / (std::string(name) + ".truth.json")).string());
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete truths_;
  }
  void SetUp() override {
    fs::remove(*dir_ / "narrowing.jsonl"), fs::remove(*dir_ / "steady.jsonl");
  }

  // The farm's file: the per-process `top` lines, shared defaults (warn at −1 %, clog at −2 %, a
  // 3-s baseline, a 1-s window), then `cameras`.
  static WatchFarmOptions Config(const std::string& top, const std::string& cameras) {
    const fs::path path = *dir_ / "cameras.yaml";
    std::ofstream(path) << top
                        << "defaults:\n  scale_um_per_px: 3\n  baseline_s: 3\n  window_s: 1\n"
                           "  alert_window_s: 1\n  warn_pct: -1\n  clog_pct: -2\n  report_s: 1\n"
                           "cameras:\n"
                        << cameras;
    return LoadWatchConfig(path.string());
  }
  static std::string TwoCameras() {
    return "  - {name: narrowing, source: narrowing.avi, log: narrowing.jsonl}\n"
           "  - {name: steady, source: steady.avi, log: steady.jsonl}\n";
  }

  static fs::path* dir_;
  static std::map<std::string, std::vector<synthetic::FrameTruth>>* truths_;
};
fs::path* WatchFarmTest::dir_ = nullptr;
std::map<std::string, std::vector<synthetic::FrameTruth>>* WatchFarmTest::truths_ = nullptr;

TEST_F(WatchFarmTest, OnlyTheNarrowingCameraClogsAndStatusAndMetricsSaySoUnderItsName) {
  const std::string promtool = FindOnPath("promtool");
  ASSERT_FALSE(promtool.empty()) << "promtool is not installed (Debian package prometheus)";
  const WatchFarmOptions farm = Config("http: 127.0.0.1:0\n", TwoCameras());
  std::map<std::string, std::vector<std::string>> changes;  // per camera, the levels entered
  std::mutex mutex;
  WatchFarmObservers observers;
  observers.on_level_change = [&](const std::string& printer, const watch::WatchStatus& s) {
    std::lock_guard<std::mutex> lock(mutex);
    changes[printer].push_back(watch::WatchLevelName(s.level));
  };
  bool checked = false;
  observers.on_finished = [&](int port) {
    checked = true;
    // /status: both cameras by name, each with its own level and diameter.
    const testing::HttpReply status = testing::Get(port, "/status");
    ASSERT_EQ(status.status, 200) << status.body;
    const json all = json::parse(status.body)["cameras"];
    ASSERT_EQ(all.size(), 2u) << status.body;
    EXPECT_EQ(all["narrowing"]["level"], "clog");
    EXPECT_EQ(all["steady"]["level"], "ok");
    for (const std::string name : {"narrowing", "steady"}) {
      const json& c = all[name];
      EXPECT_EQ(c["printer"], name);
      EXPECT_EQ(c["source"], (*dir_ / (name + ".avi")).string());
      EXPECT_NEAR(c["diameter"]["um"].get<double>(), LastWindowTruthUm(truths_->at(name)),
                  kToleranceUm)
          << name;
      // One camera's own path serves the same state.
      const testing::HttpReply own = testing::Get(port, "/cameras/" + name + "/status");
      ASSERT_EQ(own.status, 200);
      EXPECT_EQ(json::parse(own.body)["level"], c["level"]) << name;
      const testing::HttpReply frame = testing::Get(port, "/cameras/" + name + "/frame.jpg");
      EXPECT_EQ(frame.status, 200) << name;
      EXPECT_EQ(frame.body.substr(0, 2), "\xFF\xD8") << name << ": a JPEG";
      const testing::HttpReply page = testing::Get(port, "/cameras/" + name + "/");
      EXPECT_EQ(page.status, 200) << name;
      EXPECT_NE(page.body.find("<html"), std::string::npos) << name;
    }
    EXPECT_EQ(testing::Get(port, "/cameras/absent/status").status, 404);
    EXPECT_EQ(testing::Get(port, "/cameras/steady").status, 302);  // to the page's folder
    const testing::HttpReply index = testing::Get(port, "/");
    EXPECT_EQ(index.status, 200);
    EXPECT_NE(index.body.find("href=\"cameras/narrowing/\""), std::string::npos) << index.body;

    // /metrics: promtool-clean, every camera's series labelled.
    const testing::HttpReply r = testing::Get(port, "/metrics");
    ASSERT_EQ(r.status, 200);
    const testing::ProgramResult check =
        testing::RunWithInput({promtool, "check", "metrics"}, r.body);
    EXPECT_EQ(check.exit_code, 0) << check.output << "\n" << r.body;
    EXPECT_EQ(check.output, "") << "lint remarks";
    const std::map<std::string, double> m = testing::ParseMetrics(r.body);
    for (const std::string name : {"narrowing", "steady"}) {
      const std::string p = "printer=\"" + name + "\"";
      const double truth_um = LastWindowTruthUm(truths_->at(name));
      const double baseline_truth_um = testing::TruthMean(truths_->at(name), 0, 3.0 - 1e-6);
      EXPECT_NEAR(testing::At(m, "clogscope_strand_diameter_meters{" + p + "}"), truth_um * 1e-6,
                  kToleranceUm * 1e-6)
          << name;
      EXPECT_NEAR(testing::At(m, "clogscope_strand_drift_ratio{" + p + "}"),
                  truth_um / baseline_truth_um - 1, kDriftTolerance)
          << name;
      const bool clog = name == "narrowing";
      EXPECT_EQ(testing::At(m, "clogscope_level{" + p + ",level=\"clog\"}"), clog ? 1 : 0) << name;
      EXPECT_EQ(testing::At(m, "clogscope_level{" + p + ",level=\"ok\"}"), clog ? 0 : 1) << name;
      EXPECT_EQ(testing::At(m, "clogscope_alerts_total{" + p + ",level=\"clog\"}"), clog ? 1 : 0)
          << name;
      EXPECT_EQ(testing::At(m, "clogscope_frames_total{" + p + "}"), 250) << name;
      // Its file ended: served on as a source that is down, with what it last measured.
      EXPECT_EQ(testing::At(m, "clogscope_source_up{" + p + "}"), 0) << name;
    }
    EXPECT_EQ(testing::At(m, std::string("clogscope_build_info{version=\"") + kVersion + "\"}"), 1);
    // Each family once: as many HELP lines as families.
    std::set<std::string> helps;
    std::istringstream in(r.body);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("# HELP ", 0) == 0) {
        EXPECT_TRUE(helps.insert(line).second) << line;
      }
  };
  std::atomic<bool> stop{false};
  const WatchFarmReport report = WatchFarm(farm, &stop, observers);
  ASSERT_TRUE(checked);
  EXPECT_TRUE(report.errors.empty()) << report.errors.front();
  ASSERT_EQ(report.names, (std::vector<std::string>{"narrowing", "steady"}));
  EXPECT_EQ(report.cameras[0].summary.final_level, watch::WatchLevel::kClog);
  EXPECT_EQ(report.cameras[1].summary.final_level, watch::WatchLevel::kOk);
  EXPECT_EQ(report.cameras[1].summary.level_changes, 0);
  EXPECT_TRUE(changes["steady"].empty());
  ASSERT_FALSE(changes["narrowing"].empty());
  EXPECT_EQ(changes["narrowing"].back(), "clog");
  // Each camera's own log, every line naming it, ending with its stop line.
  for (const std::string name : {"narrowing", "steady"}) {
    const std::vector<json> lines = Lines(*dir_ / (name + ".jsonl"));
    ASSERT_FALSE(lines.empty()) << name;
    for (const json& l : lines) EXPECT_EQ(l["printer"], name);
    EXPECT_EQ(lines.back()["event"], "stop") << name;
  }
}

TEST_F(WatchFarmTest, OneCameraBehindATokenIsServedUnderItsName) {
  const std::string token = "farm-token-0123456789abcdef";
  std::ofstream(*dir_ / "token") << token << "\n";
  const WatchFarmOptions farm = Config("http: 127.0.0.1:0\nhttp_token_file: token\n",
                                       "  - {name: solo, source: steady.avi, log: steady.jsonl}\n");
  bool checked = false;
  WatchFarmObservers observers;
  observers.on_finished = [&](int port) {
    checked = true;
    // The page of the one camera is where / sends a browser (the token's fragment follows).
    const testing::HttpReply root = testing::Get(port, "/");
    EXPECT_EQ(root.status, 302);
    EXPECT_NE(root.head.find("Location: /cameras/solo/\r\n"), std::string::npos) << root.head;
    // The token guards the state, not the page nor /metrics.
    EXPECT_EQ(testing::Get(port, "/cameras/solo/").status, 200);
    EXPECT_EQ(testing::Get(port, "/metrics").status, 200);
    EXPECT_EQ(testing::Get(port, "/cameras/solo/status").status, 401);
    EXPECT_EQ(testing::Get(port, "/status").status, 401);
    const std::string bearer = "Authorization: Bearer " + token + "\r\n";
    const testing::HttpReply status = testing::Get(port, "/cameras/solo/status", bearer);
    ASSERT_EQ(status.status, 200);
    const json j = json::parse(status.body);
    EXPECT_EQ(j["printer"], "solo");
    EXPECT_EQ(j["level"], "ok");
    EXPECT_NEAR(j["diameter"]["um"].get<double>(), LastWindowTruthUm(truths_->at("steady")),
                kToleranceUm);
    const testing::HttpReply history = testing::Get(port, "/cameras/solo/history.json", bearer);
    EXPECT_EQ(history.status, 200);
    EXPECT_NO_THROW(json::parse(history.body));
  };
  std::atomic<bool> stop{false};
  WatchFarm(farm, &stop, observers);
  EXPECT_TRUE(checked);
}

TEST_F(WatchFarmTest, MqttCarriesEachCameraUnderItsNameOverOneConnection) {
  if (MosquittoBinary().empty()) GTEST_SKIP() << "no mosquitto broker (Debian package mosquitto)";
  Broker broker(*dir_, testing::FreeLoopbackPort());
  ASSERT_TRUE(broker.WaitReady(10));
  Subscriber sub(*dir_, "farm", broker.port(), {"farm/#", "homeassistant/#"});
  ASSERT_TRUE(sub.WaitSubscribed("farm/probe", 10));
  const WatchFarmOptions farm =
      Config("mqtt: mqtt://127.0.0.1:" + std::to_string(broker.port()) + "/farm\n", TwoCameras());
  WatchFarmObservers observers;
  bool online = false;
  // Held until the broker has "online": the clips would otherwise be read before it connects.
  observers.on_started = [&](int) {
    online = sub.WaitFor(Subscriber::Has("farm/availability", "online"), 10);
  };
  std::atomic<bool> stop{false};
  const WatchFarmReport report = WatchFarm(farm, &stop, observers);
  ASSERT_TRUE(online);
  ASSERT_TRUE(report.errors.empty()) << report.errors.front();
  // The clean stop's "offline" comes after every camera's last state.
  ASSERT_TRUE(sub.WaitFor(Subscriber::Has("farm/availability", "offline"), 5));
  const std::vector<Received> all = sub.Messages();

  // One availability for the process; one Home Assistant device per camera, each pointing at it.
  std::set<std::string> unique_ids, devices;
  int configs = 0;
  for (const Received& m : all) {
    if (m.topic.rfind("homeassistant/", 0) != 0) continue;
    ++configs;
    const json j = json::parse(m.payload);
    EXPECT_EQ(j["availability_topic"], "farm/availability") << m.topic;
    EXPECT_TRUE(unique_ids.insert(j["unique_id"].get<std::string>()).second) << m.topic;
    devices.insert(j["device"]["identifiers"][0].get<std::string>());
  }
  EXPECT_EQ(configs, 10);  // five entities for each of two cameras
  EXPECT_EQ(devices, (std::set<std::string>{"clogscope_farm_narrowing", "clogscope_farm_steady"}));
  EXPECT_TRUE(On(all, "farm/state").empty()) << "no state outside a camera's topics";

  // Each camera's last state under its name: the narrowing one clogged at its rendered diameter.
  for (const std::string name : {"narrowing", "steady"}) {
    const std::vector<Received> states = On(all, "farm/" + name + "/state");
    ASSERT_FALSE(states.empty()) << name;
    const json last = json::parse(states.back().payload);
    EXPECT_EQ(last["level"], name == "narrowing" ? "clog" : "ok") << name;
    EXPECT_NEAR(last["diameter_um"].get<double>(), LastWindowTruthUm(truths_->at(name)),
                kToleranceUm)
        << name;
    const std::vector<Received> levels = On(all, "farm/" + name + "/level");
    ASSERT_FALSE(levels.empty()) << name;
    EXPECT_EQ(levels.back().payload, name == "narrowing" ? "clog" : "ok") << name;
  }
}

// --duration-s ends the farm even while a camera still waits to start (its Moonraker silent).
TEST_F(WatchFarmTest, TheDurationEndsAFarmWhoseCameraNeverStarts) {
  WatchFarmOptions farm = Config("", "  - {name: off, moonraker: 'http://127.0.0.1:" +
                                         std::to_string(testing::FreeLoopbackPort()) + "'}\n");
  farm.duration_s = 0.3;
  std::atomic<bool> stop{false};
  const WatchFarmReport report = WatchFarm(farm, &stop, {});
  ASSERT_EQ(report.cameras.size(), 1u);
  EXPECT_EQ(report.cameras[0].summary.frames, 0);
}

TEST_F(WatchFarmTest, AFailedCameraLeavesTheOthersAndAStopEndsEveryCameraWithItsStopLine) {
  // "broken" is not a video: it fails at the start. "idle" is a folder no camera writes into: it
  // never ends by itself. "off" is to watch its printer's webcam, and its Moonraker does not
  // answer (a port nothing listens on): the farm starts all the same, and it is asked again until
  // the stop. "narrowing" goes on to clog; the stop comes there, as Ctrl-C would.
  fs::create_directories(*dir_ / "idle");
  std::ofstream(*dir_ / "broken.avi") << "not a video";
  const std::string dead_moonraker =
      "http://127.0.0.1:" + std::to_string(testing::FreeLoopbackPort());
  const WatchFarmOptions farm =
      Config("",
             "  - {name: broken, source: broken.avi}\n"
             "  - {name: idle, source: idle, log: idle.jsonl}\n"
             "  - {name: narrowing, source: narrowing.avi, log: narrowing.jsonl}\n"
             "  - {name: off, moonraker: '" +
                 dead_moonraker + "'}\n");
  std::atomic<bool> stop{false};
  WatchFarmObservers observers;
  observers.on_level_change = [&](const std::string& printer, const watch::WatchStatus& s) {
    if (printer == "narrowing" && s.level == watch::WatchLevel::kClog) stop = true;
  };
  const WatchFarmReport report = WatchFarm(farm, &stop, observers);
  ASSERT_EQ(report.errors.size(), 1u);
  EXPECT_EQ(report.errors[0].rfind("broken: ", 0), 0u) << report.errors[0];
  EXPECT_NE(report.errors[0].find("broken.avi"), std::string::npos) << report.errors[0];
  EXPECT_EQ(report.cameras[2].summary.final_level, watch::WatchLevel::kClog);
  EXPECT_EQ(report.cameras[1].summary.ended_because, "stopped");
  EXPECT_EQ(report.cameras[1].summary.frames, 0);
  EXPECT_EQ(report.cameras[3].summary.frames, 0);  // stopped while waiting to ask again
  for (const std::string name : {"idle", "narrowing"}) {
    const std::vector<json> lines = Lines(*dir_ / (name + ".jsonl"));
    ASSERT_FALSE(lines.empty()) << name;
    EXPECT_EQ(lines.back()["event"], "stop") << name;
    EXPECT_EQ(lines.back()["printer"], name);
  }
}

}  // namespace
}  // namespace clogscope::apps
