#include "watch/mqtt_publisher.h"

#include <fmt/format.h>
#include <mosquitto.h>

#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "common/atomic_file.h"
#include "common/host_port.h"
#include "vision/io/source_name.h"
#include "watch/frame_jpeg.h"

namespace clogscope::watch {
namespace {

using Clock = std::chrono::steady_clock;

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// libmosquitto's process-wide set-up, once; never undone (a publisher's thread may outlive a stop
// that timed out).
void InitLibrary() {
  static const int once = mosquitto_lib_init();
  (void)once;
}

std::string ErrorText(int rc, int saved_errno) {
  return rc == MOSQ_ERR_ERRNO ? std::strerror(saved_errno) : mosquitto_strerror(rc);
}

// A stalled socket is seen within this much of the network loop (its select timeout).
constexpr int kLoopTimeoutMs = 100;
// Without an answer this long after the start (a silently dropped SYN), the broker is reported
// down once; a refusal is reported at once.
constexpr double kNoAnswerWarnS = 5;

}  // namespace

std::string MqttEndpoint::Shown() const {
  const bool v6 = host.find(':') != std::string::npos;
  return fmt::format("mqtt://{}{}{}:{}/{}", v6 ? "[" : "", host, v6 ? "]" : "", port, prefix);
}

bool ParseMqttUrl(const std::string& url, MqttEndpoint* out, std::string* why) {
  const std::string shown = vision::RedactCredentials(url);
  const auto fail = [&](const std::string& problem) {
    *why = fmt::format("--mqtt '{}': {}", shown, problem);
    return false;
  };
  const std::string scheme = "mqtt://";
  if (url.rfind("mqtts://", 0) == 0)
    return fail("mqtts (TLS) is not supported: use mqtt:// on a trusted network or a TLS tunnel");
  if (url.rfind(scheme, 0) != 0) return fail("expected mqtt://HOST[:PORT][/PREFIX]");
  const std::string rest = url.substr(scheme.size());
  const size_t slash = rest.find('/');
  const std::string authority = rest.substr(0, slash);
  std::string prefix = slash == std::string::npos ? "" : rest.substr(slash + 1);
  if (authority.find('@') != std::string::npos)
    return fail(
        "a user or password in the URL shows in `ps` and logs: put 'user:password' in a file for "
        "--mqtt-credentials-file");
  MqttEndpoint e;
  HostPort hp;
  std::string problem;
  if (!SplitHostPort(authority, 1, &hp, &problem)) return fail(problem);
  e.host = hp.host;
  if (hp.port) e.port = *hp.port;
  while (!prefix.empty() && prefix.back() == '/') prefix.pop_back();
  if (!prefix.empty()) e.prefix = prefix;
  if (e.prefix.find_first_of("+#") != std::string::npos)
    return fail("the topic prefix must not hold the wildcards '+' or '#'");
  if (e.prefix.front() == '/' || e.prefix.find("//") != std::string::npos)
    return fail("the topic prefix has an empty level");
  for (const char c : e.prefix)
    if (static_cast<unsigned char>(c) < 0x20)
      return fail("the topic prefix has a control character");
  *out = e;
  return true;
}

bool ReadMqttCredentials(const std::string& path, MqttCredentials* out, std::string* why) {
  const auto fail = [&](const std::string& problem) {
    *why = fmt::format("--mqtt-credentials-file {}: {}", path, problem);
    return false;
  };
  // TryReadFile refuses what is not a regular file: a FIFO would block the watch's start.
  std::string text, problem;
  if (!TryReadFile(path, &text, &problem)) return fail("cannot be read (" + problem + ")");
  if (text.size() > 4096) return fail("longer than 4096 bytes: not a 'user:password' line");
  if (!text.empty() && text.back() == '\n') text.pop_back();
  if (!text.empty() && text.back() == '\r') text.pop_back();
  if (text.find_first_of("\r\n") != std::string::npos)
    return fail("more than one line (expected one 'user:password' line)");
  const size_t colon = text.find(':');
  if (text.empty() || colon == std::string::npos || colon == 0)
    return fail("expected one line 'user:password'");
  out->user = text.substr(0, colon);
  out->password = text.substr(colon + 1);
  return true;
}

bool MqttOptions::Validate(std::string* why) const {
  MqttEndpoint endpoint;
  std::optional<MqttCredentials> credentials;
  return Resolve(&endpoint, &credentials, why);
}

bool MqttOptions::Resolve(MqttEndpoint* endpoint, std::optional<MqttCredentials>* credentials,
                          std::string* why) const {
  credentials->reset();
  if (url.empty()) {
    if (credentials_file.empty()) return true;
    *why = "--mqtt-credentials-file goes with --mqtt";
    return false;
  }
  if (!ParseMqttUrl(url, endpoint, why)) return false;
  if (!credentials_file.empty() &&
      !ReadMqttCredentials(credentials_file, &credentials->emplace(), why))
    return false;
  if (discovery_prefix.empty() || discovery_prefix.find_first_of("+#") != std::string::npos)
    *why = "the Home Assistant discovery prefix must be a topic without wildcards";
  else if (!(frame_min_interval_s >= 0))
    *why = "the MQTT picture interval must not be negative";
  else if (!(reconnect_initial_s >= 1 && reconnect_max_s >= reconnect_initial_s))
    *why = "MQTT reconnect back-off: initial >= 1 s and max >= initial";
  else if (!(keepalive_s >= 5 && stop_timeout_s > 0))
    *why = "MQTT keepalive >= 5 s and stop timeout > 0";
  else
    return true;
  return false;
}

// Two threads: the network thread runs libmosquitto's loop and reconnects with back-off (our own
// loop rather than mosquitto_loop_start's: that one ends for good on a failed name lookup or a
// refused login, and sleeps through its back-off where a stop cannot wake it); the publishing
// thread sends what Update left and draws the picture. Update only swaps the latest messages in.
struct MqttPublisher::Impl {
  // One camera's topics, picture and latest state (its fields after `frames` under `mutex`).
  struct Feed {
    Feed(const std::string& prefix, const std::string& availability, const Camera& c)
        : topics(prefix),
          frames(c.frames ? c.frames : std::make_shared<OverlayJpegCache>(c.board, c.conversion)) {
      topics.availability = availability;  // one for the process: its last will
    }
    MqttTopics topics;
    std::vector<MqttMessage> discovery;
    std::shared_ptr<OverlayJpegCache> frames;
    std::vector<MqttMessage> latest;  // the latest state's messages
    bool state_due = false, frame_due = false;
    Clock::time_point last_frame{};
  };

