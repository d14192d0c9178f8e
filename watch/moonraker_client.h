#pragma once

// Moonraker's HTTP API, the documented endpoints only: GET /server/webcams/list,
// GET /printer/objects/query?print_stats, POST /printer/print/pause, GET /server/notifiers/list and
// POST /printer/gcode/script. Answers are {"result": …}; the API key goes in X-Api-Key.

#include <string>
#include <vector>

#include "watch/http_client.h"
#include "watch/printer_api.h"

namespace clogscope::watch {

struct MoonrakerWebcam {
  std::string name;
  bool enabled = true;
  std::string stream_url;    // as listed: a whole URL or a path on Moonraker's host
  std::string snapshot_url;  // the same, or empty
};

struct MoonrakerNotifier {
  std::string name;
  std::vector<std::string> events;  // "paused", "*", "gcode"…
};

class MoonrakerClient : public PrinterApi {
 public:
  // base: "http://printer.local:7125" (ParsePrinterUrl's); api_key empty: none sent.
  MoonrakerClient(std::string base, const std::string& api_key, double timeout_s);

  const char* name() const override { return "Moonraker"; }
  PrinterReply QueryState(PrintState* state) override;
  PrinterReply Pause() override;
  PrinterReply ListWebcams(std::vector<MoonrakerWebcam>* webcams);
  PrinterReply ListNotifiers(std::vector<MoonrakerNotifier>* notifiers);
  PrinterReply RunGcode(const std::string& script);

  const std::string& base() const { return base_; }

 private:
  std::string base_;
  HttpClient http_;
};

// Klipper's print_stats.state as a PrintState ("printing", "paused"; the rest idle).
PrintState MoonrakerPrintState(const std::string& state);

// A webcam's stream_url as something the watch opens: a whole URL as it is; a path ("/webcam/…")
// on the host and port of `base` (Moonraker's, or the web front end's that proxies it); file:///p
// as the local path /p (a recording on the printer's host).
std::string ResolveWebcamUrl(const std::string& base, const std::string& stream_url);

// The webcam to watch: the one named `name` (empty: the first enabled one with a stream URL).
// False with why when there is none.
bool ChooseWebcam(const std::vector<MoonrakerWebcam>& webcams, const std::string& name,
                  MoonrakerWebcam* chosen, std::string* why);

}  // namespace clogscope::watch
