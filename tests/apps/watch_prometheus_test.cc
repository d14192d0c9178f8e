// `clogscope watch --http` for Prometheus: its /metrics checked by promtool (Debian's prometheus
// package), and scraped by a real Prometheus started by the test on localhost, both compared with
// the diameter the rendered frames hold. At its first level change the watch waits for its
// observer with /metrics serving that state, so the test scrapes a state that holds still. The
// dashboard and alert rules in docs/ are checked against the metrics and by promtool.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "apps/watch_command.h"
#include "common/atomic_file.h"
#include "common/spawn.h"
#include "common/version.h"
#include "synthetic/synthetic.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/external_process.h"
#include "tests/apps/http_test_client.h"
#include "tests/apps/watch_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;
using testing::At;
using testing::ParseMetrics;

constexpr double kScaleUmPerPx = testing::kClipScaleUmPerPx;
constexpr double kNarrowAtS = testing::kClipNarrowAtS;
constexpr double kBaselineUm = testing::kClipBaselineUm, kNarrowedUm = testing::kClipNarrowedUm;
// The measurement's accuracy on these rendered frames: a pixel at 3 µm/px (0.8 % of the strand).
constexpr double kToleranceM = kScaleUmPerPx * 1e-6;

// The clogscope_ names a text refers to, a histogram's series by the histogram's name.
std::set<std::string> MetricNames(const std::string& text) {
  static const std::regex name(
      "clogscope_[a-z0-9_]+?(?=_bucket\\b|_sum\\b|_count\\b|[^a-z0-9_]|$)");
  std::set<std::string> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), name); it != std::sregex_iterator();
       ++it)
    out.insert(it->str());
  return out;
}

// Every expression of the dashboard's panels.
std::vector<std::string> DashboardExpressions() {
  const json dashboard =
      json::parse(ReadFile(fs::path(CLOGSCOPE_DOCS_DIR) / "grafana-dashboard.json"));
  std::vector<std::string> out;
  for (const json& panel : dashboard["panels"])
    for (const json& target : panel["targets"]) out.push_back(target["expr"]);
  return out;
}

std::string PercentEncode(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~')
      out += static_cast<char>(c);
    else
      out += fmt::format("%{:02X}", c);
  }
  return out;
}

// The body of an HTTP/1.1 reply sent in chunks, joined.
std::string Dechunk(const testing::HttpReply& r) {
  if (r.head.find("chunked") == std::string::npos) return r.body;
  std::string out;
  size_t at = 0;
  while (at < r.body.size()) {
    const size_t line_end = r.body.find("\r\n", at);
    if (line_end == std::string::npos) break;
    const size_t n = std::stoul(r.body.substr(at, line_end - at), nullptr, 16);
    if (n == 0) break;
    out += r.body.substr(line_end + 2, n);
    at = line_end + 2 + n + 2;
  }
  return out;
}