  Impl(const MqttOptions& o, const MqttEndpoint& e, const std::vector<Camera>& cameras, Log l)
      : options(o), endpoint(e), availability(e.prefix + "/availability"), log(std::move(l)) {
    for (const Camera& c : cameras) {
      const std::string prefix = c.name.empty() ? e.prefix : e.prefix + "/" + c.name;
      feeds.push_back(std::make_unique<Feed>(prefix, availability, c));
      feeds.back()->discovery =
          HaDiscoveryMessages(feeds.back()->topics, o.discovery_prefix, c.conversion.has_value());
    }
  }

  MqttOptions options;
  MqttEndpoint endpoint;
  std::optional<MqttCredentials> credentials;
  std::string availability;  // <prefix>/availability
  std::vector<std::unique_ptr<Feed>> feeds;
  Log log;
  mosquitto* mosq = nullptr;

  std::mutex mutex;
  std::condition_variable wake;
  // Under `mutex`.
  bool stopping = false;        // the publisher is being destroyed
  bool network_stop = false;    // the network thread ends
  bool quiet = false;           // no more log lines (the owner stopped waiting)
  bool connected = false;       // CONNACK accepted, not lost since
  bool ever_connected = false;  // once at least
  bool announce = false;        // (re)connected: availability, discovery and the latest state due
  bool warned = false;          // a connection problem was told since the last connection
  std::optional<int> offline_mid;
  bool offline_acked = false;
  bool publisher_done = false, network_done = false;
  std::thread network_thread, publish_thread;

