#include "pipeline/step_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>

namespace clogscope::pipeline {
namespace {

using nlohmann::json;

ExperimentOptions Options() {
  ExperimentOptions o;
  o.samples = 3;
  o.out_dir = "/tmp/unused";
  o.conversion = PlainScale(3.0);
  return o;
}

StepSpec Spec() {
  StepSpec s;
  s.step = 2;
  s.temperature_c = 210;
  s.video = "/data/step2.mp4";
  return s;
}

// A finished step of the given frame widths (all valid, all used), summarised as the run does.
StepResult Step(const std::vector<double>& widths_px, const ExperimentOptions& o) {
  StepResult r;
  r.spec = Spec();
  double sum = 0;
  for (size_t i = 0; i < widths_px.size(); ++i) {
    vision::StrandMeasurement m;
    m.status = vision::FrameStatus::kValid;
    m.width_px = widths_px[i];
    m.width_sigma_px = 0.01;
    FrameRecord f;
    f.used = true;
    f.fields = FrameFields(r.spec.video, static_cast<int>(i), 0.5 * i, m, o.conversion);
    r.frames.push_back(f);
    sum += widths_px[i];
  }
  const int n = static_cast<int>(widths_px.size());
  r.n_examined = r.n_valid = r.n_used = n;
  r.status = n >= o.samples ? model::StepStatus::kOk : model::StepStatus::kTooFewFrames;
  r.mean_px = sum / n;
  r.std_px = 0.05;
  r.has_um = true;
  r.mean_um = 3 * r.mean_px;
  r.std_um = 0.15;
  r.sem_um = 0.15 / std::sqrt(n);
  r.ci95_um = n >= 2 ? 0.4 : NAN;
  return r;
}

TEST(StepFileTest, RoundTripsAFinishedStep) {
  const ExperimentOptions o = Options();
  const StepResult r = Step({130.1, 130.2, 130.3}, o);
  StepResult back;
  std::string why;
  ASSERT_TRUE(ReadStepFile(StepFileText(r, o), Spec(), o, &back, &why)) << why;
  EXPECT_TRUE(back.resumed);
  EXPECT_EQ(back.status, model::StepStatus::kOk);
  EXPECT_EQ(back.n_used, 3);
  EXPECT_DOUBLE_EQ(back.mean_px, r.mean_px);
  EXPECT_DOUBLE_EQ(back.mean_um, r.mean_um);
  ASSERT_EQ(back.frames.size(), 3u);
  EXPECT_EQ(back.frames[1].fields, r.frames[1].fields);
}

// One used frame has no confidence interval (NaN, written as null): it still resumes.
TEST(StepFileTest, OneFrameStepWithoutIntervalResumes) {
  const ExperimentOptions o = Options();
  StepResult back;
  std::string why;
  EXPECT_TRUE(ReadStepFile(StepFileText(Step({130.1}, o), o), Spec(), o, &back, &why)) << why;
  EXPECT_TRUE(std::isnan(back.ci95_um));
}

// A calibration, ROI, target or sample count changed since: the step is measured again, not
// reported in the old calibration's microns beside new ones.
TEST(StepFileTest, StepMeasuredAnotherWayIsNotResumed) {
  const ExperimentOptions o = Options();
  const std::string text = StepFileText(Step({130.1, 130.2, 130.3}, o), o);
  std::vector<ExperimentOptions> others(5, o);
  others[0].conversion = PlainScale(3.1);
  others[1].conversion.reset();
  others[2].strand.roi = cv::Rect(10, 10, 200, 200);
  others[3].strand.target = vision::MeasureTarget::kFilament;
  others[4].samples = 4;
  for (size_t i = 0; i < others.size(); ++i) {
    StepResult back;
    std::string why;
    EXPECT_FALSE(ReadStepFile(text, Spec(), others[i], &back, &why)) << i;
    EXPECT_NE(why.find("another way"), std::string::npos) << i << ": " << why;
  }
  StepSpec moved = Spec();
  moved.video = "/data/other.mp4";
  StepResult back;
  std::string why;
  EXPECT_FALSE(ReadStepFile(text, moved, o, &back, &why));
}

// Edited, truncated or corrupt files are refused with a reason, never thrown.
TEST(StepFileTest, FilesThatDoNotAddUpAreRefused) {
  const ExperimentOptions o = Options();
  const std::string text = StepFileText(Step({130.1, 130.2, 130.3}, o), o);
  const json good = json::parse(text);
  auto edited = [&](const std::function<void(json&)>& edit) {
    json j = good;
    edit(j);
    return j.dump();
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"not json", "step file"},
      {text.substr(0, text.size() / 2), "truncated"},
      {"[]", "an array"},
      {edited([](json& j) { j["mean_px"] = 140.0; }), "mean edited"},
      {edited([](json& j) { j["mean_px"] = nullptr; }), "mean null"},
      {edited([](json& j) { j["mean_um"] = std::nan(""); }), "mean_um NaN"},
      {edited([](json& j) { j["n_used"] = 2; }), "count edited"},
      {edited([](json& j) { j["n_examined"] = -1; }), "negative count"},
      {edited([](json& j) { j["n_valid"] = "3"; }), "count as text"},
      {edited([](json& j) { j["status"] = "failed"; }), "failed step"},
      {edited([](json& j) { j["status"] = "great"; }), "unknown status"},
      {edited([](json& j) { j["status"] = "too_few_frames"; }), "status contradicts counts"},
      {edited([](json& j) { j["std_um"] = -1; }), "negative spread"},
      {edited([](json& j) { j["frames"][0]["fields"].erase(0); }), "missing column"},
      {edited([](json& j) { j["frames"][0]["fields"][4] = "wide"; }), "width not a number"},
      {edited([](json& j) { j["frames"] = json::array(); }), "no frames"},
      {edited([](json& j) { j.erase("frames"); }), "frames key missing"},
  };
  for (const auto& [bad, what] : cases) {
    StepResult back;
    std::string why;
    EXPECT_FALSE(ReadStepFile(bad, Spec(), o, &back, &why)) << what;
    EXPECT_FALSE(why.empty()) << what;
    EXPECT_FALSE(back.resumed) << what;
  }
}

// The statuses go into the step file (and the tables) by their words, and come back from them.
TEST(StepFileTest, StatusesAreWrittenAndReadByTheirWords) {
  const ExperimentOptions o = Options();
  StepResult r = Step({130.1, 130.2}, o);  // 2 of 3 samples
  r.feedstock = FeedstockResult{};
  r.feedstock->status = FeedstockStatus::kTooFewPairs;
  r.feedstock->n_pairs = 5;
  r.feedstock->n_diameter = 4;
  r.feedstock->diameter_px = 580;
  const std::string text = StepFileText(r, o);
  const json j = json::parse(text);
  EXPECT_EQ(j["status"], "too_few_frames");
  EXPECT_EQ(j["feedstock"]["status"], "too_few_pairs");
  StepResult back;
  std::string why;
  ASSERT_TRUE(ReadStepFile(text, Spec(), o, &back, &why)) << why;
  EXPECT_EQ(back.status, model::StepStatus::kTooFewFrames);
  ASSERT_TRUE(back.feedstock.has_value());
  EXPECT_EQ(back.feedstock->status, FeedstockStatus::kTooFewPairs);
  // A feedstock that failed last time is measured again; a word that is no status is refused.
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"failed", "failed last time"}, {"great", "unknown feedstock status 'great'"}};
  for (const auto& [word, reason] : refused) {
    json edited = j;
    edited["feedstock"]["status"] = word;
    EXPECT_FALSE(ReadStepFile(edited.dump(), Spec(), o, &back, &why)) << word;
    EXPECT_NE(why.find(reason), std::string::npos) << word << ": " << why;
  }
  json unknown = j;
  unknown["status"] = "OK";
  EXPECT_FALSE(ReadStepFile(unknown.dump(), Spec(), o, &back, &why));
  EXPECT_EQ(why, "unknown status 'OK'");
}

