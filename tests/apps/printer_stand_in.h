#pragma once

// A small stand-in for a printer's HTTP API in the tests (Moonraker is not packaged for Debian,
// nor is OctoPrint): libmicrohttpd on a free loopback port, the documented endpoints the watch
// uses, every call recorded with its X-Api-Key header, and the job's state set by the test.
//
// Moonraker: GET /server/webcams/list, GET /printer/objects/query?print_stats,
// POST /printer/print/pause (printing → paused), POST /printer/print/resume,
// GET /server/notifiers/list, POST /printer/gcode/script; answers {"result": …}.
// OctoPrint: GET /api/job ({"state": …}), POST /api/job {"command": "pause", "action": "pause"}
// (204; 409 when not printing).
#include <microhttpd.h>
#include <netinet/in.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clogscope::apps::testing {

struct StandInCall {
  std::string method, path, query;  // query: the raw query string ("print_stats"), or empty
  std::string api_key;              // the X-Api-Key header, or empty
  std::string body;
  std::chrono::steady_clock::time_point at;
};

class PrinterStandIn {
 public:
  enum class Flavor { kMoonraker, kOctoPrint };

  // Starts at once on 127.0.0.1 (a free port). `api_key` not empty: any other key is answered 401.
  PrinterStandIn(Flavor flavor, std::string api_key, std::string state)
      : flavor_(flavor), api_key_(std::move(api_key)), state_(std::move(state)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    daemon_ = MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD, 0, nullptr, nullptr, &Answer, this,
                               MHD_OPTION_SOCK_ADDR, reinterpret_cast<sockaddr*>(&a),
                               MHD_OPTION_NOTIFY_COMPLETED, &Completed, this, MHD_OPTION_END);
    if (daemon_) port_ = MHD_get_daemon_info(daemon_, MHD_DAEMON_INFO_BIND_PORT)->port;
  }
  ~PrinterStandIn() {
    if (daemon_) MHD_stop_daemon(daemon_);
  }
  PrinterStandIn(const PrinterStandIn&) = delete;
  PrinterStandIn& operator=(const PrinterStandIn&) = delete;

  int port() const { return port_; }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }

  void SetState(const std::string& state) {
    std::lock_guard<std::mutex> lock(mutex_);
    state_ = state;
  }
  std::string state() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return state_;
  }
  void SetWebcams(nlohmann::json webcams) {
    std::lock_guard<std::mutex> lock(mutex_);
    webcams_ = std::move(webcams);
  }
  void SetNotifiers(nlohmann::json notifiers) {
    std::lock_guard<std::mutex> lock(mutex_);
    notifiers_ = std::move(notifiers);
  }

  std::vector<StandInCall> Calls() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return calls_;
  }
  // The calls to METHOD PATH so far.
  std::vector<StandInCall> CallsTo(const std::string& method, const std::string& path) const {
    std::vector<StandInCall> out;
    for (const StandInCall& c : Calls())
      if (c.method == method && c.path == path) out.push_back(c);
    return out;
  }
  // Until pred(calls) holds, for at most timeout_s (a safety net: each call wakes it).
  bool WaitFor(const std::function<bool(const std::vector<StandInCall>&)>& pred,
               double timeout_s) const {
    std::unique_lock<std::mutex> lock(mutex_);
    return called_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                            [&] { return pred(calls_); });
  }

 private:
  struct Request {
    std::string body;
  };

  static void Completed(void*, MHD_Connection*, void** con_cls, MHD_RequestTerminationCode) {
    delete static_cast<Request*>(*con_cls);
    *con_cls = nullptr;
  }

  static MHD_Result Reply(MHD_Connection* c, unsigned status, const std::string& body) {
    MHD_Response* r = MHD_create_response_from_buffer(body.size(), const_cast<char*>(body.data()),
                                                      MHD_RESPMEM_MUST_COPY);
    if (!body.empty()) MHD_add_response_header(r, "Content-Type", "application/json");
    const MHD_Result ret = MHD_queue_response(c, status, r);
    MHD_destroy_response(r);
    return ret;
  }

  static MHD_Result CollectQuery(void* cls, MHD_ValueKind, const char* key, const char* value) {
    auto* q = static_cast<std::string*>(cls);
    if (!q->empty()) *q += "&";
    *q += key;
    if (value) *q += std::string("=") + value;
    return MHD_YES;
  }

  static MHD_Result Answer(void* cls, MHD_Connection* c, const char* url, const char* method,
                           const char*, const char* upload, size_t* upload_size, void** con_cls) {
    auto* self = static_cast<PrinterStandIn*>(cls);
    if (!*con_cls) {  // the headers: the body (if any) comes in the next calls
      *con_cls = new Request;
      return MHD_YES;
    }
    auto* request = static_cast<Request*>(*con_cls);
    if (*upload_size) {
      request->body.append(upload, *upload_size);
      *upload_size = 0;
      return MHD_YES;
    }
    StandInCall call;
    call.method = method;
    call.path = url;
    MHD_get_connection_values(c, MHD_GET_ARGUMENT_KIND, &CollectQuery, &call.query);
    const char* key = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Api-Key");
    call.api_key = key ? key : "";
    call.body = request->body;
    call.at = std::chrono::steady_clock::now();
    unsigned status = MHD_HTTP_OK;
    std::string body;
    {
      std::lock_guard<std::mutex> lock(self->mutex_);
      if (!self->api_key_.empty() && call.api_key != self->api_key_) {
        status = MHD_HTTP_UNAUTHORIZED;
        body = R"({"error": {"code": 401, "message": "Unauthorized"}})";
      } else if (self->flavor_ == Flavor::kMoonraker) {
        self->Moonraker(call, &status, &body);
      } else {
        self->OctoPrint(call, &status, &body);
      }
      self->calls_.push_back(call);
    }
    self->called_.notify_all();
    return Reply(c, status, body);
  }

  // Under mutex_.
  void Moonraker(const StandInCall& call, unsigned* status, std::string* body) {
    using nlohmann::json;
    const auto result = [&](json r) { *body = json{{"result", std::move(r)}}.dump(); };
    const std::string m = call.method, p = call.path;
    if (m == "GET" && p == "/server/webcams/list") {
      result({{"webcams", webcams_}});
    } else if (m == "GET" && p == "/printer/objects/query" &&
               call.query.find("print_stats") != std::string::npos) {
      result({{"eventtime", 1234.5},
              {"status", {{"print_stats", {{"state", state_}, {"filename", "part.gcode"}}}}}});
    } else if (m == "POST" && p == "/printer/print/pause") {
      if (state_ == "printing") state_ = "paused";
      result("ok");
    } else if (m == "POST" && p == "/printer/print/resume") {
      if (state_ == "paused") state_ = "printing";
      result("ok");
    } else if (m == "GET" && p == "/server/notifiers/list") {
      result({{"notifiers", notifiers_}});
    } else if (m == "POST" && p == "/printer/gcode/script") {
      result("ok");
    } else {
      *status = MHD_HTTP_NOT_FOUND;
      *body = R"({"error": {"code": 404, "message": "Not Found"}})";
    }
  }

  void OctoPrint(const StandInCall& call, unsigned* status, std::string* body) {
    using nlohmann::json;
    if (call.path != "/api/job") {
      *status = MHD_HTTP_NOT_FOUND;
      return;
    }
    if (call.method == "GET") {
      *body = json{{"job", {{"file", {{"name", "part.gcode"}}}}},
                   {"progress", {{"completion", 12.5}}},
                   {"state", state_}}
                  .dump();
      return;
    }
    const json j = json::parse(call.body, nullptr, false);
    if (call.method != "POST" || j.is_discarded() || j.value("command", "") != "pause") {
      *status = MHD_HTTP_BAD_REQUEST;
      return;
    }
    if (state_.rfind("Printing", 0) != 0 && state_ != "Paused") {
      *status = MHD_HTTP_CONFLICT;
      return;
    }
    if (j.value("action", "toggle") == "pause") state_ = "Paused";
    *status = MHD_HTTP_NO_CONTENT;
  }

  Flavor flavor_;
  std::string api_key_;
  MHD_Daemon* daemon_ = nullptr;
  int port_ = 0;
  mutable std::mutex mutex_;
  mutable std::condition_variable called_;
  // Under mutex_.
  std::string state_;
  nlohmann::json webcams_ = nlohmann::json::array();
  nlohmann::json notifiers_ = nlohmann::json::array();
  std::vector<StandInCall> calls_;
};

}  // namespace clogscope::apps::testing
