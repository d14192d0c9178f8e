#include "pipeline/manifest.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

#include "common/atomic_file.h"
#include "tests/scratch_dir.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

// The manifests' folder, one for the run.
const fs::path& Dir() {
  static const testutil::ScratchDir dir("clogscope_manifest_test");
  return dir.path();
}

std::string Write(const std::string& name, const std::string& text) {
  const fs::path& dir = Dir();
  fs::create_directories(dir / "frames");
  const std::string path = (dir / name).string();
  WriteFileAtomically(path, text);
  return path;
}

std::string ErrorOf(const std::string& path) {
  try {
    LoadManifest(path);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(ManifestTest, ReadsYamlWithPathsRelativeToTheManifest) {
  const Manifest m =
      LoadManifest(Write("ok.yaml",
                         "name: demo\nsamples: 30\nsettle_s: 1.5\nscale_um_per_px: 3\n"
                         "extruder: direct-pla\n"
                         "steps:\n"
                         "  - {step: 1, temperature_c: 220, video: v/step1.mp4, end_s: 8}\n"
                         "  - {step: 2, temperature_c: 210, images: frames, settle_s: 0}\n"));
  ASSERT_EQ(m.steps.size(), 2u);
  EXPECT_EQ(m.samples, 30);
  EXPECT_EQ(m.name, "demo");
  EXPECT_EQ(m.steps[0].video, (Dir() / "v/step1.mp4").string());
  EXPECT_DOUBLE_EQ(m.steps[0].settle_s, 1.5);
  EXPECT_DOUBLE_EQ(m.steps[1].settle_s, 0);
  EXPECT_DOUBLE_EQ(m.steps[0].end_s, 8);
  EXPECT_EQ(m.steps[1].line, 8);
}

TEST(ManifestTest, TargetKey) {
  const std::string steps = "steps:\n  - {step: 1, temperature_c: 220, images: frames}\n";
  EXPECT_EQ(LoadManifest(Write("t0.yaml", steps)).target, "strand");
  EXPECT_EQ(LoadManifest(Write("t1.yaml", "target: filament\n" + steps)).target, "filament");
  const std::string err = ErrorOf(Write("t2.yaml", "target: nozzle\n" + steps));
  EXPECT_NE(err.find("t2.yaml:1"), std::string::npos) << err;
  EXPECT_NE(err.find("strand or filament"), std::string::npos) << err;
}

TEST(ManifestTest, CsvForm) {
  const Manifest m = LoadManifest(Write(
      "steps.csv", "step,temperature_c,source,start_s,end_s\n1,220,a.mp4,,\n2,210,frames,,\n"));
  ASSERT_EQ(m.steps.size(), 2u);
  EXPECT_FALSE(m.steps[0].video.empty());
  EXPECT_FALSE(m.steps[1].images.empty());  // a directory
}

// A folder of images has no frame times: start_s, end_s and settle_s cannot apply to it, and a
// manifest that gives them is refused rather than measured as if they were not there.
TEST(ManifestTest, TimesOnAFolderOfImagesAreRefused) {
  const std::string step = "steps:\n  - {step: 1, temperature_c: 220, images: frames";
  for (const std::string key : {"start_s: 2", "end_s: 5", "settle_s: 1"}) {
    const std::string err = ErrorOf(Write("i.yaml", step + ", " + key + "}\n"));
    EXPECT_NE(err.find("i.yaml:2: step 1: "), std::string::npos) << key << ": " << err;
    EXPECT_NE(err.find("a folder of images has no frame times"), std::string::npos) << err;
  }
  // The manifest's settle_s reaches the step too; the step may set its own to 0.
  std::string err = ErrorOf(Write("i2.yaml", "settle_s: 2\n" + step + "}\n"));
  EXPECT_NE(err.find("i2.yaml:3: step 1: "), std::string::npos) << err;
  EXPECT_NO_THROW(LoadManifest(Write("i3.yaml", "settle_s: 2\n" + step + ", settle_s: 0}\n")));
  err = ErrorOf(Write("i.csv", "step,temperature_c,source,start_s,end_s\n1,220,frames,1,\n"));
  EXPECT_NE(err.find("i.csv:2: step 1: "), std::string::npos) << err;
}

TEST(ManifestTest, ErrorsNameTheKeyAndLine) {
  EXPECT_NE(
      ErrorOf(Write("k.yaml", "samples: 10\nstepz: []\n")).find("k.yaml:2: unknown key 'stepz'"),
      std::string::npos);
  EXPECT_NE(ErrorOf(Write("t.yaml", "samples: many\nsteps: []\n"))
                .find("t.yaml:1: samples: 'many' is not a number"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Write("w.yaml", "samples: 2.5\n")).find("whole number"), std::string::npos);
  EXPECT_NE(ErrorOf(Write("s.yaml", "steps:\n  - {step: 1, temperature_c: 220, vidoe: a.mp4}\n"))
                .find("s.yaml:2: unknown key 'vidoe'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Write("d.yaml",
                          "steps:\n  - {step: 1, temperature_c: 220, video: a.mp4}\n"
                          "  - {step: 1, temperature_c: 210, video: b.mp4}\n"))
                .find("d.yaml:3: step 1 appears twice (also at line 2)"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Write("n.yaml", "steps:\n  - {step: 1, temperature_c: 220}\n"))
                .find("give one of video: or images:"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Write("e.yaml", "name: x\n")).find("no steps"), std::string::npos);
  EXPECT_NE(ErrorOf(Write("bad.yaml", "steps: [\n")).find("bad.yaml:"), std::string::npos);
}

TEST(ManifestTest, LongVideoCutByTheTemperatureLog) {
  std::string log = "time_s,temperature_c\n";
  for (int t = 0; t <= 100; ++t)
    log += std::to_string(t) + "," +
           (t < 40   ? "220"
            : t < 50 ? std::to_string(220 - (t - 40))
                     : "210") +
           "\n";
  Write("temps.csv", log);
  const Manifest m =
      LoadManifest(Write("long.yaml",
                         "video: long.mp4\ntemperature_log: temps.csv\nvideo_start_s: 10\n"
                         "settle_s: 5\nmin_step_s: 10\nhold_tolerance_c: 1\n"));
  ASSERT_EQ(m.steps.size(), 2u);
  EXPECT_NEAR(m.steps[0].temperature_c, 220,
              0.1);                          // the hold's mean; ramp readings within ±1 count
  EXPECT_NEAR(m.steps[0].start_s, 0, 1e-9);  // log 5 s is before the video starts at log 10 s
  EXPECT_NEAR(m.steps[0].end_s, 40 - 10, 1.01);
  EXPECT_NEAR(m.steps[1].temperature_c, 210, 0.1);
  std::string flat = "time_s,temperature_c\n";
  for (int t = 0; t <= 100; ++t) flat += std::to_string(t) + "," + std::to_string(220 - t) + "\n";
  Write("ramp.csv", flat);
  EXPECT_NE(ErrorOf(Write("never.yaml", "video: long.mp4\ntemperature_log: ramp.csv\n"))
                .find("never holds"),
            std::string::npos);
}

}  // namespace
}  // namespace clogscope::pipeline