// Prometheus on a free localhost port, scraping `target` every 200 ms, its data in `dir`. The
// port is chosen by binding port 0 and closing it (Prometheus cannot be told port 0): when another
// program took it meanwhile, Prometheus ends at once and another port is tried.
class Prometheus {
 public:
  Prometheus(const fs::path& dir, const std::string& target) {
    const fs::path config = dir / "prometheus.yml";
    std::ofstream(config) << "global:\n  scrape_interval: 200ms\n  scrape_timeout: 200ms\n"
                             "scrape_configs:\n  - job_name: clogscope\n    static_configs:\n"
                             "      - targets: ['"
                          << target << "']\n";
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    for (int attempt = 0; attempt < 5 && Clock::now() < deadline; ++attempt) {
      port_ = testing::FreeLoopbackPort();
      server_ = std::make_unique<testing::ServerProcess>(std::vector<std::string>{
          FindOnPath("prometheus"), "--config.file=" + config.string(),
          "--storage.tsdb.path=" + (dir / ("data" + std::to_string(attempt))).string(),
          "--web.listen-address=127.0.0.1:" + std::to_string(port_)});
      if (!server_->started()) break;
      // Its log says when it serves; it ends at once when the port is taken.
      if (server_->WaitForLog("Server is ready to receive web requests", deadline)) {
        ready_ = testing::Get(port_, "/-/ready").status == 200;
        return;
      }
      if (server_->log().find("address already in use") == std::string::npos) break;
      log_ += server_->log();
      server_->Stop();
    }
  }
  bool ready() const { return ready_; }
  int port() const { return port_; }
  std::string log() const { return log_ + (server_ ? server_->log() : ""); }
  // /api/v1/query?query=… answered; the parsed JSON (status "success" or "error").
  json Query(const std::string& promql) {
    const testing::HttpReply r =
        testing::Get(port_, "/api/v1/query?query=" + PercentEncode(promql));
    if (r.status == 0) return json{{"status", "no answer"}};
    const json j = json::parse(Dechunk(r), nullptr, false);
    return j.is_object() ? j : json{{"status", "not JSON: " + r.body}};
  }
  // Polls the query until it has a sample, within timeout_s: Prometheus's scrapes are what it waits
  // for, and nothing tells of one. Between queries it reads Prometheus's log for up to 50 ms.
  json QueryUntilResult(const std::string& promql, double timeout_s) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(timeout_s));
    json j;
    while (Clock::now() < deadline) {
      j = Query(promql);
      if (j.value("status", "") == "success" && !j["data"]["result"].empty()) return j;
      server_->ReadFor(50);
    }
    return j;
  }

 private:
  int port_ = 0;
  bool ready_ = false;
  std::unique_ptr<testing::ServerProcess> server_;
  std::string log_;  // of the attempts that found the port taken
};

class WatchPrometheusTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::FreshDir("clogscope_prometheus_" + std::to_string(getpid())));
    truth_ = new std::vector<synthetic::FrameTruth>(testing::RenderNarrowingClip(*dir_, 11));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete truth_;
  }

  // The true mean diameter, m, of the frames within [from_s, to_s].
  static double TruthMeanM(double from_s, double to_s) {
    return 1e-6 * testing::TruthMean(*truth_, from_s, to_s);
  }

  // Watches the video with --http 127.0.0.1:0 and calls check(port, state) at the first level
  // change, while /metrics serves that state; fails when there is none.
  static void WatchHeldAtFirstChange(
      const std::function<void(int port, const watch::WatchStatus&)>& check) {
    WatchCommandOptions o;
    o.live.source = (*dir_ / "clog.avi").string();
    o.measure.scale_um_per_px = kScaleUmPerPx;
    o.live.watch.baseline_s = 3;
    o.live.watch.window_s = 1;  // the state at the change (past 6 s) holds only narrowed frames
    o.live.watch.alert_window_s = 1;
    o.log_path = (*dir_ / "watch.jsonl").string();
    testing::WatchHeldAtFirstChange(o, check);
  }

  static fs::path* dir_;
  static std::vector<synthetic::FrameTruth>* truth_;
};
fs::path* WatchPrometheusTest::dir_ = nullptr;
std::vector<synthetic::FrameTruth>* WatchPrometheusTest::truth_ = nullptr;

