#include "pipeline/manifest.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/path_check.h"
#include "common/yaml_fields.h"
#include "pipeline/statistics.h"
#include "vision/io/video_io.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

// Steps from one long video and the printer's temperature log.
std::vector<StepSpec> StepsFromLog(const Manifest& m) {
  const CsvTable t = ParseCsv(ReadFile(m.temperature_log), m.temperature_log);
  const int ct = t.Column("time_s"), cc = t.Column("temperature_c");
  if (ct < 0 || cc < 0)
    throw std::invalid_argument(m.temperature_log + ": needs columns time_s,temperature_c");
  std::vector<TemperatureSample> log;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const std::string where = fmt::format("{}:{}", m.temperature_log, t.row_line_numbers[i]);
    log.push_back({ParseNumberField(t.rows[i][ct], where, "time_s"),
                   ParseNumberField(t.rows[i][cc], where, "temperature_c")});
    if (i > 0 && log[i].time_s < log[i - 1].time_s) {
      throw std::invalid_argument(
          fmt::format("{}:{}: time goes backwards", m.temperature_log, t.row_line_numbers[i]));
    }
  }
  const auto holds = FindHolds(log, m.hold_tolerance_c, m.settle_s, m.min_step_s);
  if (holds.empty()) {
    throw std::invalid_argument(fmt::format(
        "{}: the temperature never holds within ±{} °C for {} s after a {} s settle: no steps",
        m.temperature_log, m.hold_tolerance_c, m.min_step_s, m.settle_s));
  }
  std::vector<StepSpec> steps;
  for (const auto& h : holds) {
    StepSpec s;
    s.step = static_cast<int>(steps.size()) + 1;
    s.temperature_c = std::round(h.temperature_c * 100) / 100;
    s.video = m.video;
    s.start_s = std::max(0.0, h.start_s - m.video_start_s);
    s.end_s = h.end_s - m.video_start_s;
    if (s.end_s <= s.start_s) continue;  // hold entirely before the video starts
    steps.push_back(s);
  }
  if (steps.empty())
    throw std::invalid_argument(m.temperature_log + ": no hold falls inside the video");
  return steps;
}

Manifest LoadCsvManifest(const std::string& path) {
  Manifest m;
  m.path = path;
  m.name = fs::path(path).stem().string();
  const std::string base = fs::path(path).parent_path().string();
  const CsvTable t = ParseCsv(ReadFile(path), path);
  const int c_step = t.Column("step"), c_t = t.Column("temperature_c"), c_src = t.Column("source");
  const int c_a = t.Column("start_s"), c_b = t.Column("end_s");
  if (c_step < 0 || c_t < 0 || c_src < 0) {
    throw std::invalid_argument(path + ": needs columns step,temperature_c,source[,start_s,end_s]");
  }
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const std::string where = fmt::format("{}:{}", path, t.row_line_numbers[i]);
    StepSpec s;
    s.line = t.row_line_numbers[i];
    const double step = ParseNumberField(r[c_step], where, "step");
    if (step != std::floor(step) || std::abs(step) > 1e9) {
      throw std::invalid_argument(where + ": step '" + r[c_step] + "' is not a whole number");
    }
    s.step = static_cast<int>(step);
    s.temperature_c = ParseNumberField(r[c_t], where, "temperature_c");
    if (c_a >= 0 && !r[c_a].empty()) s.start_s = ParseNumberField(r[c_a], where, "start_s");
    if (c_b >= 0 && !r[c_b].empty()) s.end_s = ParseNumberField(r[c_b], where, "end_s");
    if (r[c_src].empty()) throw std::invalid_argument(where + ": source is empty");
    const std::string src = ResolveFrom(base, r[c_src]);
    (InspectPath(src) == PathKind::kDirectory ? s.images : s.video) = src;
    m.steps.push_back(s);
  }
  return m;
}

}  // namespace

