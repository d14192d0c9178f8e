// `watch --config FILE`: the farm's YAML read into options; every refusal names the file and the
// line of the problem.
#include "apps/watch_config.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "calib/calibration_file.h"
#include "common/provenance.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

class WatchConfigTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::FreshDir("clogscope_watch_config"); }
  void TearDown() override { fs::remove_all(dir_); }
  // The text written to DIR/cameras.yaml; its path.
  std::string Write(const std::string& text, const std::string& name = "cameras.yaml") {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  fs::path dir_;
};

TEST_F(WatchConfigTest, AGoodFileGivesEachCameraTheDefaultsAndItsOwnOptions) {
  calib::ScaleCalibration cal;
  cal.usable = true;
  cal.method = "pins";
  cal.scale_um_per_px = 3.1;
  calib::WriteCalibrationFile((dir_ / "calib.yaml").string(), cal, CurrentProvenance(), {});
  const std::string path = Write(R"(# two printers
http: 127.0.0.1:8090
mqtt: mqtt://broker.local/farm
defaults:
  scale_um_per_px: 3
  window_s: 5
  clog_pct: -4
cameras:
  - name: mk4-left
    source: http://mk4-left.local/webcam/?action=stream
    moonraker: http://mk4-left.local
    log: logs/mk4-left.jsonl
  - name: voron_2
    source: voron.mp4
    window_s: 8
    target: filament
    on_alert: echo "$CLOGSCOPE_PRINTER"
    set: [nozzle_diameter_mm=0.6]
    extruder: direct-pla
)");
  const WatchFarmOptions f = LoadWatchConfig(path);
  EXPECT_EQ(f.path, path);
  EXPECT_EQ(f.http, "127.0.0.1:8090");
  EXPECT_EQ(f.mqtt.url, "mqtt://broker.local/farm");
  ASSERT_EQ(f.cameras.size(), 2u);
  const WatchCameraConfig &a = f.cameras[0], &b = f.cameras[1];
  EXPECT_EQ(a.name, "mk4-left");
  EXPECT_EQ(a.line, 9);
  EXPECT_EQ(a.options.live.source, "http://mk4-left.local/webcam/?action=stream");  // a URL as is
  EXPECT_EQ(a.options.printer.moonraker_url, "http://mk4-left.local");
  EXPECT_EQ(a.options.log_path, (dir_ / "logs/mk4-left.jsonl").string());  // from the file's folder
  EXPECT_EQ(a.options.measure.scale_um_per_px, 3.0);
  EXPECT_EQ(a.options.live.watch.window_s, 5.0);
  EXPECT_EQ(a.options.live.watch.clog_drift_pct, -4.0);
  EXPECT_TRUE(a.options.http.empty() && a.options.mqtt.url.empty());  // per process, not camera
  EXPECT_EQ(b.name, "voron_2");
  EXPECT_EQ(b.line, 13);
  EXPECT_EQ(b.options.live.source, (dir_ / "voron.mp4").string());
  EXPECT_EQ(b.options.live.watch.window_s, 8.0);  // its own over the default
  EXPECT_EQ(b.options.live.watch.clog_drift_pct, -4.0);
  EXPECT_EQ(b.options.measure.strand.target, vision::MeasureTarget::kFilament);
  EXPECT_EQ(b.options.on_alert, "echo \"$CLOGSCOPE_PRINTER\"");
  EXPECT_EQ(b.options.extruder, "direct-pla");
  EXPECT_EQ(b.options.set, std::vector<std::string>{"nozzle_diameter_mm=0.6"});
  std::string why;
  EXPECT_TRUE(f.Validate(&why)) << why;

  // A calibration file from the file's folder, read as --calib reads it.
  const WatchFarmOptions c = LoadWatchConfig(
      Write("cameras:\n  - {name: a, source: a.mp4, calib: calib.yaml}\n", "c.yaml"));
  ASSERT_TRUE(c.cameras[0].options.measure.calibration.has_value());
  EXPECT_DOUBLE_EQ(c.cameras[0].options.measure.calibration->scale_um_per_px, 3.1);

  // A camera's own scale replaces the calibration of the defaults, and the other way round.
  const WatchFarmOptions d = LoadWatchConfig(
      Write("defaults:\n  calib: calib.yaml\ncameras:\n  - {name: a, source: a.mp4, "
            "scale_um_per_px: 2.5}\n  - {name: b, source: b.mp4}\n",
            "d.yaml"));
  EXPECT_FALSE(d.cameras[0].options.measure.calibration.has_value());
  EXPECT_EQ(d.cameras[0].options.measure.scale_um_per_px, 2.5);
  ASSERT_TRUE(d.cameras[1].options.measure.calibration.has_value());
  EXPECT_FALSE(d.cameras[1].options.measure.scale_um_per_px.has_value());
  EXPECT_TRUE(d.Validate(&why)) << why;
}

