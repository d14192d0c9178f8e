#include "pipeline/experiment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"
#include "vision/io/video_io.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

synthetic::SceneParams SmallScene(double width_um, uint64_t seed) {
  synthetic::SceneParams p;
  p.width_px = 640;
  p.height_px = 360;
  p.tip_x_px = 320;
  p.tip_y_px = 100;
  p.strand_width_um = width_um;
  p.width_jitter_um = 2;
  p.seed = seed;
  return p;
}

class ExperimentTest : public ::testing::Test {
 protected:
  std::string Render(const std::string& name, double width_um, int frames, uint64_t seed) {
    const std::string path = (dir_ / name).string();
    truths_[path] = synthetic::RenderSequence(SmallScene(width_um, seed), frames, 25.0, path, "");
    return path;
  }
  ExperimentOptions Options(int samples) {
    ExperimentOptions o;
    o.samples = samples;
    o.out_dir = (dir_ / "out").string();
    o.conversion = PlainScale(3.0);
    o.jobs = 2;
    return o;
  }
  // Steps 1..n at 220, 210, … °C, each a rendered video of 400 − k·narrowing_um µm.
  Manifest VideoSteps(int n, double narrowing_um, int frames) {
    Manifest m;
    m.path = (dir_ / "m.yaml").string();
    m.name = "t";
    for (int i = 0; i < n; ++i) {
      StepSpec s;
      s.step = i + 1;
      s.temperature_c = 220 - 10 * i;
      s.video = Render("s" + std::to_string(i) + ".mp4", 400 - narrowing_um * i, frames, i + 1);
      m.steps.push_back(s);
    }
    return m;
  }
  testutil::ScratchDir scratch_{"clogscope_experiment"};
  const fs::path dir_ = scratch_.path();
  std::map<std::string, std::vector<synthetic::FrameTruth>> truths_;
};

TEST_F(ExperimentTest, StepSamplesEvenlyAndMatchesTruth) {
  StepSpec s;
  s.step = 1;
  s.temperature_c = 220;
  s.video = Render("v.mp4", 390.1, 100, 7);  // 4 s
  s.settle_s = 1.0;
  const StepResult r = MeasureStep(s, Options(15));
  ASSERT_EQ(r.status, model::StepStatus::kOk) << r.detail;
  EXPECT_EQ(r.n_valid, 15);
  EXPECT_EQ(r.n_examined, 15);
  // Frames spread over the settled 3 s: one per 0.2 s slot, from 1.1 s on.
  double truth_sum = 0, prev = 0;
  for (size_t i = 0; i < r.frames.size(); ++i) {
    const auto& f = r.frames[i];
    EXPECT_NEAR(f.time_s, 1.0 + (i + 0.5) * 0.2, 0.021) << i;
    EXPECT_GT(f.time_s, prev);
    prev = f.time_s;
    if (f.used) truth_sum += truths_[s.video][f.frame].width_um;
  }
  EXPECT_EQ(r.n_used + r.n_rejected, 15);
  // The mean against the truth of exactly the frames used: measurement error only.
  EXPECT_NEAR(r.mean_um, truth_sum / r.n_used, 0.15 * 3.0);
  EXPECT_NEAR(r.sem_um, r.std_um / std::sqrt(r.n_used), 1e-9);
  EXPECT_GT(r.ci95_um, 2 * r.sem_um);
}

// A frame that could not be read has no polarity: its row says why (reason) and leaves the
// polarity empty rather than "auto".
TEST(FrameFieldsTest, AnUnreadFrameHasNoPolarity) {
  const auto& cols = FrameColumns();
  const auto column = [&](const char* name) {
    return std::find(cols.begin(), cols.end(), name) - cols.begin();
  };
  vision::StrandMeasurement m;
  m.status = vision::FrameStatus::kUnreadable;
  m.detail = "cannot decode";
  const std::vector<std::string> f = FrameFields("a.png", 3, -1, m, std::nullopt);
  ASSERT_EQ(f.size(), cols.size());
  EXPECT_EQ(f[column("polarity")], "");
  EXPECT_EQ(f[column("reason")], "unreadable");
  EXPECT_EQ(f[column("detail")], "cannot decode");
  // A measured frame keeps the polarity it was measured with.
  m.status = vision::FrameStatus::kValid;
  m.polarity = vision::Polarity::kDarkOnBright;
  EXPECT_EQ(FrameFields("a.png", 3, -1, m, std::nullopt)[column("polarity")], "dark");
}

TEST_F(ExperimentTest, ShortStepsAndBadSourcesAreMarkedNotFatal) {
  StepSpec short_step;
  short_step.step = 1;
  short_step.temperature_c = 220;
  short_step.video = Render("short.mp4", 400, 10, 1);
  const StepResult r = MeasureStep(short_step, Options(20));
  EXPECT_EQ(r.status, model::StepStatus::kTooFewFrames);
  EXPECT_EQ(r.n_valid, 10);
  EXPECT_NE(r.detail.find("10 valid of 20"), std::string::npos);
  StepSpec missing = short_step;
  missing.video = (dir_ / "nope.mp4").string();
  const StepResult m = MeasureStep(missing, Options(20));
  EXPECT_EQ(m.status, model::StepStatus::kFailed);
  EXPECT_NE(m.detail.find("nope.mp4"), std::string::npos);
  StepSpec late = short_step;
  late.start_s = 100;
  EXPECT_EQ(MeasureStep(late, Options(5)).status, model::StepStatus::kFailed);
}

