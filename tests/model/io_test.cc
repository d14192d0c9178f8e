#include "model/io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>

#include "common/atomic_file.h"
#include "tests/scratch_dir.h"

namespace clogscope::model {
namespace {

namespace fs = std::filesystem;

std::string Write(const std::string& name, const std::string& text) {
  static const testutil::ScratchDir dir("clogscope_model_io");
  const std::string path = (dir / name).string();
  WriteFileAtomically(path, text);
  return path;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// run's table marks a step that failed (no mean) by the word "failed": the reader skips it and
// keeps the others, a step with too few frames among them.
TEST(ModelIoTest, SkipsFailedStepsOfTheDiameterTable) {
  const auto steps = ReadDiameterTable(
      Write("failed.csv",
            "step,temperature_c,n,mean_um,status,detail\n1,220,50,400.0,ok,\n2,210,0,,failed,"
            "no valid frame\n3,200,40,390.1,too_few_frames,40 valid of 50 asked\n"),
      220);
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[0].step, 1);
  EXPECT_EQ(steps[1].step, 3);
  EXPECT_DOUBLE_EQ(steps[1].diameter_m, 390.1e-6);
}

TEST(ModelIoTest, ReadsTheDiameterTable) {
  const auto steps = ReadDiameterTable(
      Write("d.csv",
            "# from "
            "measure\nstep,temperature_c,n,mean_um,std_um\n1,220,50,400.0,2\n2,210,50,396.9,2\n"),
      220);
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[1].step, 2);
  EXPECT_DOUBLE_EQ(steps[1].diameter_m, 396.9e-6);
  EXPECT_EQ(steps[1].source_line, 4);
  // Without temperatures the reference temperature is used.
  const auto no_t = ReadDiameterTable(Write("d2.csv", "step,mean_um\n1,400\n"), 215);
  EXPECT_DOUBLE_EQ(no_t[0].temperature_c, 215);
}

TEST(ModelIoTest, BadTablesNameFileAndLine) {
  EXPECT_NE(ErrorOf([] {
              ReadDiameterTable(Write("a.csv", "step,temperature_c\n1,220\n"), 220);
            }).find("mean_um"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] {
              ReadDiameterTable(Write("b.csv", "step,mean_um\n1,400\n2,abc\n"), 220);
            }).find("b.csv:3"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] {
              ReadDiameterTable(Write("c.csv", "step,mean_um\n1,400\n1,390\n"), 220);
            }).find("twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] {
              ReadDiameterTable(Write("e.csv", "step,mean_um\n1,\n"), 220);
            }).find("mean_um is missing"),
            std::string::npos);
}

TEST(ModelIoTest, MeasurementsMatchByStepOrTemperature) {
  const auto steps = ReadDiameterTable(
      Write("d3.csv", "step,temperature_c,mean_um\n1,220,400\n2,210,396.9\n"), 220);
  const auto by_t =
      ReadMeasurements(Write("m1.csv", "temperature_c,amplitude_m_s2\n210,0.65\n"), steps);
  ASSERT_EQ(by_t.size(), 1u);
  EXPECT_EQ(by_t[0].step, 2);
  const auto by_step = ReadMeasurements(Write("m2.csv", "step,current_ma\n1,420\n"), steps);
  EXPECT_DOUBLE_EQ(*by_step[0].current_ma, 420);
  EXPECT_FALSE(by_step[0].amplitude_m_s2.has_value());
  EXPECT_NE(ErrorOf([&] {
              ReadMeasurements(Write("m3.csv", "temperature_c,amplitude_m_s2\n205,0.6\n"), steps);
            }).find("m3.csv:2"),
            std::string::npos);
}

TEST(ModelIoTest, YamlRoundTripAndErrorsWithLines) {
  ExtruderParams p = ExtruderParams::Preset("bowden-pla");
  p.Set(Param::kGainMS2PerN, 0.0123456789);
  p.load_model = LoadModel::kDifference;
  Provenance prov{"0.1.0", "2026-11-21T00:00:00Z", "clogscope predict …"};
  const std::string path = Write("p.yaml", ExtruderToYaml(p, prov));
  const ExtruderParams q = LoadExtruder(path);
  for (const auto& info : AllParams()) {
    EXPECT_EQ(p.Has(info.id), q.Has(info.id)) << info.name;
    if (p.Has(info.id)) {
      EXPECT_DOUBLE_EQ(p.Get(info.id), q.Get(info.id)) << info.name;
    }
  }
  EXPECT_EQ(q.load_model, LoadModel::kDifference);

  const std::string unknown =
      ErrorOf([] { LoadExtruder(Write("u.yaml", "preset: direct-pla\nflow_idx: 0.5\n")); });
  EXPECT_NE(unknown.find("u.yaml:2"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("flow_idx"), std::string::npos);
  const std::string type = ErrorOf([] { LoadExtruder(Write("t.yaml", "flow_index: fast\n")); });
  EXPECT_NE(type.find("t.yaml:1"), std::string::npos) << type;
  EXPECT_NE(
      ErrorOf([] { LoadExtruder(Write("l.yaml", "flow_index: [1, 2]\n")); }).find("single value"),
      std::string::npos);
  EXPECT_NE(ErrorOf([] { LoadExtruder("no-such-preset"); }).find("not a preset"),
            std::string::npos);
  // A file that names a preset starts from it.
  EXPECT_DOUBLE_EQ(LoadExtruder(Write("b.yaml", "preset: bowden-pla\nflow_index: 0.7\n"))
                       .Get(Param::kNaturalFrequencyHz),
                   16.5);
}

TEST(ModelIoTest, SetByNameChecksNamesAndNumbers) {
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  p.SetByName("gain", "0.01");
  EXPECT_DOUBLE_EQ(p.Get(Param::kGainMS2PerN), 0.01);
  EXPECT_THROW(p.SetByName("gian", "0.01"), std::invalid_argument);
  EXPECT_THROW(p.SetByName("flow_index", "0.6x"), std::invalid_argument);
  EXPECT_THROW(p.SetByName("load_model", "product"), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::model
