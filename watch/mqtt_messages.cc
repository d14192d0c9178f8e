#include "watch/mqtt_messages.h"

#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>

namespace clogscope::watch {
namespace {

using Json = nlohmann::ordered_json;  // keys in the order written: the state reads top-down

// Rounded, or null when not known (JSON has no NaN; Home Assistant's template renders null as
// "None", which it shows as unknown).
Json Value(bool known, double v, int digits) {
  return known && std::isfinite(v) ? Json(RoundDecimals(v, digits)) : Json();
}

std::string Dump(const Json& j) {
  // Text from outside (a reason quoting a decoder) may not be UTF-8: replaced, never a throw.
  return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

}  // namespace

MqttTopics::MqttTopics(const std::string& p)
    : prefix(p),
      state(p + "/state"),
      availability(p + "/availability"),
      level(p + "/level"),
      diameter_mm(p + "/diameter_mm"),
      frame(p + "/frame"),
      node_id(p) {
  for (char& c : node_id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
}

std::string MqttStateJson(const WatchStatus& s, const std::optional<ClogIndex>& clog) {
  const bool d = s.has_diameter, um = s.has_diameter && s.has_scale;
  const bool drift = s.baseline_ready && s.has_diameter;
  Json j;
  j["level"] = WatchLevelName(s.level);
  j["previous_level"] = WatchLevelName(s.previous_level);
  j["level_since_s"] = RoundDecimals(s.level_since_s, 3);
  j["reason"] = s.reason;
  j["time_s"] = RoundDecimals(s.time_s, 3);
  j["source_up"] = s.source_up;
  j["clog"] = s.level == WatchLevel::kClog;
  j["diameter_mm"] = Value(um, s.diameter_um * 1e-3, 6);
  j["diameter_ci95_mm"] = Value(um, s.diameter_ci95_um * 1e-3, 6);
  j["diameter_um"] = Value(um, s.diameter_um, 3);
  j["diameter_ci95_um"] = Value(um, s.diameter_ci95_um, 3);
  j["diameter_px"] = Value(d, s.diameter_px, 4);
  j["baseline_mm"] = Value(s.baseline_ready && s.has_scale, s.baseline_um * 1e-3, 6);
  j["drift_pct"] = Value(drift, s.drift_pct, 4);
  j["drift_ci95_pct"] = Value(drift, s.drift_ci95_pct, 4);
  j["recent_drift_pct"] = Value(s.has_recent, s.recent_drift_pct, 4);
  j["recent_drift_ci95_pct"] = Value(s.has_recent, s.recent_drift_ci95_pct, 4);
  j["valid_fraction"] = RoundDecimals(s.valid_fraction, 4);
  j["frame_rate_hz"] = RoundDecimals(s.frame_rate_hz, 3);
  j["back_pressure_ratio"] = Value(clog.has_value(), clog ? clog->back_pressure_ratio : 0, 5);
  j["vibration_increase_pct"] = Value(clog.has_value(), clog ? clog->vibration_increase_pct : 0, 4);
  return Dump(j);
}

std::vector<MqttMessage> MqttStateMessages(const MqttTopics& t, const WatchStatus& s,
                                           const std::optional<ClogIndex>& clog) {
  const Json diameter_mm = Value(s.has_diameter && s.has_scale, s.diameter_um * 1e-3, 6);
  // A retained message with an empty payload deletes the retained one: an unknown diameter is
  // "nan", which every float parser reads.
  return {{t.state, MqttStateJson(s, clog)},
          {t.level, WatchLevelName(s.level)},
          {t.diameter_mm, diameter_mm.is_null() ? "nan" : diameter_mm.dump()}};
}

std::vector<MqttMessage> HaDiscoveryMessages(const MqttTopics& t,
                                             const std::string& discovery_prefix, bool has_scale) {
  const Json device = {{"identifiers", Json::array({"clogscope_" + t.node_id})},
                       {"name", "ClogScope " + t.prefix},
                       {"manufacturer", "ClogScope"},
                       {"model", "clogscope watch"}};
  std::vector<MqttMessage> out;
  // One entity: its config with the keys every entity shares.
  const auto add = [&](const std::string& component, const std::string& object_id,
                       const std::string& name, Json config) {
    Json j;
    j["name"] = name;
    j["unique_id"] = t.node_id + "_" + object_id;
    j.update(config);
    j["availability_topic"] = t.availability;
    j["payload_available"] = kMqttOnline;
    j["payload_not_available"] = kMqttOffline;
    j["device"] = device;
    out.push_back(
        {discovery_prefix + "/" + component + "/" + t.node_id + "/" + object_id + "/config",
         Dump(j)});
  };
  add("binary_sensor", "clog", "Clog",
      {{"state_topic", t.state},
       {"value_template", "{{ 'ON' if value_json.level == 'clog' else 'OFF' }}"},
       {"payload_on", "ON"},
       {"payload_off", "OFF"},
       {"device_class", "problem"}});
  Json diameter = {{"state_topic", t.state}, {"json_attributes_topic", t.state}};
  if (has_scale) {
    diameter.update({{"value_template", "{{ value_json.diameter_mm }}"},
                     {"unit_of_measurement", "mm"},
                     {"device_class", "distance"},
                     {"suggested_display_precision", 4}});
  } else {  // no scale: pixels, which Home Assistant knows no device class for
    diameter.update({{"value_template", "{{ value_json.diameter_px }}"},
                     {"unit_of_measurement", "px"},
                     {"suggested_display_precision", 2}});
  }
  diameter["state_class"] = "measurement";
  add("sensor", "diameter", "Nozzle diameter", diameter);
  Json levels = Json::array();
  for (WatchLevel l : kWatchLevels) levels.push_back(WatchLevelName(l));
  add("sensor", "level", "Level",
      {{"state_topic", t.state},
       {"value_template", "{{ value_json.level }}"},
       {"device_class", "enum"},
       {"options", levels}});
  add("sensor", "drift", "Drift",
      {{"state_topic", t.state},
       {"value_template", "{{ value_json.drift_pct }}"},
       {"unit_of_measurement", "%"},
       {"state_class", "measurement"},
       {"suggested_display_precision", 2}});
  add("camera", "frame", "Nozzle", {{"topic", t.frame}});
  return out;
}

}  // namespace clogscope::watch
