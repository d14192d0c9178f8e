#include "watch/http_client.h"

#include <curl/curl.h>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace clogscope::watch {
namespace {

// libcurl's process-wide set-up, once and never undone (a client may live on another thread).
void InitCurl() {
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

size_t Collect(char* data, size_t size, size_t n, void* user) {
  auto* body = static_cast<std::string*>(user);
  const size_t bytes = size * n;
  // A reply past the bound is cut off (the transfer fails with a write error): a printer's API
  // answers in kilobytes, and a stream URL given by mistake must not fill the memory.
  if (body->size() + bytes > kMaxHttpBodyBytes) return 0;
  body->append(data, bytes);
  return bytes;
}

}  // namespace

struct HttpClient::Impl {
  CURL* curl = nullptr;
  curl_slist* headers = nullptr;
  curl_slist* json_headers = nullptr;  // the same and Content-Type: application/json
  long timeout_ms = 0;
  char error[CURL_ERROR_SIZE] = {};

  HttpResponse Perform(const std::string& url, const std::string* post_json) {
    HttpResponse r;
    curl_easy_reset(curl);
    error[0] = '\0';
    curl_easy_setopt(curl, CURLOPT_URL, url.c_str());
    curl_easy_setopt(curl, CURLOPT_PROTOCOLS_STR, "http,https");
    // A redirect would carry the API key header to wherever it points: not followed.
    curl_easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 0L);
    curl_easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);  // no SIGALRM on a thread of the watch
    curl_easy_setopt(curl, CURLOPT_TIMEOUT_MS, timeout_ms);
    curl_easy_setopt(curl, CURLOPT_CONNECTTIMEOUT_MS, timeout_ms);
    curl_easy_setopt(curl, CURLOPT_ERRORBUFFER, error);
    curl_easy_setopt(curl, CURLOPT_WRITEFUNCTION, &Collect);
    curl_easy_setopt(curl, CURLOPT_WRITEDATA, &r.body);
    curl_easy_setopt(curl, CURLOPT_USERAGENT, "clogscope-watch");
    if (post_json) {
      curl_easy_setopt(curl, CURLOPT_HTTPHEADER, json_headers);
      curl_easy_setopt(curl, CURLOPT_POST, 1L);
      curl_easy_setopt(curl, CURLOPT_POSTFIELDS, post_json->c_str());
      curl_easy_setopt(curl, CURLOPT_POSTFIELDSIZE, static_cast<long>(post_json->size()));
    } else {
      curl_easy_setopt(curl, CURLOPT_HTTPHEADER, headers);
      curl_easy_setopt(curl, CURLOPT_HTTPGET, 1L);
    }
    const CURLcode rc = curl_easy_perform(curl);
    if (rc == CURLE_OK) {
      curl_easy_getinfo(curl, CURLINFO_RESPONSE_CODE, &r.status);
      return r;
    }
    switch (rc) {
      case CURLE_COULDNT_RESOLVE_HOST:
      case CURLE_COULDNT_CONNECT:
      case CURLE_RECV_ERROR:
      case CURLE_SEND_ERROR:
      case CURLE_GOT_NOTHING:
        r.error = HttpError::kUnreachable;
        break;
      case CURLE_OPERATION_TIMEDOUT:
        r.error = HttpError::kTimeout;
        break;
      default:
        r.error = HttpError::kOther;
    }
    r.error_text = error[0] ? error : curl_easy_strerror(rc);
    r.body.clear();
    return r;
  }
};

HttpClient::HttpClient(double timeout_s, std::vector<std::string> headers)
    : impl_(std::make_unique<Impl>()) {
  InitCurl();
  impl_->curl = curl_easy_init();
  impl_->timeout_ms = std::max(1L, std::lround(timeout_s * 1000));
  for (const std::string& h : headers) {
    impl_->headers = curl_slist_append(impl_->headers, h.c_str());
    impl_->json_headers = curl_slist_append(impl_->json_headers, h.c_str());
  }
  impl_->json_headers = curl_slist_append(impl_->json_headers, "Content-Type: application/json");
  // No "Expect: 100-continue" wait on a POST: the bodies are small.
  impl_->json_headers = curl_slist_append(impl_->json_headers, "Expect:");
}

HttpClient::~HttpClient() {
  if (impl_->curl) curl_easy_cleanup(impl_->curl);
  curl_slist_free_all(impl_->headers);
  curl_slist_free_all(impl_->json_headers);
}

HttpResponse HttpClient::Get(const std::string& url) {
  if (!impl_->curl) return {HttpError::kOther, 0, "", "libcurl could not start"};
  return impl_->Perform(url, nullptr);
}

HttpResponse HttpClient::PostJson(const std::string& url, const std::string& json) {
  if (!impl_->curl) return {HttpError::kOther, 0, "", "libcurl could not start"};
  return impl_->Perform(url, &json);
}

std::string UrlOrigin(const std::string& url) {
  for (const std::string scheme : {"http://", "https://"}) {
    if (url.rfind(scheme, 0) != 0) continue;
    const size_t end = url.find_first_of("/?#", scheme.size());
    return end == std::string::npos ? url : url.substr(0, end);
  }
  return "";
}

}  // namespace clogscope::watch
