// The feed speed through real codecs: the feedstock scene rendered to video, decoded by clogscope's
// reader and measured as `measure --speed` does (tracked filament, FeedSpeedTracker, the summary),
// its mean against the rendered speed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/speed_summary.h"
#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"
#include "vision/io/frame_source.h"
#include "vision/motion/feed_speed.h"
#include "vision/scene/batch.h"

namespace clogscope::vision {
namespace {

using synthetic::FeedstockScene;
using synthetic::FrameTruth;
using synthetic::RenderSequence;
using synthetic::SceneParams;

namespace fs = std::filesystem;

const double kMmPerPx = FeedstockScene(0).scale_um_per_px / 1e3;
constexpr int kFrames = 61;

fs::path FreshDir(const std::string& name) {
  return testutil::FreshDir("clogscope_feed_codec_" + name);
}

// The frames' truth: the texture's speed along the axis, from the first and last frames.
double TruthMmPerS(const std::vector<FrameTruth>& truth) {
  return (truth.back().feed_offset_px - truth.front().feed_offset_px) /
         (truth.back().time_s - truth.front().time_s) * kMmPerPx;
}

// MJPEG at a camera's quality (ffmpeg's mjpeg at -q:v 8, ~6 KB a frame here): its quantisation
// leaves a block pattern that stays in place. OpenCV's writer offers no quality, so the ffmpeg CLI
// encodes a lossless render.
std::vector<FrameTruth> RenderCameraMjpeg(const SceneParams& p, const fs::path& dir,
                                          std::string* video) {
  const fs::path png = dir / "png";
  const std::vector<FrameTruth> truth = RenderSequence(p, kFrames, 30, png.string(), "");
  *video = (dir / "feed.avi").string();
  const std::string cmd = "ffmpeg -nostdin -v error -y -framerate 30 -i " + png.string() +
                          "/frame_%06d.png -c:v mjpeg -q:v 8 " + *video;
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return truth;
}

struct SpeedRun {
  pipeline::FeedSpeedSummary summary;
  double mean_mm_s = 0, ci95_mm_s = 0;
};

SpeedRun MeasureVideo(const std::string& video) {
  auto source = FrameSource::Open(video);
  StrandMeasureOptions o;
  o.target = MeasureTarget::kFilament;
  FeedSpeedTracker tracker{FeedSpeedOptions{}};
  std::vector<FeedSpeedSample> rows;
  MeasureFrames(*source, o, [&](InputFrame& f, StrandMeasurement& m) {
    rows.push_back(tracker.Next(f.image, f.time_s, m));
  });
  SpeedRun r;
  r.summary = pipeline::SummariseFeedSpeeds(rows);
  r.mean_mm_s = r.summary.mean_px_per_s * kMmPerPx;
  r.ci95_mm_s = r.summary.ci95_px_per_s * kMmPerPx;
  return r;
}

// 0.3 mm/s is 0.5 px per frame, 0.8 mm/s 1.33 px (the cases): with comparisons between
// consecutive frames MJPEG's block pattern read them 7 % and 2 % low.
TEST(FeedSpeedCodecTest, CameraMjpegWithinHalfAPercent) {
  for (double v : {0.3, 0.8}) {
    const fs::path d = FreshDir("mjpeg");
    std::string video;
    const std::vector<FrameTruth> truth = RenderCameraMjpeg(FeedstockScene(v), d, &video);
    const double truth_mm_s = TruthMmPerS(truth);
    ASSERT_NEAR(truth_mm_s, v, 1e-9);
    const SpeedRun r = MeasureVideo(video);
    EXPECT_GE(r.summary.used, 30) << v << " mm/s";
    EXPECT_NEAR(r.mean_mm_s, truth_mm_s, 0.005 * truth_mm_s + 0.005) << v << " mm/s";
  }
}

TEST(FeedSpeedCodecTest, H264WithinHalfAPercent) {
  for (double v : {0.3, 0.8}) {
    const fs::path d = FreshDir("h264");
    const std::string video = (d / "feed.mp4").string();
    const std::vector<FrameTruth> truth = RenderSequence(FeedstockScene(v), kFrames, 30, video, "");
    const double truth_mm_s = TruthMmPerS(truth);
    const SpeedRun r = MeasureVideo(video);
    EXPECT_GE(r.summary.used, 30) << v << " mm/s";
    EXPECT_NEAR(r.mean_mm_s, truth_mm_s, 0.005 * truth_mm_s + 0.005) << v << " mm/s";
  }
}

}  // namespace
}  // namespace clogscope::vision
