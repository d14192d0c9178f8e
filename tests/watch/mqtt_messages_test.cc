// What `watch --mqtt` publishes, without a broker: topics, the state's JSON and single values, Home
// Assistant's discovery configs, the URL and the credentials file.
#include "watch/mqtt_messages.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "tests/scratch_dir.h"
#include "watch/mqtt_publisher.h"

namespace clogscope::watch {
namespace {

using nlohmann::json;

// A watch at clog: 372.6 ± 0.8 µm against a 400 µm baseline, with a clog index.
WatchStatus ClogStatus() {
  WatchStatus s;
  s.time_s = 17.25;
  s.level = WatchLevel::kClog;
  s.previous_level = WatchLevel::kWarn;
  s.level_since_s = 16.5;
  s.reason = "drift -6.9 % (95 % CI ±0.4 %) past -5 %";
  s.source_up = true;
  s.valid_fraction = 0.98;
  s.frame_rate_hz = 25;
  s.has_diameter = s.has_scale = s.baseline_ready = s.has_recent = true;
  s.diameter_px = 124.2;
  s.diameter_um = 372.6;
  s.diameter_ci95_um = 0.8;
  s.baseline_um = 400;
  s.drift_pct = -6.85;
  s.drift_ci95_pct = 0.4;
  s.recent_drift_pct = -6.9;
  s.recent_drift_ci95_pct = 0.5;
  return s;
}

TEST(MqttMessagesTest, TopicsSitUnderThePrefixAndTheNodeIdIsItsSafeForm) {
  const MqttTopics t("farm/printer 1");
  EXPECT_EQ(t.state, "farm/printer 1/state");
  EXPECT_EQ(t.availability, "farm/printer 1/availability");
  EXPECT_EQ(t.level, "farm/printer 1/level");
  EXPECT_EQ(t.diameter_mm, "farm/printer 1/diameter_mm");
  EXPECT_EQ(t.frame, "farm/printer 1/frame");
  EXPECT_EQ(t.node_id, "farm_printer_1");
}

TEST(MqttMessagesTest, TheStateCarriesTheLevelAndTheDiameterInMillimetres) {
  ClogIndex clog;
  clog.back_pressure_ratio = 1.3312;
  clog.vibration_increase_pct = 12.5;
  const json j = json::parse(MqttStateJson(ClogStatus(), clog));
  EXPECT_EQ(j["level"], "clog");
  EXPECT_EQ(j["previous_level"], "warn");
  EXPECT_EQ(j["clog"], true);
  EXPECT_EQ(j["reason"], "drift -6.9 % (95 % CI ±0.4 %) past -5 %");
  EXPECT_DOUBLE_EQ(j["diameter_mm"].get<double>(), 0.3726);
  EXPECT_DOUBLE_EQ(j["diameter_ci95_mm"].get<double>(), 0.0008);
  EXPECT_DOUBLE_EQ(j["diameter_um"].get<double>(), 372.6);
  EXPECT_DOUBLE_EQ(j["diameter_px"].get<double>(), 124.2);
  EXPECT_DOUBLE_EQ(j["baseline_mm"].get<double>(), 0.4);
  EXPECT_DOUBLE_EQ(j["drift_pct"].get<double>(), -6.85);
  EXPECT_DOUBLE_EQ(j["recent_drift_pct"].get<double>(), -6.9);
  EXPECT_DOUBLE_EQ(j["valid_fraction"].get<double>(), 0.98);
  EXPECT_DOUBLE_EQ(j["back_pressure_ratio"].get<double>(), 1.3312);
  EXPECT_DOUBLE_EQ(j["vibration_increase_pct"].get<double>(), 12.5);
  // The order written: the level first, for a person reading mosquitto_sub.
  EXPECT_EQ(MqttStateJson(ClogStatus(), clog).rfind("{\"level\":\"clog\"", 0), 0u);
}

TEST(MqttMessagesTest, WhatIsNotKnownIsNullAndWithoutAScaleOnlyPixels) {
  WatchStatus s = ClogStatus();
  s.has_scale = false;
  s.diameter_um = s.diameter_ci95_um = s.baseline_um = NAN;
  json j = json::parse(MqttStateJson(s, std::nullopt));
  EXPECT_TRUE(j["diameter_mm"].is_null());
  EXPECT_TRUE(j["diameter_um"].is_null());
  EXPECT_TRUE(j["baseline_mm"].is_null());
  EXPECT_TRUE(j["back_pressure_ratio"].is_null());
  EXPECT_DOUBLE_EQ(j["diameter_px"].get<double>(), 124.2);
  EXPECT_DOUBLE_EQ(j["drift_pct"].get<double>(), -6.85);  // a ratio: no scale needed

  const WatchStatus starting;  // no frame yet
  j = json::parse(MqttStateJson(starting, std::nullopt));
  EXPECT_EQ(j["level"], "starting");
  EXPECT_EQ(j["clog"], false);
  EXPECT_EQ(j["source_up"], false);
  for (const char* key : {"diameter_mm", "diameter_px", "drift_pct", "recent_drift_pct"})
    EXPECT_TRUE(j[key].is_null()) << key;
}

TEST(MqttMessagesTest, TheStateMessagesAreRetainedAndAnUnknownDiameterIsNan) {
  const MqttTopics t("p");
  auto m = MqttStateMessages(t, ClogStatus(), std::nullopt);
  ASSERT_EQ(m.size(), 3u);
  for (const MqttMessage& x : m) EXPECT_TRUE(x.retain) << x.topic;
  EXPECT_EQ(m[0].topic, "p/state");
  EXPECT_EQ(m[1].topic, "p/level");
  EXPECT_EQ(m[1].payload, "clog");
  EXPECT_EQ(m[2].topic, "p/diameter_mm");
  EXPECT_DOUBLE_EQ(std::stod(m[2].payload), 0.3726);
  m = MqttStateMessages(t, WatchStatus(), std::nullopt);
  EXPECT_EQ(m[1].payload, "starting");
  EXPECT_EQ(m[2].payload, "nan");  // an empty retained payload would delete the topic
}

TEST(MqttMessagesTest, DiscoveryConfigsHaveWhatHomeAssistantRequires) {
  const MqttTopics t("farm/p1");
  const auto configs = HaDiscoveryMessages(t, "homeassistant", /*has_scale=*/true);
  const json state = json::parse(MqttStateJson(ClogStatus(), std::nullopt));
  std::map<std::string, json> by_topic;
  std::set<std::string> unique_ids;
  for (const MqttMessage& m : configs) {
    EXPECT_TRUE(m.retain) << m.topic;
    const json j = json::parse(m.payload);
    by_topic[m.topic] = j;
    // homeassistant/<component>/<node_id>/<object_id>/config
    EXPECT_TRUE(std::regex_match(
        m.topic, std::regex("homeassistant/(binary_sensor|sensor|camera)/farm_p1/[a-z_]+/config")))
        << m.topic;
    for (const char* key : {"name", "unique_id", "availability_topic", "payload_available",
                            "payload_not_available", "device"})
      EXPECT_TRUE(j.contains(key)) << m.topic << " lacks " << key;
    EXPECT_EQ(j["availability_topic"], "farm/p1/availability");
    EXPECT_EQ(j["payload_available"], "online");
    EXPECT_EQ(j["payload_not_available"], "offline");
    EXPECT_EQ(j["device"]["identifiers"], json::array({"clogscope_farm_p1"}));
    EXPECT_TRUE(unique_ids.insert(j["unique_id"].get<std::string>()).second) << j["unique_id"];
    // Every value the templates read is a key of the state.
    if (j.contains("value_template")) {
      const std::string tpl = j["value_template"];
      std::smatch key;
      ASSERT_TRUE(std::regex_search(tpl, key, std::regex("value_json\\.([a-z_0-9]+)"))) << tpl;
      EXPECT_TRUE(state.contains(key[1].str())) << tpl;
      EXPECT_EQ(j["state_topic"], "farm/p1/state");
    }
  }
  ASSERT_EQ(configs.size(), 5u);
  const json& clog = by_topic.at("homeassistant/binary_sensor/farm_p1/clog/config");
  EXPECT_EQ(clog["device_class"], "problem");
  EXPECT_EQ(clog["payload_on"], "ON");
  EXPECT_EQ(clog["payload_off"], "OFF");
  EXPECT_NE(clog["value_template"].get<std::string>().find("'clog'"), std::string::npos);
  const json& diameter = by_topic.at("homeassistant/sensor/farm_p1/diameter/config");
  EXPECT_EQ(diameter["unit_of_measurement"], "mm");
  EXPECT_EQ(diameter["device_class"], "distance");
  EXPECT_EQ(diameter["value_template"], "{{ value_json.diameter_mm }}");
  const json& level = by_topic.at("homeassistant/sensor/farm_p1/level/config");
  EXPECT_EQ(level["device_class"], "enum");
  EXPECT_EQ(level["options"].size(), std::size(kWatchLevels));
  const json& camera = by_topic.at("homeassistant/camera/farm_p1/frame/config");
  EXPECT_EQ(camera["topic"], "farm/p1/frame");
  EXPECT_TRUE(by_topic.count("homeassistant/sensor/farm_p1/drift/config"));

  // Without a scale the diameter is in px, with no device class (distance wants a length unit).
  for (const MqttMessage& m : HaDiscoveryMessages(t, "ha", /*has_scale=*/false)) {
    EXPECT_EQ(m.topic.rfind("ha/", 0), 0u) << m.topic;
    if (m.topic != "ha/sensor/farm_p1/diameter/config") continue;
    const json j = json::parse(m.payload);
    EXPECT_EQ(j["unit_of_measurement"], "px");
    EXPECT_FALSE(j.contains("device_class"));
    EXPECT_EQ(j["value_template"], "{{ value_json.diameter_px }}");
  }
}

TEST(MqttMessagesTest, TheUrlGivesHostPortAndPrefix) {
  MqttEndpoint e;
  std::string why;
  ASSERT_TRUE(ParseMqttUrl("mqtt://broker.lan", &e, &why)) << why;
  EXPECT_EQ(e.host, "broker.lan");
  EXPECT_EQ(e.port, kMqttDefaultPort);
  EXPECT_EQ(e.prefix, "clogscope");
  ASSERT_TRUE(ParseMqttUrl("mqtt://10.0.0.2:1884/farm/p1/", &e, &why)) << why;
  EXPECT_EQ(e.host, "10.0.0.2");
  EXPECT_EQ(e.port, 1884);
  EXPECT_EQ(e.prefix, "farm/p1");
  EXPECT_EQ(e.Shown(), "mqtt://10.0.0.2:1884/farm/p1");
  ASSERT_TRUE(ParseMqttUrl("mqtt://[::1]:1885/x", &e, &why)) << why;
  EXPECT_EQ(e.host, "::1");
  EXPECT_EQ(e.Shown(), "mqtt://[::1]:1885/x");
  for (const char* bad :
       {"http://h/x", "mqtts://h/x", "h:1883", "mqtt://", "mqtt://:1883/x", "mqtt://h:0/x",
        "mqtt://h:65536/x", "mqtt://h:12ab/x", "mqtt://h:/x", "mqtt://h/x/#", "mqtt://h/+/x",
        "mqtt://h//x", "mqtt://h/a//b", "mqtt://[::1/x", "mqtt://::1:1883/x"}) {
    EXPECT_FALSE(ParseMqttUrl(bad, &e, &why)) << bad;
    EXPECT_EQ(why.rfind("--mqtt '", 0), 0u) << why;
  }
  // Credentials in the URL are refused, and not repeated.
  EXPECT_FALSE(ParseMqttUrl("mqtt://farm:s3cret@h/x", &e, &why));
  EXPECT_NE(why.find("--mqtt-credentials-file"), std::string::npos) << why;
  EXPECT_EQ(why.find("s3cret"), std::string::npos) << why;
}

TEST(MqttMessagesTest, TheCredentialsFileIsOneUserPasswordLine) {
  const auto dir = testutil::FreshDir("clogscope_mqtt_credentials");
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return (dir / name).string();
  };
  MqttCredentials c;
  std::string why;
  ASSERT_TRUE(ReadMqttCredentials(write("good", "farm:pa:ss\n"), &c, &why)) << why;
  EXPECT_EQ(c.user, "farm");
  EXPECT_EQ(c.password, "pa:ss");
  ASSERT_TRUE(ReadMqttCredentials(write("crlf", "farm:s3cret\r\n"), &c, &why)) << why;
  EXPECT_EQ(c.password, "s3cret");
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"empty", ""},
           {"nocolon", "s3cret\n"},
           {"nouser", ":s3cret\n"},
           {"twolines", "farm:s3cret\nother:s3cret\n"}}) {
    EXPECT_FALSE(ReadMqttCredentials(write(name, text), &c, &why)) << name;
    EXPECT_EQ(why.rfind("--mqtt-credentials-file " + (dir / name).string(), 0), 0u) << why;
    EXPECT_EQ(why.find("s3cret"), std::string::npos) << why;
  }
  EXPECT_FALSE(ReadMqttCredentials((dir / "missing").string(), &c, &why));
  EXPECT_NE(why.find("cannot be read"), std::string::npos) << why;

  MqttOptions o;
  o.credentials_file = write("good2", "farm:x\n");
  EXPECT_FALSE(o.Validate(&why));
  EXPECT_EQ(why, "--mqtt-credentials-file goes with --mqtt");
  o.url = "mqtt://127.0.0.1/x";
  EXPECT_TRUE(o.Validate(&why)) << why;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace clogscope::watch
