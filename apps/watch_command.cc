#include "apps/watch_command.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <stdexcept>

#include "apps/cli_util.h"
#include "apps/measure_options.h"
#include "apps/watch_camera.h"
#include "apps/watch_config.h"
#include "apps/watch_farm.h"
#include "apps/watch_http.h"
#include "apps/watch_outputs.h"
#include "model/prediction_run.h"
#include "pipeline/experiment.h"

namespace clogscope::apps {
namespace {

std::atomic<bool> g_stop_watch{false};

extern "C" void OnWatchSignal(int) {
  // A second Ctrl-C while the watch winds down ends it at once.
  if (g_stop_watch.exchange(true)) _exit(130);
}

// Installs the stop on Ctrl-C and SIGTERM for the duration of `run`.
template <typename Run>
auto WithStopSignals(Run run) {
  g_stop_watch.store(false);
  std::signal(SIGINT, OnWatchSignal);
  std::signal(SIGTERM, OnWatchSignal);
  try {
    auto result = run();
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    return result;
  } catch (...) {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    throw;
  }
}

// `watch --config FILE`: every camera's options come from the file; the command line may only
// add --duration-s.
int RunWatchFarm(const CLI::App& app, const std::string& config, double duration_s) {
  for (const CLI::Option* o : app.get_options()) {
    if (o->count() == 0 || o->get_name() == "--config" || o->get_name() == "--duration-s") continue;
    const std::string name = o->get_name() == "source" ? "a source" : o->get_name();
    throw std::invalid_argument(fmt::format(
        "--config {} and {}: with --config, every camera's source and options are in the file "
        "(only --duration-s may be added)",
        config, name));
  }
  WatchFarmOptions farm = LoadWatchConfig(config);
  farm.duration_s = duration_s;
  const WatchFarmReport r = WithStopSignals([&] { return WatchFarm(farm, &g_stop_watch); });
  for (size_t i = 0; i < r.names.size(); ++i)
    LogWatchEnded(r.names[i] + ": ", r.cameras[i].summary);
  if (!r.errors.empty())
    throw std::invalid_argument(fmt::format("{} of {} cameras failed: {}", r.errors.size(),
                                            r.names.size(), fmt::join(r.errors, "; ")));
  return 0;
}

}  // namespace

WatchReport WatchNozzle(const WatchCommandOptions& options, std::atomic<bool>* stop,
                        const WatchObservers& observers) {
  CameraWatch camera(options, "", observers.on_printer);
  if (!options.http_token_file.empty() && options.http.empty())
    throw std::invalid_argument("--http-token-file goes with --http");
  WatchHttpOptions http_options;
  http_options.address = options.http;
  if (!options.http_token_file.empty()) http_options.token = ReadHttpToken(options.http_token_file);

  std::optional<WatchHttpServer> http;
  const watch::CameraFeed feed = camera.Feed();
  if (!options.http.empty()) http.emplace(http_options, feed.board, feed.conversion, feed.frames);
  std::optional<watch::MqttPublisher> mqtt;
  if (!options.mqtt.url.empty() || !options.mqtt.credentials_file.empty())
    mqtt.emplace(options.mqtt, feed.board, feed.conversion, MqttLog(), feed.frames);
  const int http_port = http ? http->port() : 0;
  if (http) {
    camera.SetHttpUrl(http->url());
    spdlog::info("serving the page at /, /status, /history.json, /metrics and /frame.jpg on {}{}",
                 http->url(),
                 http_options.token.empty()
                     ? ""
                     : " (a bearer token for all but / and /metrics: open the page as "
                       "/#token=TOKEN)");
    if (!http->loopback_only() && http_options.token.empty())
      spdlog::warn(
          "--http {}: reachable from other machines, with no --http-token-file: whoever reaches "
          "the port sees the camera's frames and the state",
          options.http);
  }
  if (observers.on_started) observers.on_started(http_port);
  WatchReport report = camera.Run(
      stop,
      [&](const watch::WatchStatus& s, const std::optional<watch::ClogIndex>& clog) {
        if (mqtt) mqtt->Update(s, clog);
      },
      observers.on_level_change);
  report.http_port = http_port;
  return report;
}

int RunWatch(int argc, char** argv) {
  CLI::App app{
      "Watch a nozzle live: the effective diameter from a camera, stream, video file or folder, "
      "its drift from a baseline, a clog index and alert levels (ok, warn, clog, not_extruding, "
      "no_view) as JSON lines, over HTTP and through a command.",
      "clogscope watch"};
  WatchCommandOptions o;
  MeasureCliText text;
  watch::LiveWatchOptions& live = o.live;
  watch::WatchOptions& w = live.watch;
  app.add_option("source", live.source,
                 "/dev/videoN, a stream URL (http://…/?action=stream, rtsp://, tcp://, udp://), a "
                 "video file, or a folder a camera writes images into; with --moonraker, "
                 "default its webcam's stream");
  AddMeasurementOptions(app, &o.measure, &text);
  app.add_flag("--realtime", live.source_options.realtime,
               "Video file: deliver frames at their timestamps (replays, tests)");
  app.add_option("--open-timeout-s", live.source_options.open_timeout_s,
                 "A stream must deliver its first frame within this")
      ->capture_default_str();
  app.add_option("--read-timeout-s", live.source_options.read_timeout_s,
                 "A stream silent this long has dropped: reopen it")
      ->capture_default_str();
  app.add_option("--window-s", w.window_s, "Rolling statistics over the last window")
      ->capture_default_str();
  app.add_option("--alert-window-s", w.alert_window_s,
                 "The alert levels test the drift of the last this-many seconds")
      ->capture_default_str();
  app.add_option("--baseline-s", w.baseline_s, "Baseline: the first seconds of valid frames")
      ->capture_default_str();
  app.add_option("--baseline-um", w.baseline_um, "Or a given baseline diameter (needs a scale)");
  app.add_option("--warn-pct", w.warn_drift_pct, "Drift that raises warn")->capture_default_str();
  app.add_option("--clog-pct", w.clog_drift_pct, "Drift that raises clog")->capture_default_str();
  app.add_option("--hysteresis-pct", w.hysteresis_pct,
                 "A drift level is left this far back above its threshold")
      ->capture_default_str();
  app.add_option("--hold-s", w.hold_s, "A level's condition must hold this long")
      ->capture_default_str();
  app.add_option("--min-valid-fraction", w.min_valid_fraction,
                 "Fewer valid frames than this in the window: not_extruding or no_view")
      ->capture_default_str();
  app.add_option("--extruder", o.extruder,
                 "Preset or YAML: attach the predictor (back-pressure ratio, vibration increase)");
  app.add_option("--set", o.set, "name=value overrides of the extruder's parameters");
  app.add_option("--temperature-c", o.temperature_c,
                 "Nozzle temperature for the clog index (default: the extruder's reference)");
  app.add_option("--log", o.log_path, "Append the JSON lines here (default: standard output)");
  app.add_option("--report-s", live.report_every_s,
                 "A status line every this-many seconds (default: --window-s)");
  app.add_option("--http", o.http,
                 "[HOST:]PORT to serve a page at / (live frame, diameter history, level), "
                 "/status, /history.json, /metrics and /frame.jpg: a port alone is "
                 "127.0.0.1, this machine only; 0.0.0.0:PORT lets every network that reaches "
                 "this machine see the camera's frames and the state, unencrypted: add "
                 "--http-token-file, or keep it on a trusted network");
  app.add_option("--http-token-file", o.http_token_file,
                 "A file holding a bearer token (one line, at least 16 characters): every path "
                 "but / and /metrics then asks for 'Authorization: Bearer TOKEN' (open the page "
                 "as http://HOST:PORT/#token=TOKEN)");
  app.add_option("--on-alert", o.on_alert,
                 "Shell command run on every level change (state in CLOGSCOPE_* variables)");
  app.add_option("--mqtt", o.mqtt.url,
                 "mqtt://HOST[:PORT][/PREFIX]: publish the state (retained) to PREFIX/state, "
                 "/level, /diameter_mm, /availability and /frame, with Home Assistant discovery");
  app.add_option("--mqtt-credentials-file", o.mqtt.credentials_file,
                 "A file holding one line 'user:password' for the MQTT broker");
  watch::PrinterLinkOptions& p = o.printer;
  std::string pause_level = "clog";
  app.add_option("--moonraker", p.moonraker_url,
                 "http://HOST (Klipper; the web interface's address, which proxies Moonraker's "
                 "API and webcam, or Moonraker's own HOST:7125): pause the print on a clog while "
                 "it prints; with no source, watch the webcam Moonraker lists");
  app.add_option("--octoprint", p.octoprint_url,
                 "http://HOST: pause the print on a clog through OctoPrint's REST API");
  app.add_option("--printer-api-key-file", p.api_key_file,
                 "A file holding the printer's API key (one line), sent as X-Api-Key");
  app.add_option("--pause-level", pause_level, "The level that pauses: clog, or warn")
      ->capture_default_str();
  app.add_option("--pause-holdoff-s", p.pause.holdoff_s,
                 "After a resume, no pause for this long (the watch's seconds)")
      ->capture_default_str();
  app.add_option("--printer-poll-s", p.poll_interval_s, "Ask the job's state this often")
      ->capture_default_str();
  app.add_option("--webcam", p.webcam,
                 "Moonraker's webcam to watch, by name (default: the first "
                 "enabled)");
  app.add_option("--moonraker-notify-macro", p.notify_macro,
                 "A Klipper macro run after a pause (NAME LEVEL=… TIME_S=… DRIFT_PCT=…), e.g. one "
                 "that calls Moonraker's notifier");
  app.add_option("--duration-s", live.duration_s, "Stop after this long (default: until Ctrl-C)");
  std::string config;
  app.add_option("--config", config,
                 "A YAML file of many cameras watched by this one process (docs/watch.md): "
                 "http, mqtt and defaults at its top, then each camera's name, source and "
                 "options; with it, no source and no other option but --duration-s");
  app.footer(
      "Examples:\n"
      "  clogscope watch http://printer.local/webcam/?action=stream --calib calib.yaml \\\n"
      "      --http 8090 --log watch.jsonl             # served to this machine only\n"
      "  head -c 24 /dev/urandom | base64 > token && chmod 600 token\n"
      "  clogscope watch /dev/video0 --scale-um-per-px 3 --http 0.0.0.0:8090 \\\n"
      "      --http-token-file token                   # to the network, behind a token\n"
      "  clogscope watch /dev/video0 --scale-um-per-px 3 --extruder direct-pla --temperature-c "
      "210\n"
      "  clogscope watch --moonraker http://printer.local --printer-api-key-file key \\\n"
      "      --calib calib.yaml                        # its webcam; pauses on a clog\n"
      "  clogscope watch replay.mp4 --realtime --scale-um-per-px 3 --on-alert \\\n"
      "      'curl -s -X POST http://printer.local/printer/print/pause'\n"
      "Exit status: 0 after Ctrl-C, the file's end or --duration-s; 1 when nothing could be "
      "watched or the source failed.");
  if (!ParseCommandLine(app, argc, argv)) return 0;
  if (!config.empty()) return RunWatchFarm(app, config, live.duration_s);
  ApplyMeasurementOptions(app, text, &o.measure);
  if (!watch::ParsePauseLevel(pause_level, &p.pause.pause_level))
    throw std::invalid_argument("--pause-level " + pause_level + ": warn or clog");
  const WatchReport r = WithStopSignals([&] { return WatchNozzle(o, &g_stop_watch); });
  LogWatchEnded("", r.summary);
  if (!r.summary.error.empty()) throw std::invalid_argument(r.summary.error);
  return 0;
}

}  // namespace clogscope::apps
