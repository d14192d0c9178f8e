#pragma once

// `watch --mqtt`: the watch's state published to an MQTT broker through libmosquitto, for Home
// Assistant (discovery), Moonraker's [sensor] of type mqtt, or anything that subscribes.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "watch/frame_jpeg.h"
#include "watch/live_watch.h"
#include "watch/mqtt_messages.h"

namespace clogscope::watch {

inline constexpr int kMqttDefaultPort = 1883;

// Where --mqtt points: mqtt://HOST[:PORT][/PREFIX], HOST a name, an IPv4 address or [IPv6].
struct MqttEndpoint {
  std::string host;
  int port = kMqttDefaultPort;
  std::string prefix = "clogscope";  // the topics' prefix; no '+', '#' or empty level
  std::string Shown() const;         // "mqtt://host:1883/prefix" (never a password)
};

// False with a line naming --mqtt in *why when the URL is not mqtt://HOST[:PORT][/PREFIX]: another
// scheme (mqtts is not supported), credentials in the URL (they belong in
// --mqtt-credentials-file, and are hidden in the line), a bad port or a prefix with wildcards.
bool ParseMqttUrl(const std::string& url, MqttEndpoint* endpoint, std::string* why);

struct MqttCredentials {
  std::string user, password;
};
// --mqtt-credentials-file PATH: one line "user:password" (split at the first ':'). False with a
// line naming the option and the file (never its content) when it cannot be read, is empty, has no
// ':' or more than one line.
bool ReadMqttCredentials(const std::string& path, MqttCredentials* credentials, std::string* why);

struct MqttOptions {
  std::string url;               // --mqtt; empty: no MQTT
  std::string credentials_file;  // --mqtt-credentials-file; empty: anonymous
  std::string discovery_prefix = kHaDiscoveryPrefix;
  double frame_min_interval_s = 2;  // the camera's picture: at most one per this (JPEG, ~50 kB)
  int reconnect_initial_s = 1;      // back-off after a failed or lost connection: doubles up to
  int reconnect_max_s = 30;         // max (libmosquitto's whole seconds)
  int keepalive_s = 15;             // a silent broker is dead after 1.5× this; so is this client
  double stop_timeout_s = 1.5;      // a stop waits at most this for the broker (offline, then bye)
  // Checks the URL and reads the credentials file: false with one line naming the option.
  bool Validate(std::string* why) const;
  // Validate that also hands back the parsed URL and the credentials read (nullopt: anonymous),
  // so that what is used is what was checked.
  bool Resolve(MqttEndpoint* endpoint, std::optional<MqttCredentials>* credentials,
               std::string* why) const;
};

// Publishes on its own thread; libmosquitto's loop runs on another, which reconnects with back-off
// (1 s doubling to 30 s) when the broker is down at the start, refuses the login or drops later. On
// every (re)connection: <prefix>/availability "online", the discovery configs, the latest state and
// picture, all retained; the last will, set before connecting, is "offline" (retained), and a stop
// publishes "offline" itself. Messages are dropped, not queued, while the broker is away (the
// latest state is sent when it is back).
class MqttPublisher {
 public:
  struct Log {
    std::function<void(const std::string&)> info, warning;  // called on any thread
  };
  // Starts at once (connecting in the background). Throws std::invalid_argument (one line naming
  // the option) when the options do not validate. `board` gives the picture for the camera and
  // must outlive the publisher.
  MqttPublisher(const MqttOptions& options, const WatchBoard* board,
                std::optional<calib::ScaleCalibration> conversion, Log log,
                std::shared_ptr<OverlayJpegCache> frames = nullptr);
  // A camera of a farm (`watch --config`): its topics are <prefix>/<name>/state, /level,
  // /diameter_mm and /frame, its Home Assistant device <prefix>_<name>.
  using Camera = CameraFeed;
  // Many cameras over one connection: one <prefix>/availability (one last will) for them all.
  MqttPublisher(const MqttOptions& options, std::vector<Camera> cameras, Log log);
  // Publishes "offline", disconnects and ends the threads, waiting at most about stop_timeout_s
  // (a broker that does not answer is left to its keepalive and the last will).
  ~MqttPublisher();
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  // The state, retained, on every status report and level change: never waits for the network
  // (the watch's measuring thread calls it). A new picture goes with it, at most one per
  // frame_min_interval_s.
  void Update(const WatchStatus& status, const std::optional<ClogIndex>& clog);
  // The same for camera `camera` (its index in the cameras given).
  void Update(size_t camera, const WatchStatus& status, const std::optional<ClogIndex>& clog);

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;  // shared with its thread, which may outlive a stop that timed out
};

}  // namespace clogscope::watch
