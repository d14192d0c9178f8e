#pragma once

// What `watch --mqtt` publishes, built without a broker: the topics under a prefix, the state as
// flat JSON and single values, and Home Assistant's MQTT discovery configs.

#include <optional>
#include <string>
#include <vector>

#include "watch/watch_report.h"
#include "watch/watch_state.h"

namespace clogscope::watch {

// The availability payloads (Home Assistant's defaults), and its discovery prefix by default.
inline constexpr char kMqttOnline[] = "online";
inline constexpr char kMqttOffline[] = "offline";
inline constexpr char kHaDiscoveryPrefix[] = "homeassistant";

struct MqttMessage {
  std::string topic;
  std::string payload;
  int qos = 1;
  bool retain = true;
};

// The topics of one watch under its prefix ("clogscope/printer1").
struct MqttTopics {
  explicit MqttTopics(const std::string& prefix);
  std::string prefix;
  std::string state;         // <prefix>/state: the state as JSON (MqttStateJson)
  std::string availability;  // <prefix>/availability: online / offline (the last will)
  std::string level;         // <prefix>/level: the level's name alone
  std::string diameter_mm;   // <prefix>/diameter_mm: the window's mean diameter alone, or "nan"
  std::string frame;         // <prefix>/frame: the latest frame with its overlay, JPEG bytes
  // The prefix as a Home Assistant node id and device id: every character outside
  // [A-Za-z0-9_-] becomes '_' ("clogscope/printer1" -> "clogscope_printer1").
  std::string node_id;
};

// The state as one flat JSON object, for templates (Home Assistant's value_template, Moonraker's
// state_response_template): level, previous_level, level_since_s, reason, time_s, source_up,
// clog (the level is clog), diameter_mm, diameter_ci95_mm, diameter_um, diameter_ci95_um,
// diameter_px, baseline_mm, drift_pct, drift_ci95_pct (the window's), recent_drift_pct,
// recent_drift_ci95_pct (the alert window's), valid_fraction, frame_rate_hz,
// back_pressure_ratio, vibration_increase_pct. A quantity not known (no diameter or scale yet, no
// clog index) is null.
std::string MqttStateJson(const WatchStatus& status, const std::optional<ClogIndex>& clog);

// The state's retained messages: <prefix>/state, <prefix>/level, <prefix>/diameter_mm.
std::vector<MqttMessage> MqttStateMessages(const MqttTopics& topics, const WatchStatus& status,
                                           const std::optional<ClogIndex>& clog);

// Home Assistant's discovery configs (retained, on
// <discovery_prefix>/<component>/<node_id>/<object_id>/config), each with the availability topic
// and one device: a binary sensor "Clog" (device_class problem, on at level clog), a sensor
// "Nozzle diameter" in mm (px without a scale) with the whole state as its attributes, a sensor
// "Level" (an enum of the levels), a sensor "Drift" in %, and a camera "Nozzle" showing
// <prefix>/frame.
std::vector<MqttMessage> HaDiscoveryMessages(const MqttTopics& topics,
                                             const std::string& discovery_prefix, bool has_scale);

}  // namespace clogscope::watch
