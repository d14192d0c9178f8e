// The watch's page at / in a real browser: headless Chromium (Debian's package chromium) loads it
// from a running `watch --http`, and what the page drew is read back from the DOM it left (the
// diameter line and the baseline turned back into µm through the axis the page wrote beside them)
// and from a screenshot, and compared with the diameter the rendered frames hold. At its first
// level change the watch waits for its observer with the server serving that state, so the browser
// sees a state that holds still. Chromium runs virtual time (--virtual-time-budget): the page's
// requests and its one-second refreshes run to completion, then the DOM is dumped; no clock is
// waited on.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "apps/watch_command.h"
#include "common/atomic_file.h"
#include "common/spawn.h"
#include "synthetic/synthetic.h"
#include "tests/apps/browser_test_util.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/external_process.h"
#include "tests/apps/http_test_client.h"
#include "tests/apps/watch_test_util.h"
#include "vision/io/video_io.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;
using testing::Attr;
using testing::Axes;
using testing::NumAttr;
using testing::PathVertices;
using testing::Tag;
using testing::Text;

constexpr double kScaleUmPerPx = testing::kClipScaleUmPerPx;
constexpr double kNarrowAtS = testing::kClipNarrowAtS;
constexpr double kBaselineUm = testing::kClipBaselineUm, kNarrowedUm = testing::kClipNarrowedUm;
constexpr double kWindowS = 1.0;
// The measurement's accuracy on these rendered frames: a pixel at 3 µm/px (0.8 % of the strand).
constexpr double kToleranceUm = kScaleUmPerPx;
// As `base64` makes them: with "+" and "/", which a form decoder would spoil.
constexpr const char* kToken = "page+test/token-0123456789==";
// The page's colours (watch/web/index.html): the diameter line, and clog's.
const cv::Vec3b kLineBgr(180, 119, 31);
const cv::Vec3b kClogBgr(40, 39, 214);

class WatchPageTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::FreshDir("clogscope_page_" + std::to_string(getpid())));
    truth_ = new std::vector<synthetic::FrameTruth>(testing::RenderNarrowingClip(*dir_, 17));
    std::ofstream(*dir_ / "token") << kToken << "\n";
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete truth_;
  }

  // The true mean diameter, µm (or its apparent width in px), of the frames within [from_s, to_s].
  static double TruthMeanUm(double from_s, double to_s, bool px = false) {
    return testing::TruthMean(*truth_, from_s, to_s, px);
  }

  // Watches the video with --http 127.0.0.1:0 (with the token file, with the pixel scale when
  // asked) and calls check(port, state) at the first level change, while the server serves that
  // state.
  static void WatchHeldAtFirstChange(
      bool with_token, const std::function<void(int port, const watch::WatchStatus&)>& check,
      bool with_scale = true) {
    WatchCommandOptions o;
    o.live.source = (*dir_ / "clog.avi").string();
    if (with_scale) o.measure.scale_um_per_px = kScaleUmPerPx;
    o.live.watch.baseline_s = 3;
    o.live.watch.window_s = kWindowS;
    o.live.watch.alert_window_s = kWindowS;
    o.log_path = (*dir_ / "watch.jsonl").string();
    if (with_token) o.http_token_file = (*dir_ / "token").string();
    testing::WatchHeldAtFirstChange(o, check);
  }

  static std::string Chromium(const std::string& url, const std::string& mode,
                              int budget_ms = 3000) {
    return testing::Chromium(*dir_, runs_++, url, mode, budget_ms);
  }

  static fs::path* dir_;
  static std::vector<synthetic::FrameTruth>* truth_;
  static int runs_;
};
fs::path* WatchPageTest::dir_ = nullptr;
std::vector<synthetic::FrameTruth>* WatchPageTest::truth_ = nullptr;
int WatchPageTest::runs_ = 0;

json GetJson(int port, const std::string& path, const std::string& headers = "") {
  const testing::HttpReply r = testing::Get(port, path, headers);
  EXPECT_EQ(r.status, 200) << path << ": " << r.body;
  return json::parse(r.body, nullptr, false);
}

