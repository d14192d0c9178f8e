#include "watch/printer_link.h"

#include <fmt/format.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/csv.h"
#include "vision/io/source_name.h"
#include "watch/moonraker_client.h"
#include "watch/octoprint_client.h"

namespace clogscope::watch {
namespace {

using Clock = std::chrono::steady_clock;

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// A Klipper macro name: letters, digits and '_' (what a G-code command may be).
bool IsMacroName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

}  // namespace

const char* PrinterEventName(PrinterEvent::Kind kind) {
  switch (kind) {
    case PrinterEvent::Kind::kState:
      return "state";
    case PrinterEvent::Kind::kResumed:
      return "resumed";
    case PrinterEvent::Kind::kPauseSent:
      return "pause_sent";
    case PrinterEvent::Kind::kPauseFailed:
      return "pause_failed";
    case PrinterEvent::Kind::kNotified:
      return "notified";
  }
  return "unknown";
}

bool PrinterLinkOptions::Validate(std::string* why) const {
  std::string base, key;
  return Resolve(&base, &key, why);
}

bool PrinterLinkOptions::Resolve(std::string* base, std::string* key, std::string* why) const {
  key->clear();
  if (!moonraker_url.empty() && !octoprint_url.empty()) {
    *why = "--moonraker and --octoprint: one printer per watch";
    return false;
  }
  if (!enabled()) {
    for (const auto& [set, name] : {std::pair{!api_key_file.empty(), "--printer-api-key-file"},
                                    std::pair{!webcam.empty(), "--webcam"},
                                    std::pair{!notify_macro.empty(), "--moonraker-notify-macro"}})
      if (set) {
        *why = std::string(name) + " goes with --moonraker or --octoprint";
        return false;
      }
    return true;
  }
  const bool moonraker = !moonraker_url.empty();
  if (!ParsePrinterUrl(moonraker ? "--moonraker" : "--octoprint",
                       moonraker ? moonraker_url : octoprint_url, base, why))
    return false;
  if (!moonraker && (!webcam.empty() || !notify_macro.empty())) {
    *why = std::string(!webcam.empty() ? "--webcam" : "--moonraker-notify-macro") +
           " goes with --moonraker (OctoPrint has neither)";
    return false;
  }
  if (!notify_macro.empty() && !IsMacroName(notify_macro)) {
    *why = fmt::format("--moonraker-notify-macro '{}': a Klipper macro's name (letters, digits, _)",
                       notify_macro);
    return false;
  }
  if (!pause.Validate(why)) return false;
  if (!(std::isfinite(poll_interval_s) && poll_interval_s >= 0.05 && poll_interval_s <= 3600)) {
    *why = "--printer-poll-s must be in [0.05, 3600]";
    return false;
  }
  if (!(std::isfinite(request_timeout_s) && request_timeout_s > 0 && request_timeout_s <= 60)) {
    *why = "the printer request timeout must be in (0, 60] s";
    return false;
  }
  return api_key_file.empty() || ReadApiKeyFile(api_key_file, key, why);
}

struct PrinterLink::Impl {
  PrinterLinkOptions options;
  std::string base;
  std::string key;  // for a client of the caller's own (WebcamSource); never shown
  Log log;
  std::function<void(const PrinterEvent&)> on_event;
  std::unique_ptr<PrinterApi> api;
  MoonrakerClient* moonraker = nullptr;  // api, when it is Moonraker's
  PausePolicy policy;

  std::mutex mutex;
  std::condition_variable wake;
  // Under `mutex`.
  bool stopping = false;
  bool update_due = false;
  double latest_time_s = 0;
  bool has_state = false;  // an Update came
  WatchLevel latest_level = WatchLevel::kStarting;
  std::string latest_reason;
  double latest_drift_pct = NAN;  // the alert window's; NaN while not known
  bool poll_now = false;
  std::thread thread;
  // The worker's own (no lock).
  bool state_warned = false;  // a failed state question was told (until one succeeds)
  PrintState told_state = PrintState::kUnknown;

  Impl(const PrinterLinkOptions& o, Log l, std::function<void(const PrinterEvent&)> e)
      : options(o), log(std::move(l)), on_event(std::move(e)), policy(o.pause) {}