TEST_F(WatchPrometheusTest, MetricsPassPromtoolAndTellTheRenderedDiameterInBaseUnits) {
  const std::string promtool = FindOnPath("promtool");
  ASSERT_FALSE(promtool.empty())
      << "promtool is not installed: it comes with Debian's package prometheus "
         "(scripts/install-deps.sh installs it)";
  WatchHeldAtFirstChange([&](int port, const watch::WatchStatus& s) {
    const testing::HttpReply r = testing::Get(port, "/metrics");
    ASSERT_EQ(r.status, 200);
    EXPECT_NE(r.head.find("text/plain; version=0.0.4"), std::string::npos) << r.head;
    const testing::ProgramResult check =
        testing::RunWithInput({promtool, "check", "metrics"}, r.body);
    std::cout << "promtool check metrics: exit " << check.exit_code << ", output '" << check.output
              << "'\n";
    EXPECT_EQ(check.exit_code, 0) << check.output << "\n" << r.body;
    EXPECT_EQ(check.output, "") << "lint remarks";

    const std::map<std::string, double> m = ParseMetrics(r.body);
    // The window (1 s before the change) holds only frames after the narrowing.
    ASSERT_GT(s.time_s - 1.0, kNarrowAtS);
    const double truth_m = TruthMeanM(s.time_s - 1.0, s.time_s);
    const double baseline_truth_m = TruthMeanM(0, 3.0);
    std::cout << "at " << s.time_s << " s (" << watch::WatchLevelName(s.level)
              << "): clogscope_strand_diameter_meters " << At(m, "clogscope_strand_diameter_meters")
              << ", rendered " << truth_m << "\n";
    EXPECT_NEAR(At(m, "clogscope_strand_diameter_meters"), truth_m, kToleranceM);
    EXPECT_NEAR(At(m, "clogscope_strand_baseline_diameter_meters"), baseline_truth_m, kToleranceM);
    EXPECT_NEAR(At(m, "clogscope_strand_drift_ratio"), truth_m / baseline_truth_m - 1, 0.01);
    EXPECT_NEAR(At(m, "clogscope_strand_drift_ratio"),
                At(m, "clogscope_strand_diameter_meters") /
                        At(m, "clogscope_strand_baseline_diameter_meters") -
                    1,
                1e-9);
    EXPECT_GT(At(m, "clogscope_strand_diameter_ci95_meters"), 0);
    EXPECT_LT(At(m, "clogscope_strand_diameter_ci95_meters"), kToleranceM);
    EXPECT_NEAR(At(m, "clogscope_strand_diameter_pixels"),
                At(m, "clogscope_strand_diameter_meters") / (kScaleUmPerPx * 1e-6), 1e-6);
    EXPECT_GT(At(m, "clogscope_window_valid_ratio"), 0.9);
    EXPECT_NEAR(At(m, "clogscope_frame_interval_seconds"), 1 / 25.0, 1e-3);
    // The level, and the change into it counted as one alert.
    for (watch::WatchLevel l : watch::kWatchLevels) {
      const std::string name = watch::WatchLevelName(l);
      EXPECT_EQ(At(m, "clogscope_level{level=\"" + name + "\"}"), l == s.level ? 1 : 0) << name;
      if (watch::IsAlertLevel(l)) {
        EXPECT_EQ(At(m, "clogscope_alerts_total{level=\"" + name + "\"}"), l == s.level ? 1 : 0);
      }
    }
    EXPECT_EQ(At(m, "clogscope_level_changes_total"), 1);
    EXPECT_EQ(At(m, std::string("clogscope_build_info{version=\"") + kVersion + "\"}"), 1);
    // The latency histogram: every frame measured before the one being published, cumulative.
    const double frames = At(m, "clogscope_frames_total");
    const std::string h = "clogscope_frame_latency_seconds";
    EXPECT_EQ(At(m, h + "_count"), frames - 1);
    EXPECT_EQ(At(m, h + "_bucket{le=\"+Inf\"}"), At(m, h + "_count"));
    double previous = 0;
    for (double le : watch::kLatencyBucketsS) {
      const double v = At(m, h + "_bucket{le=\"" + fmt::format("{}", le) + "\"}");
      EXPECT_GE(v, previous) << le;
      previous = v;
    }
    EXPECT_GT(At(m, h + "_sum"), 0);
    EXPECT_LT(At(m, h + "_sum"), 2.0 * At(m, h + "_count"));
  });
}