TEST_F(WatchPageTest, TheBrowserDrawsTheRenderedDiameterItsBaselineAndTheLevel) {
  ASSERT_FALSE(FindOnPath("chromium").empty())
      << "chromium is not installed: Debian's package chromium (scripts/install-deps.sh "
         "installs it)";
  WatchHeldAtFirstChange(false, [&](int port, const watch::WatchStatus& s) {
    const std::string url = fmt::format("http://127.0.0.1:{}/", port);
    const json status = GetJson(port, "/status");
    const json history = GetJson(port, "/history.json");
    const std::string dom = Chromium(url, "--dump-dom");
    ASSERT_FALSE(dom.empty());

    const std::string body = Tag(dom, "<body");
    EXPECT_EQ(Attr(body, "data-state"), "live") << Text(dom, "note");
    // Refreshed since the load: the later ones asked for ?since_s= and merged it (the points
    // drawn below are then the served ones, none twice, none lost).
    EXPECT_GE(NumAttr(body, "data-updates"), 2);
    // The level and why, as the state says.
    const std::string level = Tag(dom, "level");
    EXPECT_EQ(Attr(level, "data-level"), watch::WatchLevelName(s.level));
    EXPECT_EQ(status["level"], watch::WatchLevelName(s.level));
    EXPECT_NE(dom.find(">" + s.reason + "<"), std::string::npos) << "the reason is not shown";
    // The latest frame, loaded whole (the scene is 640×360).
    const std::string frame = Tag(dom, "frame");
    EXPECT_EQ(NumAttr(frame, "data-width"), 640);
    EXPECT_EQ(NumAttr(frame, "data-height"), 360);

    // The plot: a point per second of the watch's clock, each drawn at the diameter of its
    // second's window, read back through the page's axes.
    const std::string svg = Tag(dom, "plot");
    const Axes axes(svg);
    const size_t served = history["points"].size();
    ASSERT_GE(served, 5u) << history.dump();
    std::cout << "/history.json: " << served << " points; the newest "
              << history["points"].back().dump() << "\n";
    EXPECT_EQ(NumAttr(svg, "data-points"), served);
    EXPECT_EQ(Attr(svg, "data-unit"), "um");
    const std::vector<cv::Point2d> line = PathVertices(Attr(Tag(dom, "diameter-line"), "d"));
    ASSERT_EQ(line.size(), served) << "one vertex per point";
    int compared = 0;
    double worst_um = 0;
    for (size_t i = 0; i < line.size(); ++i) {
      const double t = axes.Time(line[i].x), drawn_um = axes.Value(line[i].y);
      const json& p = history["points"][i];
      EXPECT_NEAR(t, p["time_s"].get<double>(), 0.05) << i;
      EXPECT_NEAR(drawn_um, p["diameter_um"].get<double>(), 0.05) << i;
      // The windows that hold one width only (not across the narrowing at 4 s).
      if (t - kWindowS < kNarrowAtS && t >= kNarrowAtS) continue;
      const double truth_um = TruthMeanUm(t - kWindowS, t);
      std::cout << fmt::format("  t {:5.2f} s: drawn {:7.2f} µm, rendered {:7.2f} µm, level {}\n",
                               t, drawn_um, truth_um, p["level"].get<std::string>());
      EXPECT_NEAR(drawn_um, truth_um, kToleranceUm) << "at " << t << " s";
      worst_um = std::max(worst_um, std::abs(drawn_um - truth_um));
      ++compared;
    }
    EXPECT_GE(compared, 4);
    std::cout << compared << " points drawn within " << worst_um
              << " µm of the rendered diameter\n";
    // The newest is /status's diameter; the band around it its 95 % CI.
    const double last_um = axes.Value(line.back().y);
    EXPECT_NEAR(last_um, status["diameter"]["um"].get<double>(), 0.05);
    EXPECT_NEAR(last_um, TruthMeanUm(s.time_s - kWindowS, s.time_s), kToleranceUm);
    const std::vector<cv::Point2d> band = PathVertices(Attr(Tag(dom, "ci-band"), "d"));
    ASSERT_EQ(band.size(), 2 * served) << "the CI's upper bounds, then its lower ones back";
    const double high_um = axes.Value(band[served - 1].y), low_um = axes.Value(band[served].y);
    EXPECT_LT(low_um, last_um);
    EXPECT_GT(high_um, last_um);
    EXPECT_NEAR(high_um - low_um, 2 * status["diameter"]["ci95_um"].get<double>(), 0.1);
    // The baseline, dashed, at the first 3 s's diameter.
    const std::string baseline = Tag(dom, "baseline-line");
    EXPECT_EQ(Attr(baseline, "visibility"), "visible");
    const double baseline_um = axes.Value(NumAttr(baseline, "y1"));
    std::cout << "baseline drawn at " << baseline_um << " µm, rendered " << TruthMeanUm(0, 3.0)
              << " µm; latest drawn " << last_um << " µm\n";
    EXPECT_NEAR(baseline_um, TruthMeanUm(0, 3.0), kToleranceUm);
    // The drift shown is the state's, and the rendered one.
    const double drift_pct = NumAttr(Tag(dom, "drift"), "data-pct");
    EXPECT_NEAR(drift_pct, status["drift"]["pct"].get<double>(), 1e-9);
    EXPECT_NEAR(drift_pct,
                100 * (TruthMeanUm(s.time_s - kWindowS, s.time_s) / TruthMeanUm(0, 3.0) - 1), 1.0);

    // What a person sees: the line in its colour, higher (wider) before the narrowing than after,
    // and the level's colour (the badge and the strip below the plot).
    const fs::path png = *dir_ / "page.png";
    Chromium(url, "--screenshot=" + png.string());
    // To look at it: CLOGSCOPE_PAGE_SCREENSHOT=PATH keeps a copy.
    if (const char* keep = std::getenv("CLOGSCOPE_PAGE_SCREENSHOT"))
      fs::copy_file(png, keep, fs::copy_options::overwrite_existing);
    std::string why;
    cv::Mat shot = vision::ReadImage(png.string(), &why);
    ASSERT_FALSE(shot.empty()) << "no screenshot: " << why;
    if (shot.channels() == 4) cv::cvtColor(shot, shot, cv::COLOR_BGRA2BGR);
    ASSERT_EQ(shot.channels(), 3);
    std::cout << "screenshot " << shot.cols << "×" << shot.rows << ", " << fs::file_size(png)
              << " bytes\n";
    const auto near = [](const cv::Vec3b& a, const cv::Vec3b& b) {
      return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) < 30;
    };
    std::vector<cv::Point> line_px;
    int level_px = 0;
    for (int y = 0; y < shot.rows; ++y) {
      for (int x = 0; x < shot.cols; ++x) {
        const cv::Vec3b& c = shot.at<cv::Vec3b>(y, x);
        if (near(c, kLineBgr)) line_px.emplace_back(x, y);
        if (near(c, kClogBgr)) ++level_px;
      }
    }
    std::cout << line_px.size() << " pixels in the line's colour, " << level_px << " in clog's\n";
    ASSERT_GT(line_px.size(), 300u) << "no diameter line in the screenshot";
    if (s.level == watch::WatchLevel::kClog) {
      EXPECT_GT(level_px, 500);
    }
    const cv::Rect span = cv::boundingRect(line_px);
    double first_rows = 0, last_rows = 0;
    int first_n = 0, last_n = 0;
    for (const cv::Point& p : line_px) {
      if (p.x < span.x + span.width / 5) first_rows += p.y, ++first_n;
      if (p.x > span.x + 4 * span.width / 5) last_rows += p.y, ++last_n;
    }
    ASSERT_GT(first_n, 0);
    ASSERT_GT(last_n, 0);
    EXPECT_LT(first_rows / first_n + 20, last_rows / last_n) << "400 µm is not drawn above 360 µm";
  });
}