  void Info(const std::string& m) const {
    if (log.info) log.info(m);
  }
  void Warn(const std::string& m) const {
    if (log.warning) log.warning(m);
  }
  void Tell(const PrinterEvent& e) const {
    if (on_event) on_event(e);
  }
  std::string Who() const { return fmt::format("{} {}", api->name(), base); }

  // Asks the job's state and feeds the policy; called without the lock.
  void Poll() {
    PrintState state = PrintState::kUnknown;
    const PrinterReply reply = api->QueryState(&state);
    if (!reply.ok()) {
      if (!state_warned)
        Warn(fmt::format("{}: {} ({}); pausing is disarmed until it answers, the watch goes on",
                         Who(), reply.detail, PrinterErrorName(reply.error)));
      state_warned = true;
    } else if (state_warned) {
      state_warned = false;
      Info(fmt::format("{}: answering again", Who()));
    }
    double t;
    bool resumed;
    std::optional<double> holdoff_until;
    {
      std::lock_guard<std::mutex> lock(mutex);
      t = latest_time_s;
      resumed = policy.OnPrinterState(t, state);
      holdoff_until = policy.holdoff_until_s();
    }
    if (state != told_state) {
      told_state = state;
      if (state != PrintState::kUnknown)
        Info(fmt::format("{}: the job is {}: pausing {}", Who(), PrintStateName(state),
                         state == PrintState::kPrinting ? "armed" : "disarmed"));
      Tell({PrinterEvent::Kind::kState, t, state, reply.error, reply.detail});
    }
    if (resumed) {
      Info(fmt::format("{}: the print was resumed at {:.1f} s: no pause before {:.1f} s", Who(), t,
                       holdoff_until.value_or(t)));
      Tell({PrinterEvent::Kind::kResumed, t, state, PrinterError::kNone, ""});
    }
  }

  void PauseNow(double t, WatchLevel level, const std::string& reason, double drift_pct) {
    const PrinterReply reply = api->Pause();
    {
      std::lock_guard<std::mutex> lock(mutex);
      policy.OnPauseResult(latest_time_s, reply.ok());
      poll_now = true;  // the state it left, soon: a resume is seen from it
    }
    if (!reply.ok()) {
      Warn(
          fmt::format("{}: the print could not be paused at {:.1f} s ({}): {}; tried again in "
                      "{:g} s while the level holds",
                      Who(), t, WatchLevelName(level), reply.detail, options.pause.retry_s));
      Tell({PrinterEvent::Kind::kPauseFailed, t, PrintState::kUnknown, reply.error, reply.detail});
      return;
    }
    Warn(fmt::format("{}: paused the print at {:.1f} s ({}: {})", Who(), t, WatchLevelName(level),
                     reason));
    Tell({PrinterEvent::Kind::kPauseSent, t, PrintState::kUnknown, PrinterError::kNone, ""});
    if (moonraker && !options.notify_macro.empty()) {
      // Parameters without blanks: no quoting for Klipper's command line to get wrong.
      std::string script = fmt::format("{} LEVEL={} TIME_S={}", options.notify_macro,
                                       WatchLevelName(level), CsvNumber(t, 1));
      if (std::isfinite(drift_pct)) script += " DRIFT_PCT=" + CsvNumber(drift_pct, 2);
      const PrinterReply notified = moonraker->RunGcode(script);
      if (!notified.ok())
        Warn(fmt::format("{}: --moonraker-notify-macro {}: {}", Who(), options.notify_macro,
                         notified.detail));
      Tell({PrinterEvent::Kind::kNotified, t, PrintState::kUnknown, notified.error,
            notified.detail});
    }
  }

  // Which notifiers a pause reaches: told once, at the start.
  void TellNotifiers() {
    std::vector<MoonrakerNotifier> notifiers;
    const PrinterReply reply = moonraker->ListNotifiers(&notifiers);
    if (!reply.ok()) {
      // 404: no [notifier] component loaded; an absent Moonraker is told by the state's warning.
      if (reply.error == PrinterError::kUnauthorized || reply.error == PrinterError::kBadReply)
        Info(fmt::format("{}: {}", Who(), reply.detail));
      return;
    }
    std::vector<std::string> reached;
    for (const MoonrakerNotifier& n : notifiers)
      for (const std::string& e : n.events)
        if (e == "paused" || e == "*") {
          reached.push_back(n.name);
          break;
        }
    if (reached.empty())
      Info(
          fmt::format("{}: no [notifier] with 'events: paused': a pause is seen in the web "
                      "interface only (docs/watch.md: Moonraker's notifier)",
                      Who()));
    else
      Info(fmt::format("{}: a pause is told by the notifier(s) {}", Who(),
                       fmt::join(reached, ", ")));
  }