TEST_F(ExperimentTest, RunWritesTablesAndResumes) {
  Manifest m = VideoSteps(3, 5.0, 50);
  m.steps.push_back({4, 190, (dir_ / "missing.mp4").string(), "", 0, -1, 0, 0, ""});
  ExperimentOptions o = Options(10);
  const auto results = RunExperiment(m, o);
  ASSERT_EQ(results.size(), 4u);
  std::vector<std::string> warnings;
  WriteExperimentTables(m, results, o, &warnings);
  const CsvTable t = ParseCsv(ReadFile((dir_ / "out" / "diameters.csv").string()), "diameters.csv");
  for (const char* col : {"step", "temperature_c", "n", "mean_um", "std_um", "sem_um", "ci95_um"}) {
    EXPECT_GE(t.Column(col), 0) << col;
  }
  ASSERT_EQ(t.rows.size(), 4u);
  EXPECT_NEAR(std::stod(t.rows[2][t.Column("mean_um")]), 390, 2.0);
  EXPECT_EQ(t.rows[3][t.Column("status")], "failed");
  EXPECT_TRUE(fs::exists(dir_ / "out" / "frames.csv"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "diameters.json"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "steps" / "step_0002.json"));
  EXPECT_FALSE(fs::is_empty(dir_ / "out" / "overlays"));
  // --resume keeps finished steps (and retries the failed one).
  o.resume = true;
  const auto again = RunExperiment(m, o);
  ASSERT_EQ(again.size(), 4u);
  EXPECT_TRUE(again[0].resumed);
  EXPECT_FALSE(again[3].resumed);
  EXPECT_DOUBLE_EQ(again[1].mean_um, results[1].mean_um);
  // A cancelled run keeps nothing it had not finished.
  std::atomic<bool> cancel{true};
  o.resume = false;
  o.out_dir = (dir_ / "cancelled").string();
  o.cancel = &cancel;
  EXPECT_TRUE(RunExperiment(m, o).empty());
}

// A step whose files cannot be written (its step file is a directory), and a step whose source
// makes the measurement throw: each is reported on its own step; the run and its tables go on.
TEST_F(ExperimentTest, OneStepsErrorDoesNotStopTheRun) {
  Manifest m = VideoSteps(2, 0.0, 30);
  // A 16x16 image: the options' ROI lies outside it, which throws inside the worker.
  const fs::path tiny = dir_ / "tiny";
  fs::create_directories(tiny);
  vision::WriteImageAtomically((tiny / "a.png").string(), cv::Mat(16, 16, CV_8UC1, cv::Scalar(90)));
  m.steps.push_back({3, 200, "", tiny.string(), 0, -1, 0, 0, ""});
  ExperimentOptions o = Options(5);
  o.strand.roi = cv::Rect(0, 0, 600, 300);
  fs::create_directories(dir_ / "out" / "steps" / "step_0002.json");
  std::vector<StepResult> results;
  ASSERT_NO_THROW(results = RunExperiment(m, o));
  ASSERT_EQ(results.size(), 3u);
  EXPECT_EQ(results[0].status, model::StepStatus::kOk) << results[0].detail;
  EXPECT_EQ(results[1].status, model::StepStatus::kOk) << results[1].detail;
  EXPECT_NE(results[1].detail.find("step file not written"), std::string::npos);
  EXPECT_EQ(results[2].status, model::StepStatus::kFailed);
  EXPECT_NE(results[2].detail.find("roi"), std::string::npos) << results[2].detail;
  std::vector<std::string> warnings;
  WriteExperimentTables(m, results, o, &warnings);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "diameters.csv"));
}

// A step of images has no clock: an image's time is its index. Ten images in five slots of two:
// each slot takes the first image that covers its middle (1, 3, 5, 7, 9), as a video's would.
TEST_F(ExperimentTest, AStepOfImagesIsSampledByIndex) {
  const fs::path images = dir_ / "images";
  fs::create_directories(images);
  for (int k = 0; k < 10; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "img_%02d.png", k);
    vision::WriteImageAtomically((images / name).string(),
                                 synthetic::RenderFrame(SmallScene(400, 7), k, nullptr));
  }
  StepSpec s;
  s.step = 1;
  s.temperature_c = 220;
  s.images = images.string();
  const StepResult r = MeasureStep(s, Options(5));
  ASSERT_EQ(r.status, model::StepStatus::kOk) << r.detail;
  std::vector<int> frames;
  for (const auto& f : r.frames) {
    frames.push_back(f.frame);
    EXPECT_EQ(f.time_s, -1);
    char name[32];
    std::snprintf(name, sizeof(name), "img_%02d.png", f.frame);
    EXPECT_EQ(fs::path(f.source).filename(), name);
  }
  EXPECT_EQ(frames, (std::vector<int>{1, 3, 5, 7, 9}));
}

// An error that escapes a step (here the progress callback's) reaches RunExperiment's caller
// after the other workers end, instead of ending the process.
TEST_F(ExperimentTest, AnErrorOutsideAStepReachesTheCaller) {
  const Manifest m = VideoSteps(3, 5.0, 30);
  ExperimentOptions o = Options(5);
  std::atomic<int> reported{0};
  o.on_step = [&](const StepResult& r, int, int) {
    ++reported;
    if (r.spec.step == 2) throw std::runtime_error("progress display failed");
  };
  try {
    RunExperiment(m, o);
    ADD_FAILURE() << "the callback's error was lost";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "progress display failed");
  }
  EXPECT_GE(reported, 1);
  EXPECT_LE(reported, 3);
}

}  // namespace
}  // namespace clogscope::pipeline
