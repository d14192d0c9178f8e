#include "watch/printer_api.h"

#include <fmt/format.h>

#include "common/atomic_file.h"
#include "vision/io/source_name.h"

namespace clogscope::watch {

const char* PrinterErrorName(PrinterError error) {
  switch (error) {
    case PrinterError::kNone:
      return "ok";
    case PrinterError::kUnreachable:
      return "unreachable";
    case PrinterError::kTimeout:
      return "timeout";
    case PrinterError::kUnauthorized:
      return "unauthorized";
    case PrinterError::kNotPrinting:
      return "not_printing";
    case PrinterError::kRefused:
      return "refused";
    case PrinterError::kBadReply:
      return "bad_reply";
  }
  return "unknown";
}

PrinterReply ReplyOf(const HttpResponse& r, const std::string& what) {
  switch (r.error) {
    case HttpError::kNone:
      break;
    case HttpError::kUnreachable:
      return {PrinterError::kUnreachable, what + ": " + r.error_text};
    case HttpError::kTimeout:
      return {PrinterError::kTimeout, what + ": " + r.error_text};
    case HttpError::kOther:
      return {PrinterError::kUnreachable, what + ": " + r.error_text};
  }
  if (r.ok()) return {};
  const std::string status = fmt::format("{}: HTTP {}", what, r.status);
  if (r.status == 401 || r.status == 403)
    return {PrinterError::kUnauthorized,
            status + " (the API key is missing or wrong: --printer-api-key-file)"};
  if (r.status == 409) return {PrinterError::kNotPrinting, status + " (no job to pause)"};
  return {PrinterError::kRefused, status};
}

bool ParsePrinterUrl(const std::string& option, const std::string& url, std::string* base,
                     std::string* why) {
  const std::string shown = vision::RedactCredentials(url);
  const std::string origin = UrlOrigin(url);
  if (origin.empty()) {
    *why = fmt::format("{} '{}': expected http://HOST[:PORT] or https://…", option, shown);
    return false;
  }
  if (origin.find('@') != std::string::npos) {
    *why = fmt::format(
        "{} '{}': no user or password in the URL (`ps` and logs show it): the API key goes in "
        "--printer-api-key-file",
        option, shown);
    return false;
  }
  if (origin.find("://", 0) + 3 == origin.size()) {
    *why = fmt::format("{} '{}': no host", option, shown);
    return false;
  }
  if (url.find_first_of("?#") != std::string::npos) {
    *why = fmt::format("{} '{}': no query or fragment: the API's address only", option, shown);
    return false;
  }
  std::string b = url;
  while (b.size() > origin.size() && b.back() == '/') b.pop_back();
  *base = b;
  return true;
}

std::vector<std::string> ApiKeyHeader(const std::string& api_key) {
  if (api_key.empty()) return {};
  return {"X-Api-Key: " + api_key};
}

bool ReadApiKeyFile(const std::string& path, std::string* key, std::string* why) {
  const auto fail = [&](const std::string& problem) {
    *why = fmt::format("--printer-api-key-file {}: {}", path, problem);
    return false;
  };
  std::string text, problem;
  if (!TryReadFile(path, &text, &problem)) return fail("cannot be read (" + problem + ")");
  if (text.size() > 4096) return fail("longer than 4096 bytes: not a key");
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return fail("empty");
  const size_t last = text.find_last_not_of(" \t\r\n");
  const std::string k = text.substr(first, last - first + 1);
  if (k.find_first_of("\r\n") != std::string::npos)
    return fail("more than one line (expected the key alone)");
  for (const char c : k)
    if (static_cast<unsigned char>(c) < 0x21 || c == 0x7f)
      return fail("a blank or control character inside the key");
  *key = k;
  return true;
}

}  // namespace clogscope::watch
