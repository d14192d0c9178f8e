#pragma once

// `clogscope watch --config cameras.yaml`: a farm of cameras watched by one process. The file
// (docs/watch.md) holds the per-process options at its top (http, http_token_file, mqtt,
// mqtt_credentials_file), `defaults` for every camera, and `cameras`, each with a unique `name`,
// its `source` and any per-camera option of the command line, spelt without dashes
// (scale_um_per_px, calib, target, window_s, moonraker, on_alert, log…).

#include <string>
#include <vector>

#include "apps/watch_command.h"
#include "watch/mqtt_publisher.h"

namespace clogscope::apps {

struct WatchCameraConfig {
  std::string name;  // the printer's label: [A-Za-z0-9_-]+, unique in the file
  // Its options as the command line would give them; http, http_token_file and mqtt stay empty.
  WatchCommandOptions options;
  int line = 0;  // where the camera starts in the file
};

struct WatchFarmOptions {
  std::string path;             // the file read
  std::string http;             // [HOST:]PORT of the one server; empty: none
  std::string http_token_file;  // as --http-token-file
  watch::MqttOptions mqtt;      // one connection for every camera; no url: none
  double duration_s = 0;        // --duration-s: stop every camera after this long; 0: never
  std::vector<WatchCameraConfig> cameras;
  // False with one line in *why: no camera, a name that is not [A-Za-z0-9_-]+ or is taken twice,
  // a camera with neither source nor moonraker, a token file without http, bad MQTT options.
  bool Validate(std::string* why) const;
};

// True when `name` may label a printer: 1 to 64 of [A-Za-z0-9_-].
bool IsPrinterName(const std::string& name);

// Reads and checks the file. Paths in it (calib, log, key and token files, a file source, an
// extruder's YAML) are relative to its folder. Throws std::invalid_argument with one line
// "PATH:LINE: problem" (unknown key, wrong type, duplicate name, a value refused…).
WatchFarmOptions LoadWatchConfig(const std::string& path);

}  // namespace clogscope::apps