TEST_F(WatchConfigTest, TheExampleInTheDocsIsAGoodFile) {
  const std::string path = std::string(CLOGSCOPE_TESTDATA_DIR) + "/../examples/cameras.yaml";
  const WatchFarmOptions f = LoadWatchConfig(path);
  EXPECT_EQ(f.http, "127.0.0.1:8090");
  ASSERT_EQ(f.cameras.size(), 3u);
  EXPECT_EQ(f.cameras[1].name, "mk3-right");
  EXPECT_EQ(f.cameras[1].options.measure.scale_um_per_px, 3.1);
  EXPECT_EQ(f.cameras[0].options.measure.scale_um_per_px, 3.0);
  EXPECT_TRUE(f.cameras[2].options.live.source.empty());  // Moonraker's webcam
  EXPECT_EQ(f.cameras[2].options.printer.pause.pause_level, watch::WatchLevel::kWarn);
  EXPECT_EQ(f.cameras[2].options.temperature_c, 240.0);
}

struct BadCase {
  const char* what;
  const char* yaml;
  int line;             // where the message must point
  const char* message;  // a part of it
};

TEST_F(WatchConfigTest, EachBadInputIsRefusedNamingTheFileAndTheLine) {
  const BadCase cases[] = {
      {"unknown top key", "http: 8090\nport: 9\ncameras:\n  - {name: a, source: a.mp4}\n", 2,
       "unknown key 'port' at the top"},
      {"per-camera key at the top", "window_s: 3\ncameras:\n  - {name: a, source: a.mp4}\n", 1,
       "per-camera options go under defaults"},
      {"unknown camera key", "cameras:\n  - name: a\n    source: a.mp4\n    colour: red\n", 4,
       "unknown key 'colour' in a camera"},
      {"name in defaults", "defaults:\n  name: a\ncameras:\n  - {name: a, source: a.mp4}\n", 2,
       "unknown key 'name' in defaults"},
      {"duplicate name",
       "cameras:\n  - name: a\n    source: a.mp4\n  - name: b\n    source: b.mp4\n"
       "  - name: a\n    source: c.mp4\n",
       6, "the name 'a' is taken twice (also at line 2)"},
      {"bad name", "cameras:\n  - name: my printer\n    source: a.mp4\n", 2,
       "name 'my printer': 1 to 64 letters, digits, '_' or '-'"},
      {"no name", "cameras:\n  - source: a.mp4\n", 2, "a camera without a name"},
      {"no source", "cameras:\n  - name: a\n    window_s: 3\n", 2, "camera 'a' has no source"},
      {"not a number", "cameras:\n  - name: a\n    source: a.mp4\n    window_s: ten\n", 4,
       "window_s: 'ten' is not a number"},
      {"not a flag", "cameras:\n  - name: a\n    source: a.mp4\n    realtime: sometimes\n", 4,
       "realtime: 'sometimes': expected true or false"},
      {"a list for a value", "cameras:\n  - name: a\n    source: [a.mp4, b.mp4]\n", 3,
       "source: expected a single value"},
      {"bad pause level", "cameras:\n  - name: a\n    source: a.mp4\n    pause_level: ok\n", 4,
       "pause_level 'ok': warn or clog"},
      {"bad target", "cameras:\n  - name: a\n    source: a.mp4\n    target: nozzle\n", 4,
       "target: "},
      {"missing calibration file", "cameras:\n  - name: a\n    source: a.mp4\n    calib: no.yaml\n",
       4, "calib: "},
      {"cameras not a list", "cameras:\n  name: a\n", 2, "cameras: expected a list of cameras"},
      {"empty list", "cameras: []\n", 1, "cameras: expected a list of cameras"},
      {"YAML syntax", "cameras:\n  - name: a\n    source: [a.mp4\n", 4, ""},
      {"scale and calibration",
       "cameras:\n  - name: a\n    source: a.mp4\n    calib: c.yaml\n    scale_um_per_px: 3\n", 5,
       "give either calib or scale_um_per_px, not both"},
      {"a key twice", "cameras:\n  - name: a\n    source: a.mp4\n    source: b.mp4\n", 4,
       "'source' given twice (also at line 3)"},
      {"a top key twice", "http: 8090\nhttp: 8091\ncameras:\n  - {name: a, source: a.mp4}\n", 2,
       "'http' given twice (also at line 1)"},
  };
  for (const BadCase& c : cases) {
    const std::string path = Write(c.yaml);
    try {
      LoadWatchConfig(path);
      ADD_FAILURE() << c.what << ": accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(path + ":" + std::to_string(c.line) + ": ", 0), 0u) << c.what << ": " << m;
      EXPECT_NE(m.find(c.message), std::string::npos) << c.what << ": " << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << c.what << ": one line: " << m;
    }
  }
  // What has no line: no cameras at all, or a file that is not a mapping.
  for (const std::string text : {"http: 8090\n", "- a\n- b\n"}) {
    const std::string path = Write(text);
    EXPECT_THROW(
        {
          try {
            LoadWatchConfig(path);
          } catch (const std::invalid_argument& e) {
            EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
            throw;
          }
        },
        std::invalid_argument);
  }
  EXPECT_THROW(LoadWatchConfig((dir_ / "absent.yaml").string()), std::invalid_argument);
}