  void Run() {
    if (moonraker) TellNotifiers();
    auto next_poll = Clock::now() + Seconds(options.poll_interval_s);
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      wake.wait_until(lock, next_poll, [&] { return stopping || update_due || poll_now; });
      if (!update_due && stopping) break;
      if (!stopping && (poll_now || Clock::now() >= next_poll)) {
        poll_now = false;
        lock.unlock();
        Poll();
        lock.lock();
        next_poll = Clock::now() + Seconds(options.poll_interval_s);
        // The printer's state may have armed the link: the latest level is decided again.
        if (has_state) update_due = true;
      }
      if (update_due) {
        update_due = false;
        const double t = latest_time_s;
        const WatchLevel level = latest_level;
        const std::string reason = latest_reason;
        const double drift_pct = latest_drift_pct;
        if (policy.OnLevel(t, level)) {
          lock.unlock();
          PauseNow(t, level, reason, drift_pct);
          lock.lock();
        }
      }
    }
  }
};

PrinterLink::PrinterLink(const PrinterLinkOptions& options, Log log,
                         std::function<void(const PrinterEvent&)> on_event)
    : impl_(std::make_unique<Impl>(options, std::move(log), std::move(on_event))) {
  std::string why;
  std::string& key = impl_->key;
  if (!options.Resolve(&impl_->base, &key, &why)) throw std::invalid_argument(why);
  if (!options.enabled()) throw std::invalid_argument("no --moonraker or --octoprint");
  if (!options.moonraker_url.empty()) {
    auto m = std::make_unique<MoonrakerClient>(impl_->base, key, options.request_timeout_s);
    impl_->moonraker = m.get();
    impl_->api = std::move(m);
  } else {
    impl_->api = std::make_unique<OctoPrintClient>(impl_->base, key, options.request_timeout_s);
  }
  // Before the watch starts: armed from its first frame when the printer is printing.
  impl_->Poll();
  impl_->thread = std::thread([this] { impl_->Run(); });
}

PrinterLink::~PrinterLink() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  impl_->thread.join();
}

std::string PrinterLink::WebcamSource() {
  if (!impl_->moonraker)
    throw std::invalid_argument("--octoprint: give the camera's source (OctoPrint lists none)");
  // A client of this thread's own: the link's thread is using its own already (a libcurl handle
  // serves one thread at a time).
  MoonrakerClient client(impl_->base, impl_->key, impl_->options.request_timeout_s);
  std::vector<MoonrakerWebcam> webcams;
  const PrinterReply reply = client.ListWebcams(&webcams);
  const std::string shown = vision::RedactCredentials(impl_->base);
  if (!reply.ok())
    throw std::invalid_argument(fmt::format("--moonraker {}: no webcam to watch ({}): {}", shown,
                                            PrinterErrorName(reply.error), reply.detail));
  MoonrakerWebcam chosen;
  std::string why;
  if (!ChooseWebcam(webcams, impl_->options.webcam, &chosen, &why))
    throw std::invalid_argument(fmt::format("--moonraker {}: {}", shown, why));
  const std::string source = ResolveWebcamUrl(impl_->base, chosen.stream_url);
  impl_->Info(
      fmt::format("Moonraker's webcam '{}': {}", chosen.name, vision::RedactCredentials(source)));
  return source;
}

void PrinterLink::Update(const WatchStatus& status) {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->latest_time_s = status.time_s;
    impl_->latest_level = status.level;
    impl_->latest_reason = status.reason;
    impl_->latest_drift_pct = status.has_recent ? status.recent_drift_pct : NAN;
    impl_->has_state = true;
    impl_->update_due = true;
  }
  impl_->wake.notify_all();
}

const char* PrinterLink::api_name() const { return impl_->api->name(); }
const std::string& PrinterLink::base_url() const { return impl_->base; }

}  // namespace clogscope::watch
