#include "apps/watch_config.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>

#include "calib/calibration_file.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/path_check.h"
#include "common/yaml_fields.h"
#include "pipeline/band.h"
#include "vision/edges/polarity.h"
#include "vision/scene/frame_status.h"
#include "watch/pause_policy.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

// Reads typed values out of the file's nodes (YamlFields), and its paths relative to its folder;
// every refusal is "PATH:LINE: problem".
class Reader : public YamlFields {
 public:
  Reader(std::string path, fs::path base) : YamlFields(std::move(path)), base_(std::move(base)) {}

  const std::string& path() const { return source(); }
  // A path in the file: relative to the file's folder.
  std::string Path(const YAML::Node& n, const std::string& key) const {
    return ResolveFrom(base_.string(), Text(n, key));
  }
  // A source: a URL or device as written, a relative file or folder from the file's folder.
  std::string Source(const YAML::Node& n) const {
    const std::string s = Text(n, "source");
    return s.find("://") == std::string::npos ? Path(n, "source") : s;
  }

 private:
  fs::path base_;
};

using Setter =
    std::function<void(const Reader&, const YAML::Node&, const std::string&, WatchCommandOptions*)>;

// A number into a field of the options.
template <typename Field>
Setter Num(Field field) {
  return [field](const Reader& r, const YAML::Node& n, const std::string& key,
                 WatchCommandOptions* o) { field(o) = r.Number(n, key); };
}

// The per-camera keys (in `defaults` and in each camera) and what each sets.
const std::map<std::string, Setter>& CameraKeys() {
  using O = WatchCommandOptions;
  static const std::
      map<std::string, Setter>
          keys =
              {
                  // A camera's own scale or calibration replaces the other from defaults.
                  {"scale_um_per_px",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     o->measure.scale_um_per_px = r.Number(n, k);
                     o->measure.calibration.reset();
                   }},
                  {"calib",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     const std::string path = r.Path(n, k);
                     RequireInputPath("calib", path, PathExpect::kFile);
                     o->measure.calibration = calib::ReadCalibrationFile(path);
                     o->measure.scale_um_per_px.reset();
                   }},
                  {"roi", [](const Reader& r, const YAML::Node& n, const std::string& k,
                             O* o) { o->measure.strand.roi = pipeline::ParseRoi(r.Text(n, k)); }},
                  {"band_start_um",
                   Num([](O* o) -> std::optional<double>& { return o->measure.band.start_um; })},
                  {"band_height_um",
                   Num([](O* o) -> std::optional<double>& { return o->measure.band.height_um; })},
                  {"band_start_px",
                   Num([](O* o) -> std::optional<double>& { return o->measure.band.start_px; })},
                  {"band_height_px",
                   Num([](O* o) -> std::optional<double>& { return o->measure.band.height_px; })},
                  {"target",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     o->measure.strand.target = vision::ParseMeasureTarget(r.Text(n, k));
                   }},
                  {"polarity",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     o->measure.strand.polarity = vision::ParsePolarity(r.Text(n, k));
                   }},
                  {"realtime", [](const Reader& r, const YAML::Node& n, const std::string& k,
                                  O* o) { o->live.source_options.realtime = r.Flag(n, k); }},
                  {"open_timeout_s",
                   Num([](O* o) -> double& { return o->live.source_options.open_timeout_s; })},
                  {"read_timeout_s",
                   Num([](O* o) -> double& { return o->live.source_options.read_timeout_s; })},
                  {"window_s", Num([](O* o) -> double& { return o->live.watch.window_s; })},
                  {"alert_window_s",
                   Num([](O* o) -> double& { return o->live.watch.alert_window_s; })},
                  {"baseline_s", Num([](O* o) -> double& { return o->live.watch.baseline_s; })},
                  {"baseline_um",
                   Num([](O* o) -> std::optional<double>& { return o->live.watch.baseline_um; })},
                  {"warn_pct", Num([](O* o) -> double& { return o->live.watch.warn_drift_pct; })},
                  {"clog_pct", Num([](O* o) -> double& { return o->live.watch.clog_drift_pct; })},
                  {"hysteresis_pct",
                   Num([](O* o) -> double& { return o->live.watch.hysteresis_pct; })},
                  {"hold_s", Num([](O* o) -> double& { return o->live.watch.hold_s; })},
                  {"min_valid_fraction",
                   Num([](O* o) -> double& { return o->live.watch.min_valid_fraction; })},
                  {"report_s", Num([](O* o) -> double& { return o->live.report_every_s; })},
                  {"extruder",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     // A preset's name as written; a YAML file from the config's folder.
                     const std::string e = r.Text(n, k);
                     const std::string ext = fs::path(e).extension().string();
                     const bool file =
                         e.find('/') != std::string::npos || ext == ".yaml" || ext == ".yml";
                     o->extruder = file ? r.Path(n, k) : e;
                   }},
                  {"set", [](const Reader& r, const YAML::Node& n, const std::string& k,
                             O* o) { o->set = r.TextList(n, k); }},
                  {"temperature_c",
                   Num([](O* o) -> std::optional<double>& { return o->temperature_c; })},
                  {"log", [](const Reader& r, const YAML::Node& n, const std::string& k,
                             O* o) { o->log_path = r.Path(n, k); }},
                  {"on_alert", [](const Reader& r, const YAML::Node& n, const std::string& k,
                                  O* o) { o->on_alert = r.Text(n, k); }},
                  {"moonraker", [](const Reader& r, const YAML::Node& n, const std::string& k,
                                   O* o) { o->printer.moonraker_url = r.Text(n, k); }},
                  {"octoprint", [](const Reader& r, const YAML::Node& n, const std::string& k,
                                   O* o) { o->printer.octoprint_url = r.Text(n, k); }},
                  {"printer_api_key_file",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     o->printer.api_key_file = r.Path(n, k);
                   }},
                  {"pause_level",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     const std::string level = r.Text(n, k);
                     if (!watch::ParsePauseLevel(level, &o->printer.pause.pause_level))
                       r.Fail(n, fmt::format("pause_level '{}': warn or clog", level));
                   }},
                  {"pause_holdoff_s",
                   Num([](O* o) -> double& { return o->printer.pause.holdoff_s; })},
                  {"printer_poll_s",
                   Num([](O* o) -> double& { return o->printer.poll_interval_s; })},
                  {"webcam", [](const Reader& r, const YAML::Node& n, const std::string& k,
                                O* o) { o->printer.webcam = r.Text(n, k); }},
                  {"moonraker_notify_macro",
                   [](const Reader& r, const YAML::Node& n, const std::string& k, O* o) {
                     o->printer.notify_macro = r.Text(n, k);
                   }},
              };
  return keys;
}

