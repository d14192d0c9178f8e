// The typed function behind `clogscope measure INPUTS`: the per-frame CSV written atomically, the
// summary, the band resolved from µm or px, and overlays written as the frames go by.
#include "pipeline/measure_inputs.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

fs::path FreshDir(const std::string& name) {
  return testutil::FreshDir("clogscope_measure_inputs_" + name);
}

// A small scene: 640x360 frames, the tip at (320, 100), as `render --size 640x360 --tip-x-px 320
// --tip-y-px 100` writes it: `frames` frames to `out` (a folder or a video), the truth beside them.
std::string RenderSmall(const std::string& out, int frames) {
  synthetic::SceneParams scene;
  scene.width_px = 640;
  scene.height_px = 360;
  scene.tip_x_px = 320;
  scene.tip_y_px = 100;
  const fs::path p(out);
  const fs::path truth =
      p.has_extension() ? p.parent_path() / (p.stem().string() + ".truth.json") : p / "truth.json";
  synthetic::RenderSequence(scene, frames, 25.0, out, truth.string());
  return out;
}

// Overlays are drawn and written as the frames go by: the frames waiting for theirs stay few
// (those whose width-outlier verdict awaits the following frames), however long the video.
TEST(MeasureInputsTest, OverlaysDoNotHoldTheVideo) {
  const fs::path d = FreshDir("overlay_memory");
  MeasureInputsOptions o;
  o.inputs = {RenderSmall((d / "v.mp4").string(), 90)};
  o.out_frames = (d / "frames.csv").string();
  o.overlay_dir = (d / "ov").string();
  o.overlay_every = 1;
  for (const bool flags : {true, false}) {
    o.flag_outliers = flags;
    const MeasureSummary s = MeasureInputs(o);
    EXPECT_EQ(s.frames, 90);
    EXPECT_EQ(s.overlays_written, 90);
    // At most the outlier window's half (25 frames) and the frame in hand; 1 without flags.
    EXPECT_LE(s.overlay_frames_held_peak, flags ? 26 : 1) << "flags " << flags;
    EXPECT_GE(s.overlay_frames_held_peak, 1);
    EXPECT_TRUE(fs::exists(d / "ov" / "v.mp4_000089.png"));
  }
}

TEST(MeasureInputsTest, BandOptionsResolveFromMicronsOrPixels) {
  MeasureInputsOptions o;
  o.inputs = {"x"};
  o.ResolveBand();
  EXPECT_NEAR(o.strand.band_start_px, 50.0 / 3.0, 1e-12);
  EXPECT_NEAR(o.strand.band_height_px, 50.0, 1e-12);
  o.scale_um_per_px = 2.5;
  o.ResolveBand();
  EXPECT_NEAR(o.strand.band_start_px, 20.0, 1e-12);
  EXPECT_NEAR(o.strand.band_height_px, 60.0, 1e-12);
  o.band.height_px = 30;
  o.ResolveBand();
  EXPECT_NEAR(o.strand.band_height_px, 30.0, 1e-12);
  o.band.height_um = 100;
  EXPECT_THROW(o.ResolveBand(), std::invalid_argument);
}

TEST(MeasureInputsTest, TypedFunctionWritesAtomicallyAndSummarises) {
  const fs::path d = FreshDir("typed");
  MeasureInputsOptions o;
  o.inputs = {RenderSmall((d / "png").string(), 3), (d / "nothing-here").string()};
  o.out_frames = (d / "frames.csv").string();
  const MeasureSummary s = MeasureInputs(o);
  EXPECT_EQ(s.inputs_ok, 1);
  EXPECT_EQ(s.inputs_failed, 1);
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.valid_frames, 3);
  EXPECT_TRUE(fs::exists(o.out_frames));
  EXPECT_FALSE(fs::exists(o.out_frames + ".partial"));
  // Without a scale the µm columns stay empty.
  const CsvTable t = ParseCsv(ReadFile(o.out_frames), "frames.csv");
  EXPECT_EQ(t.rows[0][t.Column("width_um")], "");
}

}  // namespace
}  // namespace clogscope::pipeline