Manifest LoadManifest(const std::string& path) {
  const std::string ext = vision::LowerExtension(path);
  Manifest m;
  if (ext == ".csv") {
    m = LoadCsvManifest(path);
  } else {
    const std::string text = ReadFile(path);
    const YAML::Node root = LoadYamlText(text, path);
    const YamlFields y(path);
    if (!root.IsMap())
      throw std::invalid_argument(path + ": expected a mapping (name:, steps:, …)");
    y.CheckKeys(root, {"name",
                       "samples",
                       "settle_s",
                       "scale_um_per_px",
                       "calibration",
                       "calibrate",
                       "extruder",
                       "extruder_set",
                       "roi",
                       "polarity",
                       "target",
                       "band_start_um",
                       "band_height_um",
                       "steps",
                       "video",
                       "temperature_log",
                       "video_start_s",
                       "hold_tolerance_c",
                       "min_step_s",
                       "feedstock"});
    m.path = path;
    const std::string base = fs::path(path).parent_path().string();
    m.name = root["name"] ? y.Text(root["name"], "name") : fs::path(path).stem().string();
    if (root["samples"]) {
      m.samples = y.Whole(root["samples"], "samples");
      if (m.samples < 2) y.Fail(root["samples"], "samples: need at least 2");
    }
    if (root["settle_s"]) m.settle_s = y.Number(root["settle_s"], "settle_s");
    if (root["scale_um_per_px"])
      m.scale_um_per_px = y.Number(root["scale_um_per_px"], "scale_um_per_px");
    if (root["calibration"])
      m.calibration_file = ResolveFrom(base, y.Text(root["calibration"], "calibration"));
    if (const auto c = root["calibrate"]) {
      if (!c.IsMap())
        y.Fail(c, "calibrate: expected pins: CSV or micrometer: IMAGE(S) with pitch_um:");
      y.CheckKeys(c, {"pins", "micrometer", "pitch_um"});
      if (c["pins"]) m.calibrate_pins_csv = ResolveFrom(base, y.Text(c["pins"], "pins"));
      if (c["micrometer"]) {
        for (const auto& p : y.TextList(c["micrometer"], "micrometer"))
          m.calibrate_micrometer.push_back(ResolveFrom(base, p));
      }
      if (c["pitch_um"]) m.calibrate_pitch_um = y.Number(c["pitch_um"], "pitch_um");
    }
    if (root["extruder"]) {
      m.extruder = y.Text(root["extruder"], "extruder");
      if (InspectPath(ResolveFrom(base, m.extruder)) != PathKind::kMissing)
        m.extruder = ResolveFrom(base, m.extruder);
    }
    if (root["extruder_set"]) m.extruder_set = y.TextList(root["extruder_set"], "extruder_set");
    if (root["roi"]) m.roi = y.Text(root["roi"], "roi");
    if (root["polarity"]) m.polarity = y.Text(root["polarity"], "polarity");
    if (root["target"]) {
      m.target = y.Text(root["target"], "target");
      if (m.target != "strand" && m.target != "filament")
        y.Fail(root["target"], "target: expected strand or filament, not '" + m.target + "'");
    }
    if (root["band_start_um"]) m.band_start_um = y.Number(root["band_start_um"], "band_start_um");
    if (root["band_height_um"])
      m.band_height_um = y.Number(root["band_height_um"], "band_height_um");
    if (root["video_start_s"]) m.video_start_s = y.Number(root["video_start_s"], "video_start_s");
    if (root["hold_tolerance_c"])
      m.hold_tolerance_c = y.Number(root["hold_tolerance_c"], "hold_tolerance_c");
    if (root["min_step_s"]) m.min_step_s = y.Number(root["min_step_s"], "min_step_s");
    if (root["video"]) m.video = ResolveFrom(base, y.Text(root["video"], "video"));
    if (root["temperature_log"])
      m.temperature_log = ResolveFrom(base, y.Text(root["temperature_log"], "temperature_log"));
    if (const auto f = root["feedstock"]) {
      if (!f.IsMap())
        y.Fail(f, "feedstock: expected roi:, gear_roi:, gear_radius_mm:, scale_um_per_px:, …");
      y.CheckKeys(f, {"roi", "gear_roi", "gear_centre", "gear_radius_mm", "polarity",
                      "scale_um_per_px", "calibration"});
      FeedstockSpec& fs = m.feedstock;
      fs.enabled = true;
      if (f["roi"]) fs.roi = y.Text(f["roi"], "roi");
      if (f["gear_roi"]) fs.gear_roi = y.Text(f["gear_roi"], "gear_roi");
      if (f["gear_centre"]) fs.gear_centre = y.Text(f["gear_centre"], "gear_centre");
      if (f["gear_radius_mm"]) fs.gear_radius_mm = y.Number(f["gear_radius_mm"], "gear_radius_mm");
      if (f["polarity"]) fs.polarity = y.Text(f["polarity"], "polarity");
      if (f["scale_um_per_px"]) {
        fs.scale_um_per_px = y.Number(f["scale_um_per_px"], "scale_um_per_px");
        if (!(*fs.scale_um_per_px > 0))
          y.Fail(f["scale_um_per_px"], "scale_um_per_px: must be positive");
      }
      if (f["calibration"])
        fs.calibration_file = ResolveFrom(base, y.Text(f["calibration"], "calibration"));
      if (fs.scale_um_per_px && !fs.calibration_file.empty())
        y.Fail(f, "feedstock: give scale_um_per_px: or calibration:, not both");
      if (!fs.gear_roi.empty() && !(fs.gear_radius_mm > 0))
        y.Fail(f, "feedstock: gear_roi: needs gear_radius_mm: (the gear's radius where it grips)");
    }
    if (root["steps"] && (root["video"] || root["temperature_log"])) {
      y.Fail(root["steps"], "give either steps: or video: with temperature_log:, not both");
    }
    if (const auto steps = root["steps"]) {
      if (!steps.IsSequence()) y.Fail(steps, "steps: expected a list");
      for (const auto& n : steps) {
        if (!n.IsMap()) y.Fail(n, "a step: expected step:, temperature_c: and video: or images:");
        y.CheckKeys(n, {"step", "temperature_c", "video", "images", "start_s", "end_s", "settle_s",
                        "feedstock_video"});
        StepSpec s;
        s.line = n.Mark().line + 1;
        if (!n["step"]) y.Fail(n, "a step needs step:");
        if (!n["temperature_c"]) y.Fail(n, "a step needs temperature_c:");
        s.step = y.Whole(n["step"], "step");
        s.temperature_c = y.Number(n["temperature_c"], "temperature_c");
        if (n["video"]) s.video = ResolveFrom(base, y.Text(n["video"], "video"));
        if (n["images"]) s.images = ResolveFrom(base, y.Text(n["images"], "images"));
        if (s.video.empty() == s.images.empty())
          y.Fail(n, fmt::format("step {}: give one of video: or images:", s.step));
        if (n["start_s"]) s.start_s = y.Number(n["start_s"], "start_s");
        if (n["end_s"]) s.end_s = y.Number(n["end_s"], "end_s");
        s.settle_s = n["settle_s"] ? y.Number(n["settle_s"], "settle_s") : m.settle_s;
        if (n["feedstock_video"]) {
          s.feedstock_video = ResolveFrom(base, y.Text(n["feedstock_video"], "feedstock_video"));
          m.feedstock.enabled = true;
        }
        m.steps.push_back(s);
      }
    } else if (!m.video.empty() || !m.temperature_log.empty()) {
      if (m.video.empty() || m.temperature_log.empty()) {
        throw std::invalid_argument(path + ": video: and temperature_log: go together");
      }
      m.steps = StepsFromLog(m);
    }
  }
  if (m.steps.empty()) throw std::invalid_argument(m.path + ": no steps");
  // With a feedstock ROI, a step without its own feedstock video films the feedstock in its own
  // video (the ROI tells the filament from the strand). Other steps have no feedstock.
  if (!m.feedstock.roi.empty()) {
    for (auto& s : m.steps) {
      if (s.feedstock_video.empty()) s.feedstock_video = s.video;
    }
  }
  std::map<int, int> seen;  // step -> line
  for (const auto& s : m.steps) {
    const auto [it, fresh] = seen.insert({s.step, s.line});
    if (!fresh) {
      throw std::invalid_argument(fmt::format("{}:{}: step {} appears twice (also at line {})",
                                              m.path, s.line, s.step, it->second));
    }
    if (s.temperature_c <= -273.15) {
      throw std::invalid_argument(fmt::format("{}:{}: temperature {} °C is below absolute zero",
                                              m.path, s.line, s.temperature_c));
    }
    if (s.end_s >= 0 && s.end_s <= s.start_s) {
      throw std::invalid_argument(
          fmt::format("{}:{}: end_s must be after start_s", m.path, s.line));
    }
    if (!s.images.empty() && (s.start_s != 0 || s.end_s >= 0 || s.settle_s != 0)) {
      throw std::invalid_argument(fmt::format(
          "{}:{}: step {}: start_s, end_s and settle_s need a video: a folder of images has no "
          "frame times (a settle_s at the top reaches every step: give this one settle_s: 0)",
          m.path, s.line, s.step));
    }
  }
  return m;
}

}  // namespace clogscope::pipeline