// The keys of `map` into *o; a value the option's own parser refuses is told at its line.
void Apply(const Reader& r, const YAML::Node& map, WatchCommandOptions* o) {
  if (map["calib"] && map["scale_um_per_px"])
    r.Fail(map["scale_um_per_px"], "give either calib or scale_um_per_px, not both");
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    const auto it = CameraKeys().find(key);
    if (it == CameraKeys().end()) continue;  // name, source: the caller's
    try {
      it->second(r, kv.second, key, o);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      if (what.rfind(r.path() + ":", 0) == 0) throw;  // already told at its line
      r.Fail(kv.second, key + ": " + what);
    }
  }
}

const char kTopKeys[] = "http, http_token_file, mqtt, mqtt_credentials_file, defaults, cameras";

}  // namespace

bool IsPrinterName(const std::string& name) {
  return !name.empty() && name.size() <= 64 &&
         std::all_of(name.begin(), name.end(),
                     [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-'; });
}

bool WatchFarmOptions::Validate(std::string* why) const {
  std::set<std::string> names;
  const auto at = [&](const WatchCameraConfig& c) { return fmt::format("{}:{}", path, c.line); };
  if (cameras.empty()) {
    *why = path + ": no cameras (a list under 'cameras:')";
    return false;
  }
  for (const WatchCameraConfig& c : cameras) {
    if (!IsPrinterName(c.name)) {
      *why = fmt::format("{}: name '{}': 1 to 64 letters, digits, '_' or '-'", at(c), c.name);
      return false;
    }
    if (!names.insert(c.name).second) {
      *why = fmt::format("{}: the name '{}' is taken twice", at(c), c.name);
      return false;
    }
    if (c.options.live.source.empty() && c.options.printer.moonraker_url.empty()) {
      *why = fmt::format("{}: camera '{}' has no source (nor moonraker, whose webcam it would be)",
                         at(c), c.name);
      return false;
    }
  }
  if (!http_token_file.empty() && http.empty()) {
    *why = path + ": http_token_file goes with http";
    return false;
  }
  if (!(duration_s >= 0)) {
    *why = fmt::format("--duration-s {:g}: must not be negative", duration_s);
    return false;
  }
  return mqtt.Validate(why);
}

WatchFarmOptions LoadWatchConfig(const std::string& path) {
  RequireInputPath("--config", path, PathExpect::kFile);
  const std::string text = ReadFile(path);
  const YAML::Node root = LoadYamlText(text, path);
  if (!root.IsMap()) throw std::invalid_argument(path + ": expected a mapping (" + kTopKeys + ")");
  const Reader r(path, fs::path(path).parent_path());
  const std::set<std::string> top = {"http",     "http_token_file", "mqtt", "mqtt_credentials_file",
                                     "defaults", "cameras"};
  r.CheckKeys(
      root, [&](const std::string& k) { return top.count(k) > 0; }, "at the top",
      std::string("known: ") + kTopKeys + "; per-camera options go under defaults: or a camera");
  WatchFarmOptions farm;
  farm.path = path;
  if (root["http"]) farm.http = r.Text(root["http"], "http");
  if (root["http_token_file"])
    farm.http_token_file = r.Path(root["http_token_file"], "http_token_file");
  if (root["mqtt"]) farm.mqtt.url = r.Text(root["mqtt"], "mqtt");
  if (root["mqtt_credentials_file"])
    farm.mqtt.credentials_file = r.Path(root["mqtt_credentials_file"], "mqtt_credentials_file");
  const auto per_camera = [](const std::string& k) { return CameraKeys().count(k) > 0; };
  const std::string camera_hint = "per-camera keys are the command line's options without dashes";
  YAML::Node defaults = root["defaults"];
  if (defaults) {
    if (!defaults.IsMap()) r.Fail(defaults, "defaults: expected a mapping of per-camera options");
    r.CheckKeys(defaults, per_camera, "in defaults",
                camera_hint + "; name and source go in a camera");
  }
  const YAML::Node cameras = root["cameras"];
  if (!cameras) throw std::invalid_argument(path + ": no cameras (a list under 'cameras:')");
  if (!cameras.IsSequence() || cameras.size() == 0)
    r.Fail(cameras, "cameras: expected a list of cameras, each with a name and a source");
  std::map<std::string, int> lines;  // each name's first line
  // The defaults read once (their files opened once): each camera's keys then replace them.
  WatchCommandOptions base;
  if (defaults) Apply(r, defaults, &base);
  for (const YAML::Node& c : cameras) {
    if (!c.IsMap()) r.Fail(c, "a camera: expected a mapping (name:, source:, …)");
    r.CheckKeys(
        c, [&](const std::string& k) { return k == "name" || k == "source" || per_camera(k); },
        "in a camera", camera_hint);
    WatchCameraConfig camera;
    camera.line = c.Mark().line + 1;
    if (!c["name"]) r.Fail(c, "a camera without a name (the printer's label: [A-Za-z0-9_-]+)");
    camera.name = r.Text(c["name"], "name");
    if (!IsPrinterName(camera.name))
      r.Fail(c["name"], fmt::format("name '{}': 1 to 64 letters, digits, '_' or '-' (it labels "
                                    "the printer in paths, metrics and MQTT topics)",
                                    camera.name));
    if (const auto [it, fresh] = lines.emplace(camera.name, camera.line); !fresh)
      r.Fail(c["name"], fmt::format("the name '{}' is taken twice (also at line {})", camera.name,
                                    it->second));
    camera.options = base;
    Apply(r, c, &camera.options);
    if (c["source"]) camera.options.live.source = r.Source(c["source"]);
    if (camera.options.live.source.empty() && camera.options.printer.moonraker_url.empty())
      r.Fail(c, fmt::format("camera '{}' has no source (nor moonraker, whose webcam it would be)",
                            camera.name));
    farm.cameras.push_back(std::move(camera));
  }
  std::string why;
  if (!farm.Validate(&why)) throw std::invalid_argument(why);
  return farm;
}

}  // namespace clogscope::apps
