#include "watch/octoprint_client.h"

#include <nlohmann/json.hpp>

namespace clogscope::watch {

PrintState OctoPrintState(const std::string& state) {
  // "Resuming" is on its way back to printing: a clog then is worth a pause.
  if (state.rfind("Printing", 0) == 0 || state == "Resuming") return PrintState::kPrinting;
  if (state == "Pausing" || state == "Paused") return PrintState::kPaused;
  return PrintState::kIdle;
}

OctoPrintClient::OctoPrintClient(std::string base, const std::string& api_key, double timeout_s)
    : base_(std::move(base)), http_(timeout_s, ApiKeyHeader(api_key)) {}

PrinterReply OctoPrintClient::QueryState(PrintState* state) {
  const std::string what = "GET /api/job";
  const HttpResponse r = http_.Get(base_ + "/api/job");
  PrinterReply reply = ReplyOf(r, what);
  if (!reply.ok()) return reply;
  const nlohmann::json j = nlohmann::json::parse(r.body, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || !j.contains("state") || !j["state"].is_string())
    return {PrinterError::kBadReply, what + ": no \"state\""};
  *state = OctoPrintState(j["state"].get<std::string>());
  return {};
}

PrinterReply OctoPrintClient::Pause() {
  // "action": "pause" pauses only: without it the command toggles, and would resume a print
  // someone paused meanwhile.
  return ReplyOf(http_.PostJson(base_ + "/api/job", R"({"command": "pause", "action": "pause"})"),
                 "POST /api/job pause");
}

}  // namespace clogscope::watch