TEST(StatusNamesTest, EachStatusHasItsWordAndParsesBack) {
  const std::vector<std::pair<model::StepStatus, std::string>> steps = {
      {model::StepStatus::kOk, "ok"},
      {model::StepStatus::kTooFewFrames, "too_few_frames"},
      {model::StepStatus::kFailed, "failed"}};
  for (const auto& [status, word] : steps) {
    EXPECT_EQ(model::StepStatusName(status), word);
    EXPECT_EQ(model::ParseStepStatus(word), status) << word;
  }
  const std::vector<std::pair<FeedstockStatus, std::string>> feedstock = {
      {FeedstockStatus::kOk, "ok"},
      {FeedstockStatus::kTooFewPairs, "too_few_pairs"},
      {FeedstockStatus::kFailed, "failed"}};
  for (const auto& [status, word] : feedstock) {
    EXPECT_EQ(FeedstockStatusName(status), word);
    EXPECT_EQ(ParseFeedstockStatus(word), status) << word;
  }
  EXPECT_THROW(model::ParseStepStatus("too_few_pairs"), std::invalid_argument);
  EXPECT_THROW(model::ParseStepStatus(""), std::invalid_argument);
  EXPECT_THROW(ParseFeedstockStatus("too_few_frames"), std::invalid_argument);
}

// A file name that is not UTF-8 does not stop the step file from being written.
TEST(StepFileTest, NonUtf8NamesAreWritten) {
  const ExperimentOptions o = Options();
  StepResult r = Step({130.1, 130.2, 130.3}, o);
  r.detail = "bad \xff\xfe name";
  std::string text;
  ASSERT_NO_THROW(text = StepFileText(r, o));
  StepResult back;
  std::string why;
  EXPECT_TRUE(ReadStepFile(text, Spec(), o, &back, &why)) << why;
}

}  // namespace
}  // namespace clogscope::pipeline