TEST_F(WatchConfigTest, ValidateRefusesWhatAHandBuiltFarmGetsWrong) {
  WatchFarmOptions f;
  f.path = "farm.yaml";
  std::string why;
  EXPECT_FALSE(f.Validate(&why));
  EXPECT_NE(why.find("no cameras"), std::string::npos) << why;
  WatchCameraConfig a;
  a.name = "a";
  a.options.live.source = "a.mp4";
  f.cameras = {a, a};
  EXPECT_FALSE(f.Validate(&why));
  EXPECT_NE(why.find("taken twice"), std::string::npos) << why;
  f.cameras[1].name = "b/c";
  EXPECT_FALSE(f.Validate(&why));
  f.cameras[1].name = "b";
  EXPECT_TRUE(f.Validate(&why)) << why;
  f.http_token_file = "token";
  EXPECT_FALSE(f.Validate(&why));
  EXPECT_NE(why.find("http_token_file goes with http"), std::string::npos) << why;
  f.http = "0";
  EXPECT_TRUE(f.Validate(&why)) << why;
  f.mqtt.url = "mqtts://broker";
  EXPECT_FALSE(f.Validate(&why));
  EXPECT_NE(why.find("--mqtt"), std::string::npos) << why;
}

TEST_F(WatchConfigTest, TheCommandLineRefusesASourceOrPerCameraOptionsBesideConfig) {
  const std::string path = Write("cameras:\n  - {name: a, source: a.mp4}\n");
  for (const std::string& extra : {std::string("clip.mp4"), std::string("--scale-um-per-px 3"),
                                   std::string("--http 8090"), std::string("--log x.jsonl")}) {
    const testing::RunResult r = testing::RunCli("watch --config " + path + " " + extra, dir_);
    EXPECT_EQ(r.exit_code, 1) << extra;
    EXPECT_NE(r.err.find("with --config, every camera's source and options are in the file"),
              std::string::npos)
        << extra << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  // A bad file: its line, from the command.
  const std::string bad = Write("cameras:\n  - {name: a, source: a.mp4, window: 3}\n", "bad.yaml");
  const testing::RunResult r = testing::RunCli("watch --config " + bad, dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(bad + ":2: unknown key 'window' in a camera"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace clogscope::apps
