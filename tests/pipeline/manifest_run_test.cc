#include "pipeline/manifest_run.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "common/atomic_file.h"
#include "model/io.h"
#include "model/prediction_run.h"
#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

class ManifestRunTest : public ::testing::Test {
 protected:
  // Two steps (220 and 210 °C) of 400 and 390 µm rendered at 3 µm/px; the manifest names the
  // scale and the direct-PLA extruder.
  std::string WriteManifest() {
    std::string yaml = "name: t\nsamples: 8\nscale_um_per_px: 3.0\nextruder: direct-pla\nsteps:\n";
    for (int i = 0; i < 2; ++i) {
      synthetic::SceneParams p;
      p.width_px = 640;
      p.height_px = 360;
      p.tip_x_px = 320;
      p.tip_y_px = 100;
      p.strand_width_um = 400 - 10 * i;
      p.width_jitter_um = 2;
      p.seed = i + 1;
      const std::string video = "s" + std::to_string(i) + ".mp4";
      synthetic::RenderSequence(p, 40, 25.0, (dir_ / video).string(), "");
      yaml += "  - {step: " + std::to_string(i + 1) +
              ", temperature_c: " + std::to_string(220 - 10 * i) + ", video: " + video + "}\n";
    }
    const std::string path = (dir_ / "m.yaml").string();
    WriteFileAtomically(path, yaml);
    return path;
  }
  testutil::ScratchDir scratch_{"clogscope_manifest_run"};
  const fs::path dir_ = scratch_.path();
};

// The whole manifest from the library: the tables, the prediction from the steps held in memory,
// and the same prediction as `predict --diameters` of the diameters.csv just written.
TEST_F(ManifestRunTest, PredictsFromItsStepsAsFromTheWrittenTable) {
  ManifestRunOptions o;
  o.manifest = WriteManifest();
  o.out_dir = (dir_ / "out").string();
  o.full_pipeline = true;
  o.jobs = 1;
  const ManifestRunReport rep = RunManifest(o);
  ASSERT_EQ(rep.steps.size(), 2u);
  for (const auto& r : rep.steps) EXPECT_EQ(r.status, model::StepStatus::kOk) << r.detail;
  ASSERT_TRUE(rep.conversion.has_value());
  EXPECT_EQ(rep.conversion->scale_um_per_px, 3.0);
  ASSERT_TRUE(rep.prediction.has_value());
  for (const char* f : {"diameters.csv", "predict/predictions.csv", "summary.md", "summary.json"})
    EXPECT_TRUE(fs::exists(dir_ / "out" / f)) << f;

  const model::ExtruderParams params = model::LoadExtruderWithOverrides("direct-pla", {});
  const std::vector<model::StepInput> from_csv = model::ReadDiameterTable(
      (dir_ / "out" / "diameters.csv").string(), params.Get(model::Param::kReferenceTemperatureC));
  const model::PredictionRun expected = model::PredictSteps(params, from_csv);
  const auto& got = rep.prediction->prediction.steps;
  ASSERT_EQ(got.size(), expected.prediction.steps.size());
  for (size_t i = 0; i < got.size(); ++i) {
    const auto& e = expected.prediction.steps[i];
    EXPECT_EQ(got[i].step, e.step);
    EXPECT_EQ(got[i].temperature_c, e.temperature_c);
    EXPECT_EQ(got[i].diameter_um, e.diameter_um);  // exactly: the table's numbers
    EXPECT_EQ(got[i].f_bp_n, e.f_bp_n);
    EXPECT_EQ(got[i].relative_amplitude, e.relative_amplitude);
    // And the measurement itself, independently: 400 and 390 µm rendered, within 1 %.
    EXPECT_NEAR(got[i].diameter_um, 400 - 10.0 * i, 4.0);
  }
  EXPECT_EQ(rep.prediction->prediction.reference_load_n, expected.prediction.reference_load_n);
}

StepResult Step(int step, model::StepStatus status, double mean_um) {
  StepResult r;
  r.spec.step = step;
  r.spec.temperature_c = 200.004;
  r.status = status;
  r.has_um = status != model::StepStatus::kFailed;
  r.n_used = status == model::StepStatus::kFailed ? 0 : 10;
  r.mean_um = mean_um;
  return r;
}

TEST(PredictorSteps, TheTablesNumbersWithFailedStepsLeftOut) {
  const auto steps = PredictorSteps({Step(1, model::StepStatus::kOk, 390.12345),
                                     Step(2, model::StepStatus::kFailed, 0),
                                     Step(3, model::StepStatus::kTooFewFrames, 380.0006)});
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[0].step, 1);
  EXPECT_EQ(steps[0].diameter_m, 390.123 * 1e-6);  // 3 decimals in µm, as diameters.csv
  EXPECT_EQ(steps[0].temperature_c, 200.0);        // 2 decimals
  EXPECT_EQ(steps[1].step, 3);
  EXPECT_EQ(steps[1].diameter_m, 380.001 * 1e-6);
  EXPECT_FALSE(steps[1].filament_diameter_m.has_value());
}

TEST(PredictorSteps, AllFailedOrNoMicronsIsRefused) {
  EXPECT_THROW(PredictorSteps({Step(1, model::StepStatus::kFailed, 0)}), std::invalid_argument);
  StepResult px_only = Step(1, model::StepStatus::kOk, 0);
  px_only.has_um = false;
  EXPECT_THROW(PredictorSteps({px_only}), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::pipeline
