#include "watch/moonraker_client.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

namespace clogscope::watch {
namespace {

using nlohmann::json;

// The "result" of a 2xx answer, or the reply that says why there is none.
PrinterReply Result(const HttpResponse& r, const std::string& what, json* result) {
  PrinterReply reply = ReplyOf(r, what);
  if (!reply.ok()) return reply;
  json j = json::parse(r.body, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || !j.contains("result"))
    return {PrinterError::kBadReply, what + ": not Moonraker's {\"result\": …}"};
  *result = std::move(j["result"]);
  return {};
}

std::string StringField(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : "";
}

}  // namespace

PrintState MoonrakerPrintState(const std::string& state) {
  if (state == "printing") return PrintState::kPrinting;
  if (state == "paused") return PrintState::kPaused;
  return PrintState::kIdle;
}

MoonrakerClient::MoonrakerClient(std::string base, const std::string& api_key, double timeout_s)
    : base_(std::move(base)), http_(timeout_s, ApiKeyHeader(api_key)) {}

PrinterReply MoonrakerClient::QueryState(PrintState* state) {
  const std::string what = "GET /printer/objects/query?print_stats";
  json result;
  PrinterReply reply =
      Result(http_.Get(base_ + "/printer/objects/query?print_stats"), what, &result);
  if (!reply.ok()) return reply;
  const json* s = nullptr;
  if (result.is_object() && result.contains("status") && result["status"].is_object() &&
      result["status"].contains("print_stats"))
    s = &result["status"]["print_stats"];
  if (!s || !s->is_object() || !s->contains("state") || !(*s)["state"].is_string())
    return {PrinterError::kBadReply, what + ": no status.print_stats.state"};
  *state = MoonrakerPrintState((*s)["state"].get<std::string>());
  return {};
}

PrinterReply MoonrakerClient::Pause() {
  json result;
  return Result(http_.PostJson(base_ + "/printer/print/pause", ""), "POST /printer/print/pause",
                &result);
}

PrinterReply MoonrakerClient::ListWebcams(std::vector<MoonrakerWebcam>* webcams) {
  const std::string what = "GET /server/webcams/list";
  json result;
  PrinterReply reply = Result(http_.Get(base_ + "/server/webcams/list"), what, &result);
  if (!reply.ok()) return reply;
  if (!result.is_object() || !result.contains("webcams") || !result["webcams"].is_array())
    return {PrinterError::kBadReply, what + ": no webcams array"};
  webcams->clear();
  for (const json& w : result["webcams"]) {
    if (!w.is_object()) continue;
    MoonrakerWebcam c;
    c.name = StringField(w, "name");
    c.stream_url = StringField(w, "stream_url");
    c.snapshot_url = StringField(w, "snapshot_url");
    if (w.contains("enabled") && w["enabled"].is_boolean()) c.enabled = w["enabled"].get<bool>();
    webcams->push_back(std::move(c));
  }
  return {};
}

PrinterReply MoonrakerClient::ListNotifiers(std::vector<MoonrakerNotifier>* notifiers) {
  const std::string what = "GET /server/notifiers/list";
  json result;
  PrinterReply reply = Result(http_.Get(base_ + "/server/notifiers/list"), what, &result);
  if (!reply.ok()) return reply;
  if (!result.is_object() || !result.contains("notifiers") || !result["notifiers"].is_array())
    return {PrinterError::kBadReply, what + ": no notifiers array"};
  notifiers->clear();
  for (const json& n : result["notifiers"]) {
    if (!n.is_object()) continue;
    MoonrakerNotifier out;
    out.name = StringField(n, "name");
    if (n.contains("events") && n["events"].is_array())
      for (const json& e : n["events"])
        if (e.is_string()) out.events.push_back(e.get<std::string>());
    notifiers->push_back(std::move(out));
  }
  return {};
}

PrinterReply MoonrakerClient::RunGcode(const std::string& script) {
  json result;
  const json body = {{"script", script}};
  return Result(http_.PostJson(base_ + "/printer/gcode/script", body.dump()),
                "POST /printer/gcode/script", &result);
}

std::string ResolveWebcamUrl(const std::string& base, const std::string& stream_url) {
  if (stream_url.rfind("file://", 0) == 0) return stream_url.substr(7);
  if (stream_url.find("://") != std::string::npos) return stream_url;
  const std::string origin = UrlOrigin(base);
  return origin + (stream_url.rfind('/', 0) == 0 ? "" : "/") + stream_url;
}

bool ChooseWebcam(const std::vector<MoonrakerWebcam>& webcams, const std::string& name,
                  MoonrakerWebcam* chosen, std::string* why) {
  std::vector<std::string> names;
  for (const MoonrakerWebcam& w : webcams) {
    names.push_back(w.name);
    if (!name.empty() ? w.name == name : (w.enabled && !w.stream_url.empty())) {
      if (w.stream_url.empty()) {
        *why = fmt::format("the webcam '{}' has no stream_url", w.name);
        return false;
      }
      *chosen = w;
      return true;
    }
  }
  if (webcams.empty())
    *why = "Moonraker lists no webcam (/server/webcams/list): give the camera's source";
  else if (!name.empty())
    *why = fmt::format("--webcam '{}': Moonraker lists {}", name, fmt::join(names, ", "));
  else
    *why = fmt::format("none of Moonraker's webcams ({}) is enabled with a stream_url",
                       fmt::join(names, ", "));
  return false;
}

}  // namespace clogscope::watch