// With a token, the page itself is open (it holds no data) and every data path still asks for the
// token; the page opened as /#token=TOKEN sends it and draws, without it says so.
TEST_F(WatchPageTest, WithATokenThePageSendsItFromTheFragmentAndTheDataStaysGuarded) {
  ASSERT_FALSE(FindOnPath("chromium").empty())
      << "chromium is not installed: Debian's package chromium (scripts/install-deps.sh "
         "installs it)";
  WatchHeldAtFirstChange(true, [&](int port, const watch::WatchStatus& s) {
    const testing::HttpReply page = testing::Get(port, "/");
    ASSERT_EQ(page.status, 200);
    EXPECT_NE(page.head.find("Content-Type: text/html"), std::string::npos) << page.head;
    EXPECT_NE(page.head.find("Content-Security-Policy: default-src 'none'"), std::string::npos);
    std::cout << "the page: " << page.body.size() << " bytes\n";
    for (const char* path : {"/status", "/history.json", "/history.json?since_s=3", "/frame.jpg"})
      EXPECT_EQ(testing::Get(port, path).status, 401) << path;
    const std::string auth = std::string("Authorization: Bearer ") + kToken + "\r\n";
    const json history = GetJson(port, "/history.json", auth);

    const std::string url = fmt::format("http://127.0.0.1:{}/", port);
    const std::string refused = Chromium(url, "--dump-dom", 1500);
    EXPECT_EQ(Attr(Tag(refused, "<body"), "data-state"), "unauthorized");
    EXPECT_EQ(NumAttr(Tag(refused, "plot"), "data-points"), 0);
    EXPECT_NE(refused.find("#token=TOKEN"), std::string::npos) << "the page does not say how";

    const std::string dom = Chromium(url + "#token=" + kToken, "--dump-dom");
    EXPECT_EQ(Attr(Tag(dom, "<body"), "data-state"), "live") << Text(dom, "note");
    EXPECT_EQ(Attr(Tag(dom, "level"), "data-level"), watch::WatchLevelName(s.level));
    const std::string svg = Tag(dom, "plot");
    EXPECT_EQ(NumAttr(svg, "data-points"), history["points"].size());
    const Axes axes(svg);
    const std::vector<cv::Point2d> line = PathVertices(Attr(Tag(dom, "diameter-line"), "d"));
    ASSERT_FALSE(line.empty());
    EXPECT_NEAR(axes.Value(line.back().y), TruthMeanUm(s.time_s - kWindowS, s.time_s),
                kToleranceUm);
    EXPECT_EQ(NumAttr(Tag(dom, "frame"), "data-width"), 640);
  });
}

