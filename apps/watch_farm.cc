#include "apps/watch_farm.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "apps/watch_camera.h"
#include "apps/watch_http.h"
#include "apps/watch_outputs.h"
#include "vision/io/live_source.h"
#include "watch/mqtt_publisher.h"

namespace clogscope::apps {
namespace {

using Clock = std::chrono::steady_clock;

// One camera's thread: its watch, started again with back-off while its stream cannot be opened.
WatchReport RunCamera(CameraWatch* camera, std::atomic<bool>* stop, watch::MqttPublisher* mqtt,
                      size_t index, const WatchFarmObservers& observers, std::string* error) {
  const watch::LiveWatchOptions& live = camera->live();
  double wait_s = live.reconnect_initial_s;
  while (true) {
    try {
      return camera->Run(
          stop,
          [&](const watch::WatchStatus& s, const std::optional<watch::ClogIndex>& clog) {
            if (mqtt) mqtt->Update(index, s, clog);
          },
          [&](const watch::WatchStatus& s) {
            if (observers.on_level_change) observers.on_level_change(camera->printer(), s);
          });
    } catch (const std::exception& e) {
      // Only the start throws (the watch reports later failures in its summary).
      if (!camera->StartMayBeRetried() || stop->load()) {
        *error = e.what();
        return {};
      }
      spdlog::warn("{}: {} (next try in {:g} s)", camera->printer(), e.what(), wait_s);
      const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(wait_s));
      if (!vision::SleepUnlessStopped(until, stop)) return {};
      wait_s = std::min(2 * wait_s, live.reconnect_max_s);
    }
  }
}

}  // namespace

WatchFarmReport WatchFarm(const WatchFarmOptions& options, std::atomic<bool>* stop,
                          const WatchFarmObservers& observers) {
  std::string why;
  if (!options.Validate(&why)) throw std::invalid_argument(why);
  // Every camera's options checked, and its log opened, before any starts.
  std::vector<std::unique_ptr<CameraWatch>> cameras;
  for (const WatchCameraConfig& c : options.cameras) {
    WatchCommandOptions o = c.options;
    if (options.duration_s > 0) o.live.duration_s = options.duration_s;
    try {
      cameras.push_back(std::make_unique<CameraWatch>(o, c.name, nullptr));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(
          fmt::format("{}:{}: camera '{}': {}", options.path, c.line, c.name, e.what()));
    }
  }
  WatchHttpOptions http_options;
  http_options.address = options.http;
  if (!options.http_token_file.empty()) http_options.token = ReadHttpToken(options.http_token_file);
  std::vector<watch::CameraFeed> feeds;
  for (const auto& c : cameras) feeds.push_back(c->Feed());
  std::optional<WatchHttpServer> http;
  if (!options.http.empty()) http.emplace(http_options, feeds);
  std::optional<watch::MqttPublisher> mqtt;
  if (!options.mqtt.url.empty()) mqtt.emplace(options.mqtt, feeds, MqttLog());
  WatchFarmReport report;
  report.http_port = http ? http->port() : 0;
  if (http) {
    for (const auto& c : cameras) c->SetHttpUrl(http->url() + "/cameras/" + c->printer());
    spdlog::info(
        "serving {} cameras on {}: /metrics and /status for them all, /cameras/NAME/ (the page), "
        "/cameras/NAME/status, /history.json and /frame.jpg for each",
        cameras.size(), http->url());
    if (!http->loopback_only() && http_options.token.empty())
      spdlog::warn(
          "http {}: reachable from other machines, with no http_token_file: whoever reaches the "
          "port sees the cameras' frames and states",
          options.http);
  }
  if (observers.on_started) observers.on_started(report.http_port);

  // Each camera stops on its own flag (a watch raises it when it ends); a stop of the farm raises
  // them all.
  const size_t n = cameras.size();
  std::vector<std::atomic<bool>> stops(n);
  for (auto& s : stops) s = false;
  report.names.resize(n);
  report.cameras.resize(n);
  std::vector<std::string> errors(n);
  std::mutex mutex;
  std::condition_variable ended;
  size_t running = n;
  std::vector<std::thread> threads;
  for (size_t i = 0; i < n; ++i) {
    report.names[i] = cameras[i]->printer();
    threads.emplace_back([&, i] {
      try {
        report.cameras[i] = RunCamera(cameras[i].get(), &stops[i], mqtt ? &*mqtt : nullptr, i,
                                      observers, &errors[i]);
      } catch (const std::exception& e) {  // an observer's throw: this camera ends, not the farm
        errors[i] = e.what();
      }
      if (!report.cameras[i].summary.error.empty()) errors[i] = report.cameras[i].summary.error;
      // Served on as ended, not as a source still up: /status, /metrics and MQTT say so.
      const watch::WatchSnapshot last = cameras[i]->PublishEnded();
      if (mqtt) mqtt->Update(i, last.status, last.clog);
      stops[i] = true;
      std::lock_guard<std::mutex> lock(mutex);
      --running;
      ended.notify_all();
    });
  }
  {
    std::unique_lock<std::mutex> lock(mutex);
    // A signal handler cannot notify: the farm's flag is looked at every 50 ms. --duration-s
    // ends the farm too, cameras still waiting to start included (a camera's own watch counts it
    // from its own start).
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(options.duration_s));
    while (running > 0) {
      if (stop->load() || (options.duration_s > 0 && Clock::now() >= deadline))
        for (auto& s : stops) s = true;
      ended.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  for (std::thread& t : threads) t.join();
  for (size_t i = 0; i < n; ++i) {
    if (errors[i].empty()) continue;
    spdlog::error("{}: {}", report.names[i], errors[i]);
    report.errors.push_back(report.names[i] + ": " + errors[i]);
  }
  if (observers.on_finished) observers.on_finished(report.http_port);
  stop->store(true);
  return report;
}

}  // namespace clogscope::apps