  void Info(const std::string& m) {
    if (!quiet && log.info) log.info(m);
  }
  void Warn(const std::string& m) {
    if (!quiet && log.warning) log.warning(m);
  }
  // A connection problem, told once until the next connection (the back-off retries quietly).
  void Problem(const std::string& what) {
    if (warned || stopping) return;
    warned = true;
    Warn(
        fmt::format("MQTT {}: {}; retrying with back-off ({} s doubling to {} s), the watch "
                    "goes on",
                    endpoint.Shown(), what, options.reconnect_initial_s, options.reconnect_max_s));
  }

  static Impl* Self(void* obj) { return static_cast<Impl*>(obj); }
  static void OnConnect(mosquitto*, void* obj, int rc) {
    Impl* self = Self(obj);
    std::lock_guard<std::mutex> lock(self->mutex);
    if (rc != 0) {
      self->Problem(
          fmt::format("the broker refused the connection: {}", mosquitto_connack_string(rc)));
      return;
    }
    self->Info(fmt::format("MQTT: {} {} (Home Assistant discovery under {}/)",
                           self->ever_connected ? "connected again to" : "publishing to",
                           self->endpoint.Shown(), self->options.discovery_prefix));
    self->connected = self->ever_connected = self->announce = true;
    self->warned = false;
    self->wake.notify_all();
  }
  static void OnDisconnect(mosquitto*, void* obj, int rc) {
    const int saved_errno = errno;
    Impl* self = Self(obj);
    std::lock_guard<std::mutex> lock(self->mutex);
    const bool was = self->connected;
    self->connected = false;
    if (rc != 0)
      self->Problem(fmt::format("{} ({})", was ? "the connection was lost" : "cannot connect",
                                ErrorText(rc, saved_errno)));
    self->wake.notify_all();
  }
  static void OnPublish(mosquitto*, void* obj, int mid) {
    Impl* self = Self(obj);
    std::lock_guard<std::mutex> lock(self->mutex);
    if (self->offline_mid == mid) self->offline_acked = true;
    self->wake.notify_all();
  }

  void Send(const MqttMessage& m) {
    // Not connected any more: dropped; the next connection sends the latest state again.
    mosquitto_publish(mosq, nullptr, m.topic.c_str(), static_cast<int>(m.payload.size()),
                      m.payload.data(), m.qos, m.retain);
  }

  void RunNetwork() {
    // The name lookup blocks here, on this thread, never the watch's.
    errno = 0;
    int rc =
        mosquitto_connect_async(mosq, endpoint.host.c_str(), endpoint.port, options.keepalive_s);
    const int connect_errno = errno;
    if (rc != MOSQ_ERR_SUCCESS) {
      std::lock_guard<std::mutex> lock(mutex);
      Problem(fmt::format("cannot connect ({})", ErrorText(rc, connect_errno)));
    }
    const auto started = Clock::now();
    int wait_s = options.reconnect_initial_s;
    std::unique_lock<std::mutex> lock(mutex);
    while (!network_stop) {
      if (connected) wait_s = options.reconnect_initial_s;
      if (!ever_connected && Clock::now() - started > Seconds(kNoAnswerWarnS))
        Problem(fmt::format("no answer within {:g} s", kNoAnswerWarnS));
      lock.unlock();
      if (rc == MOSQ_ERR_SUCCESS) rc = mosquitto_loop(mosq, kLoopTimeoutMs, 1);
      lock.lock();
      if (rc == MOSQ_ERR_SUCCESS || network_stop) continue;
      // Down, refused or lost: wait (a stop wakes it), then try again.
      wake.wait_for(lock, std::chrono::seconds(wait_s), [&] { return network_stop; });
      wait_s = std::min(2 * wait_s, options.reconnect_max_s);
      if (network_stop) break;
      if (stopping) continue;  // no new connection for a publisher on its way out
      lock.unlock();
      errno = 0;
      rc = mosquitto_reconnect_async(mosq);
      const int saved_errno = errno;
      lock.lock();
      if (rc != MOSQ_ERR_SUCCESS)
        Problem(fmt::format("cannot connect ({})", ErrorText(rc, saved_errno)));
    }
    network_done = true;
    wake.notify_all();
  }

