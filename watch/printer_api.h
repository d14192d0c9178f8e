#pragma once

// What the watch asks of a printer's API (Moonraker, OctoPrint): its job's state, and a pause.
// Every call blocks for at most the client's timeout; none throws for what the network or the
// printer does: the outcome is a PrinterReply with its reason.

#include <string>
#include <vector>

#include "watch/http_client.h"
#include "watch/pause_policy.h"

namespace clogscope::watch {

enum class PrinterError {
  kNone,
  kUnreachable,   // no connection (down, refused, name unknown)
  kTimeout,       // no answer within the timeout
  kUnauthorized,  // 401 or 403: the API key is missing, wrong or lacks the right
  kNotPrinting,   // the printer refused because there is no job to pause (409)
  kRefused,       // another HTTP status (Klipper not ready: 503, …)
  kBadReply,      // an answer that is not the documented JSON
};
const char* PrinterErrorName(PrinterError error);

struct PrinterReply {
  PrinterError error = PrinterError::kNone;
  std::string detail;  // one line for a warning (never the API key)
  bool ok() const { return error == PrinterError::kNone; }
};

// The HTTP outcome as a reply: transport errors and non-2xx statuses (`what` names the request,
// e.g. "GET /printer/objects/query").
PrinterReply ReplyOf(const HttpResponse& response, const std::string& what);

class PrinterApi {
 public:
  virtual ~PrinterApi() = default;
  virtual const char* name() const = 0;  // "Moonraker", "OctoPrint"
  virtual PrinterReply QueryState(PrintState* state) = 0;
  virtual PrinterReply Pause() = 0;
};

// --moonraker / --octoprint URL: http(s)://HOST[:PORT][/PATH], no credentials in it. Returns the
// URL without a trailing '/'; false with a line naming `option` in *why.
bool ParsePrinterUrl(const std::string& option, const std::string& url, std::string* base,
                     std::string* why);

// --printer-api-key-file PATH: the key on the file's one line, blanks around it dropped. False
// with a line naming the option and the file (never its content) when it cannot be read, is
// empty, holds more than one line or characters a header value cannot.
bool ReadApiKeyFile(const std::string& path, std::string* key, std::string* why);

// The request header that carries the key (Moonraker's and OctoPrint's X-Api-Key); none when the
// key is empty.
std::vector<std::string> ApiKeyHeader(const std::string& api_key);

}  // namespace clogscope::watch
