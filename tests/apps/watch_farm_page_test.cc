// A farm's pages in a real browser (headless Chromium, Debian's package chromium): the list at /
// links each camera's page, and a camera's page at /cameras/NAME/ (the single watch's page, its
// data asked for by relative paths) draws that camera's level and diameters, compared with the
// state it serves and the diameter the rendered frames hold. At the camera's first level change
// its watch waits for the observer, so the browser sees a state that holds still.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/watch_config.h"
#include "apps/watch_farm.h"
#include "tests/apps/browser_test_util.h"
#include "tests/apps/http_test_client.h"
#include "tests/apps/watch_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::Attr;
using testing::Axes;
using testing::NumAttr;
using testing::PathVertices;
using testing::Tag;

constexpr double kWindowS = 1.0;
constexpr double kToleranceUm = testing::kClipScaleUmPerPx;  // a pixel

TEST(WatchFarmPageTest, TheListLinksEachCameraAndACamerasPageDrawsItsOwnState) {
  ASSERT_FALSE(FindOnPath("chromium").empty())
      << "chromium is not installed: Debian's package chromium (scripts/install-deps.sh "
         "installs it)";
  const fs::path dir = testing::FreshDir("clogscope_farm_page_" + std::to_string(getpid()));
  const std::vector<synthetic::FrameTruth> truth = testing::RenderNarrowingClip(dir, 17);
  // Two cameras on the clip: "held" is looked at in the browser at its first level change;
  // "other" only has to be listed.
  const fs::path config = dir / "cameras.yaml";
  std::ofstream(config) << "http: 127.0.0.1:0\n"
                           "defaults:\n  scale_um_per_px: 3\n  baseline_s: 3\n  window_s: 1\n"
                           "  alert_window_s: 1\n"
                           "cameras:\n"
                           "  - {name: held, source: clog.avi, log: held.jsonl}\n"
                           "  - {name: other, source: clog.avi, log: other.jsonl}\n";
  const WatchFarmOptions farm = LoadWatchConfig(config.string());
  int port = 0, runs = 0;
  bool checked = false;
  WatchFarmObservers observers;
  observers.on_started = [&](int p) { port = p; };
  observers.on_level_change = [&](const std::string& printer, const watch::WatchStatus& s) {
    if (printer != "held" || checked) return;
    checked = true;
    // The list: a link to each camera's page, handing on the list's fragment (where a token
    // goes: /#token=T).
    const std::string list = testing::Chromium(
        dir, runs++, fmt::format("http://127.0.0.1:{}/#token=probe", port), "--dump-dom");
    EXPECT_NE(
        list.find(fmt::format("href=\"http://127.0.0.1:{}/cameras/held/#token=probe\"", port)),
        std::string::npos)
        << list;
    EXPECT_NE(
        list.find(fmt::format("href=\"http://127.0.0.1:{}/cameras/other/#token=probe\"", port)),
        std::string::npos)
        << list;

    // The held camera's page draws its state: level, and its diameters through the page's axes.
    const std::string base = "/cameras/held/";
    const testing::HttpReply status_reply = testing::Get(port, base + "status");
    ASSERT_EQ(status_reply.status, 200) << status_reply.body;
    const json status = json::parse(status_reply.body);
    const json history = json::parse(testing::Get(port, base + "history.json").body);
    const std::string dom = testing::Chromium(
        dir, runs++, fmt::format("http://127.0.0.1:{}{}", port, base), "--dump-dom");
    EXPECT_EQ(Attr(Tag(dom, "<body"), "data-state"), "live");
    EXPECT_EQ(Attr(Tag(dom, "level"), "data-level"), watch::WatchLevelName(s.level));
    EXPECT_EQ(status["level"], watch::WatchLevelName(s.level));
    EXPECT_EQ(NumAttr(Tag(dom, "frame"), "data-width"), 640);  // its frame.jpg loaded
    const std::string svg = Tag(dom, "plot");
    const Axes axes(svg);
    const size_t served = history["points"].size();
    ASSERT_GE(served, 5u) << history.dump();
    EXPECT_EQ(NumAttr(svg, "data-points"), served);
    const std::vector<cv::Point2d> line = PathVertices(Attr(Tag(dom, "diameter-line"), "d"));
    ASSERT_EQ(line.size(), served);
    const double last_um = axes.Value(line.back().y);
    EXPECT_NEAR(last_um, status["diameter"]["um"].get<double>(), 0.05);
    EXPECT_NEAR(last_um, testing::TruthMean(truth, s.time_s - kWindowS, s.time_s), kToleranceUm);
    const double first_um = axes.Value(line.front().y);
    const double first_t = axes.Time(line.front().x);
    EXPECT_NEAR(first_um, testing::TruthMean(truth, first_t - kWindowS, first_t), kToleranceUm);
  };
  std::atomic<bool> stop{false};
  const WatchFarmReport report = WatchFarm(farm, &stop, observers);
  EXPECT_TRUE(checked) << "the held camera's level never changed";
  EXPECT_TRUE(report.errors.empty()) << report.errors.front();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace clogscope::apps
