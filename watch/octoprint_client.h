#pragma once

// OctoPrint's REST API, the documented job operations only: GET /api/job (its "state") and
// POST /api/job {"command": "pause", "action": "pause"} (204; 409 when no job is printing). The
// API key goes in X-Api-Key.

#include <string>

#include "watch/http_client.h"
#include "watch/printer_api.h"

namespace clogscope::watch {

class OctoPrintClient : public PrinterApi {
 public:
  // base: "http://octopi.local" (ParsePrinterUrl's); api_key empty: none sent.
  OctoPrintClient(std::string base, const std::string& api_key, double timeout_s);

  const char* name() const override { return "OctoPrint"; }
  PrinterReply QueryState(PrintState* state) override;
  PrinterReply Pause() override;

 private:
  std::string base_;
  HttpClient http_;
};

// OctoPrint's state text ("Printing", "Printing from SD", "Pausing", "Paused", "Operational"…)
// as a PrintState.
PrintState OctoPrintState(const std::string& state);

}  // namespace clogscope::watch