  // The states due, taken (under `mutex`).
  std::vector<MqttMessage> TakeStates(bool all) {
    std::vector<MqttMessage> out;
    for (auto& f : feeds) {
      if (!f->state_due && !all) continue;
      f->state_due = false;
      out.insert(out.end(), f->latest.begin(), f->latest.end());
    }
    return out;
  }

  void RunPublisher() {
    std::unique_lock<std::mutex> lock(mutex);
    while (!stopping) {
      // The camera whose picture is due soonest (frame_at), if any.
      Feed* picture = nullptr;
      Clock::time_point frame_at = Clock::time_point::max();
      bool state_due = false;
      for (auto& f : feeds) {
        state_due = state_due || f->state_due;
        const Clock::time_point at = f->last_frame + Seconds(options.frame_min_interval_s);
        if (f->frame_due && at < frame_at) {
          picture = f.get();
          frame_at = at;
        }
      }
      if (connected && announce) {
        announce = false;
        for (auto& f : feeds) f->frame_due = true;  // the pictures too, once frames are there
        const std::vector<MqttMessage> state = TakeStates(/*all=*/true);
        lock.unlock();
        Send({availability, kMqttOnline});
        for (auto& f : feeds)
          for (const MqttMessage& m : f->discovery) Send(m);
        for (const MqttMessage& m : state) Send(m);
        lock.lock();
      } else if (connected && state_due) {
        const std::vector<MqttMessage> state = TakeStates(/*all=*/false);
        lock.unlock();
        for (const MqttMessage& m : state) Send(m);
        lock.lock();
      } else if (connected && picture && Clock::now() >= frame_at) {
        picture->frame_due = false;
        lock.unlock();
        // Drawn here, never on the measuring thread. No frame yet: the next update asks again.
        const auto jpeg = picture->frames->Latest();
        if (jpeg) Send({picture->topics.frame, std::string(jpeg->begin(), jpeg->end()), /*qos=*/0});
        lock.lock();
        if (jpeg) picture->last_frame = Clock::now();
      } else if (connected && picture) {
        wake.wait_until(lock, frame_at);
      } else {
        wake.wait(lock);
      }
    }
    // Stopping: the last state (the watch's "stop" report may have come just before the stop, not
    // yet sent), then "offline" (retained) while still connected, and its acknowledgement awaited,
    // so that it is there before the disconnection; then a clean disconnection (no last will).
    const auto deadline = Clock::now() + Seconds(options.stop_timeout_s * 0.7);
    if (connected) {
      const std::vector<MqttMessage> state = TakeStates(/*all=*/false);
      lock.unlock();
      for (const MqttMessage& m : state) Send(m);
      lock.lock();
    }
    if (connected) {
      int mid = 0;
      const std::string offline = kMqttOffline;
      lock.unlock();
      const int rc = mosquitto_publish(mosq, &mid, availability.c_str(),
                                       static_cast<int>(offline.size()), offline.data(), 1, true);
      lock.lock();
      if (rc == MOSQ_ERR_SUCCESS) {
        offline_mid = mid;
        wake.wait_until(lock, deadline, [&] { return offline_acked || !connected; });
      }
    }
    lock.unlock();
    mosquitto_disconnect(mosq);
    lock.lock();
    wake.wait_until(lock, deadline + Seconds(options.stop_timeout_s * 0.2),
                    [&] { return !connected; });
    network_stop = true;
    wake.notify_all();
    wake.wait(lock, [&] { return network_done; });
    lock.unlock();
    mosquitto_destroy(mosq);
    lock.lock();
    mosq = nullptr;
    publisher_done = true;
    wake.notify_all();
  }
};

MqttPublisher::MqttPublisher(const MqttOptions& options, const WatchBoard* board,
                             std::optional<calib::ScaleCalibration> conversion, Log log,
                             std::shared_ptr<OverlayJpegCache> frames)
    : MqttPublisher(options, {Camera{"", board, std::move(conversion), std::move(frames)}},
                    std::move(log)) {}

MqttPublisher::MqttPublisher(const MqttOptions& options, std::vector<Camera> cameras, Log log) {
  std::string why;
  MqttEndpoint endpoint;
  std::optional<MqttCredentials> credentials;
  if (!options.Resolve(&endpoint, &credentials, &why)) throw std::invalid_argument(why);
  if (cameras.empty()) throw std::invalid_argument("MQTT: no camera to publish");
  impl_ = std::make_shared<Impl>(options, endpoint, cameras, std::move(log));
  Impl& m = *impl_;
  m.credentials = std::move(credentials);
  InitLibrary();
  // One client id per prefix: a watch started again takes its predecessor's session over (the
  // broker sends that one's last will first), so "online" is never overwritten by a stale will.
  const std::string client_id = "clogscope-" + MqttTopics(endpoint.prefix).node_id;
  m.mosq = mosquitto_new(client_id.c_str(), /*clean_session=*/true, &m);
  if (!m.mosq) throw std::runtime_error("MQTT: cannot create the client (out of memory)");
  mosquitto_threaded_set(m.mosq, true);
  mosquitto_connect_callback_set(m.mosq, &Impl::OnConnect);
  mosquitto_disconnect_callback_set(m.mosq, &Impl::OnDisconnect);
  mosquitto_publish_callback_set(m.mosq, &Impl::OnPublish);
  // Set before connecting: the broker publishes it when this client vanishes without a word.
  mosquitto_will_set(m.mosq, m.availability.c_str(), static_cast<int>(std::strlen(kMqttOffline)),
                     kMqttOffline, 1, true);
  if (m.credentials)
    mosquitto_username_pw_set(m.mosq, m.credentials->user.c_str(), m.credentials->password.c_str());
  // The threads share the Impl: if a stop gives up on them (a name lookup that hangs), they finish
  // on their own and the last one frees it.
  std::shared_ptr<Impl> self = impl_;
  m.network_thread = std::thread([self] { self->RunNetwork(); });
  m.publish_thread = std::thread([self] { self->RunPublisher(); });
}

MqttPublisher::~MqttPublisher() {
  Impl& m = *impl_;
  std::unique_lock<std::mutex> lock(m.mutex);
  m.stopping = true;
  m.wake.notify_all();
  const bool done = m.wake.wait_for(lock, Seconds(m.options.stop_timeout_s + 0.3),
                                    [&] { return m.publisher_done; });
  if (!done) m.quiet = true;  // the process may be ending: no log line from a thread left behind
  lock.unlock();
  if (done) {
    m.publish_thread.join();
    m.network_thread.join();
  } else {
    m.publish_thread.detach();
    m.network_thread.detach();
  }
}

void MqttPublisher::Update(const WatchStatus& status, const std::optional<ClogIndex>& clog) {
  Update(0, status, clog);
}

void MqttPublisher::Update(size_t camera, const WatchStatus& status,
                           const std::optional<ClogIndex>& clog) {
  Impl::Feed& f = *impl_->feeds.at(camera);
  std::vector<MqttMessage> messages = MqttStateMessages(f.topics, status, clog);
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    f.latest = std::move(messages);
    f.state_due = f.frame_due = true;
  }
  impl_->wake.notify_all();
}

}  // namespace clogscope::watch