// Without a pixel scale the plot is in pixels: the µm fields are null, the line is the apparent
// width.
TEST_F(WatchPageTest, WithoutAScaleThePlotIsInPixels) {
  ASSERT_FALSE(FindOnPath("chromium").empty())
      << "chromium is not installed: Debian's package chromium (scripts/install-deps.sh "
         "installs it)";
  WatchHeldAtFirstChange(
      false,
      [&](int port, const watch::WatchStatus& s) {
        const json history = GetJson(port, "/history.json");
        ASSERT_EQ(history["unit"], "px");
        const std::string dom = Chromium(fmt::format("http://127.0.0.1:{}/", port), "--dump-dom");
        EXPECT_EQ(Attr(Tag(dom, "<body"), "data-state"), "live") << Text(dom, "note");
        EXPECT_EQ(Attr(Tag(dom, "level"), "data-level"), watch::WatchLevelName(s.level));
        const std::string svg = Tag(dom, "plot");
        EXPECT_EQ(Attr(svg, "data-unit"), "px");
        const Axes axes(svg);
        const std::vector<cv::Point2d> line = PathVertices(Attr(Tag(dom, "diameter-line"), "d"));
        ASSERT_EQ(line.size(), history["points"].size());
        const double last_px = axes.Value(line.back().y);
        std::cout << "latest drawn " << last_px << " px, rendered "
                  << TruthMeanUm(s.time_s - kWindowS, s.time_s, true) << " px\n";
        EXPECT_NEAR(last_px, TruthMeanUm(s.time_s - kWindowS, s.time_s, true), 1.0);
        EXPECT_NEAR(axes.Value(NumAttr(Tag(dom, "baseline-line"), "y1")), TruthMeanUm(0, 3.0, true),
                    1.0);
        EXPECT_EQ(PathVertices(Attr(Tag(dom, "ci-band"), "d")).size(), 2 * line.size());
      },
      /*with_scale=*/false);
}

}  // namespace
}  // namespace clogscope::apps
