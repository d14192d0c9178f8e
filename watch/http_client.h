#pragma once

// A small blocking HTTP client (libcurl) for the printer's API: one request at a time, every one
// bounded by a timeout, no redirects followed, http and https only. For a thread of its own, never
// the measuring thread.

#include <memory>
#include <string>
#include <vector>

namespace clogscope::watch {

// Why a request got no usable answer.
enum class HttpError {
  kNone,         // an answer (any status)
  kUnreachable,  // name unknown, connection refused or reset
  kTimeout,      // nothing, or not all, within the timeout
  kOther,        // TLS, a malformed URL, out of memory…
};

struct HttpResponse {
  HttpError error = HttpError::kNone;
  long status = 0;         // HTTP status when error is kNone
  std::string body;        // at most kMaxHttpBodyBytes
  std::string error_text;  // libcurl's words when error is not kNone (never a header's value)
  bool ok() const { return error == HttpError::kNone && status >= 200 && status < 300; }
};
inline constexpr size_t kMaxHttpBodyBytes = 1 << 20;

class HttpClient {
 public:
  // timeout_s bounds each request whole (connecting included). `headers` ("Name: value") go with
  // every request: the API key lives here and is never logged.
  HttpClient(double timeout_s, std::vector<std::string> headers);
  ~HttpClient();
  HttpClient(const HttpClient&) = delete;
  HttpClient& operator=(const HttpClient&) = delete;

  HttpResponse Get(const std::string& url);
  // A POST with `json` as its body (Content-Type: application/json); an empty one for none.
  HttpResponse PostJson(const std::string& url, const std::string& json);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// "http://host:7125/x" → "http://host:7125" (scheme and authority); empty when not http(s).
std::string UrlOrigin(const std::string& url);

}  // namespace clogscope::watch
