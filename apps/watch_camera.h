#pragma once

// One camera's watch as `clogscope watch` runs it, for a single watch and for each camera of a
// farm (`watch --config`): its options resolved, its printer link, log and alert command, and the
// board its state is published to.

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "apps/watch_command.h"
#include "apps/watch_outputs.h"
#include "watch/frame_jpeg.h"
#include "watch/live_watch.h"
#include "watch/printer_link.h"

namespace clogscope::apps {

class CameraWatch {
 public:
  // Checks and resolves the per-camera options of `options` (its http and mqtt are not looked
  // at): the scale and band, the extruder, the printer link (with no source, its webcam is the
  // source: asked for here, or in a farm as Run starts), then opens its log. `printer` names the
  // camera in a farm (in its lines and log lines), or is empty. Throws std::invalid_argument (one
  // line naming the option or file).
  CameraWatch(const WatchCommandOptions& options, std::string printer,
              std::function<void(const watch::PrinterEvent&)> on_printer);
  ~CameraWatch();
  CameraWatch(const CameraWatch&) = delete;
  CameraWatch& operator=(const CameraWatch&) = delete;

  const std::string& printer() const { return printer_; }
  const watch::LiveWatchOptions& live() const { return live_; }
  // The camera for the outputs: its name, board, scale and the overlay pictures they share.
  watch::CameraFeed Feed() const { return {printer_, &board_, live_.conversion, frames_}; }
  // Whether a start that failed may succeed later: a stream or device (its printer switched off),
  // or a farm's camera whose source is its printer's webcam (asked for as it starts). A file or
  // folder that cannot be opened will not come back by waiting.
  bool StartMayBeRetried() const;
  // After Run: the board's last state with its source down (a farm goes on serving the others;
  // the last level and diameter stay, as measured). The state published.
  watch::WatchSnapshot PublishEnded();
  // Where /status is served, told in every line.
  void SetHttpUrl(const std::string& url) { live_.http_url = url; }

  // Watches until *stop (which it sets on return), the file's end or --duration-s, writing its
  // lines, running the alert command and telling the printer link. on_report follows every
  // status, level and stop line (MQTT); on_level_change every level change, once the board
  // serves it.
  WatchReport Run(
      std::atomic<bool>* stop,
      std::function<void(const watch::WatchStatus&, const std::optional<watch::ClogIndex>&)>
          on_report,
      std::function<void(const watch::WatchStatus&)> on_level_change);

 private:
  std::string printer_;
  std::string tag_;  // "NAME: " before its log lines in a farm, else empty
  watch::LiveWatchOptions live_;
  std::optional<watch::PrinterLink> link_;
  std::unique_ptr<LineLog> log_;
  std::optional<AlertCommand> alert_;
  watch::WatchBoard board_;
  std::shared_ptr<watch::OverlayJpegCache> frames_;  // of board_, drawn once for every output
  bool webcam_from_printer_ = false;  // a farm's camera with no source: its printer's webcam
};

}  // namespace clogscope::apps