TEST_F(WatchPrometheusTest, ARealPrometheusScrapesTheWatchAndAnswersTheRenderedDiameter) {
  ASSERT_FALSE(FindOnPath("prometheus").empty())
      << "prometheus is not installed: it comes with Debian's package prometheus "
         "(scripts/install-deps.sh installs it)";
  WatchHeldAtFirstChange([&](int port, const watch::WatchStatus& s) {
    const fs::path dir = *dir_ / "prometheus";
    fs::create_directories(dir);
    const auto t0 = Clock::now();
    Prometheus prometheus(dir, "127.0.0.1:" + std::to_string(port));
    ASSERT_TRUE(prometheus.ready()) << prometheus.log();
    const json j = prometheus.QueryUntilResult("clogscope_strand_diameter_meters", 30);
    ASSERT_EQ(j.value("status", ""), "success") << j.dump() << "\n" << prometheus.log();
    ASSERT_EQ(j["data"]["result"].size(), 1u) << j.dump() << "\n" << prometheus.log();
    const json& sample = j["data"]["result"][0];
    EXPECT_EQ(sample["metric"]["job"], "clogscope");
    EXPECT_EQ(sample["metric"]["instance"], "127.0.0.1:" + std::to_string(port));
    const double scraped_m = std::stod(sample["value"][1].get<std::string>());
    const double truth_m = TruthMeanM(s.time_s - 1.0, s.time_s);
    std::cout << "Prometheus answered clogscope_strand_diameter_meters " << scraped_m
              << " (rendered " << truth_m << ") "
              << std::chrono::duration<double>(Clock::now() - t0).count()
              << " s after it was started\n";
    EXPECT_NEAR(scraped_m, truth_m, kToleranceM);
    // Exactly what the watch serves (the state holds still).
    const auto served = ParseMetrics(testing::Get(port, "/metrics").body);
    EXPECT_EQ(scraped_m, served.at("clogscope_strand_diameter_meters"));

    // The level, and the latency histogram as PromQL reads it.
    const json level = prometheus.Query("clogscope_level == 1");
    ASSERT_EQ(level["data"]["result"].size(), 1u) << level.dump();
    EXPECT_EQ(level["data"]["result"][0]["metric"]["level"], watch::WatchLevelName(s.level));
    const json median =
        prometheus.Query("histogram_quantile(0.5, clogscope_frame_latency_seconds_bucket)");
    ASSERT_EQ(median["data"]["result"].size(), 1u) << median.dump();
    const double median_s = std::stod(median["data"]["result"][0]["value"][1].get<std::string>());
    EXPECT_GT(median_s, 0);
    EXPECT_LE(median_s, 2.0);
    // Every expression of the dashboard is PromQL that Prometheus accepts (Grafana's variables
    // replaced as Grafana would).
    for (std::string e : DashboardExpressions()) {
      e = std::regex_replace(e, std::regex("\\$__rate_interval"), "1m");
      e = std::regex_replace(e, std::regex("\\$instance"), ".*");
      e = std::regex_replace(e, std::regex("\\$printer"), ".*");
      EXPECT_EQ(prometheus.Query(e).value("status", ""), "success") << e;
    }
  });
}

// The dashboard and the alert rules name only metrics the watch serves (a state with everything
// known), and promtool accepts the rules and their behaviour on made-up series.
TEST_F(WatchPrometheusTest, TheDashboardAndAlertRulesInDocsMatchTheMetrics) {
  watch::WatchStatus s;
  s.level = watch::WatchLevel::kWarn;
  s.frame_rate_hz = 25;
  s.has_diameter = s.has_scale = s.baseline_ready = s.has_recent = true;
  s.diameter_px = 130, s.diameter_um = 390, s.diameter_ci95_um = 1, s.baseline_um = 400;
  s.drift_pct = -2.5, s.drift_ci95_pct = 0.3, s.recent_drift_pct = -2.6;
  watch::ClogIndex clog;
  clog.back_pressure_ratio = 1.2;
  std::set<std::string> served;
  for (const auto& [sample, value] : ParseMetrics(watch::PrometheusText(s, clog, {})))
    for (const std::string& n : MetricNames(sample)) served.insert(n);
  for (const std::string& e : DashboardExpressions())
    for (const std::string& n : MetricNames(e)) EXPECT_TRUE(served.count(n)) << n << " in " << e;
  const fs::path rules = fs::path(CLOGSCOPE_DOCS_DIR) / "prometheus-alerts.yml";
  for (const std::string& n : MetricNames(ReadFile(rules)))
    EXPECT_TRUE(served.count(n)) << n << " in " << rules;

  const std::string promtool = FindOnPath("promtool");
  ASSERT_FALSE(promtool.empty()) << "promtool is not installed (Debian package prometheus)";
  const testing::ProgramResult check =
      testing::RunWithInput({promtool, "check", "rules", rules.string()}, "");
  std::cout << check.output;
  EXPECT_EQ(check.exit_code, 0) << check.output;
  const testing::ProgramResult unit = testing::RunWithInput(
      {promtool, "test", "rules",
       (fs::path(CLOGSCOPE_DOCS_DIR) / "prometheus-alerts.test.yml").string()},
      "");
  std::cout << unit.output;
  EXPECT_EQ(unit.exit_code, 0) << unit.output;
}

}  // namespace
}  // namespace clogscope::apps
