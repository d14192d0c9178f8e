#include "vision/io/source_name.h"

#include <algorithm>
#include <array>

#include "common/ascii.h"

namespace clogscope::vision {
namespace {

constexpr const char* kHidden = "***";

bool NamesASecret(const std::string& raw) {
  const std::string name = LowerAscii(raw);
  static constexpr std::array<const char*, 8> kWords = {"pass", "pwd",  "token", "secret",
                                                        "key",  "auth", "sig",   "cred"};
  return std::any_of(kWords.begin(), kWords.end(),
                     [&](const char* w) { return name.find(w) != std::string::npos; });
}

// "a=1&pwd=2" → "a=1&pwd=***".
std::string RedactQuery(const std::string& query) {
  std::string out;
  size_t start = 0;
  while (start <= query.size()) {
    const size_t end = std::min(query.find('&', start), query.size());
    const std::string pair = query.substr(start, end - start);
    const size_t eq = pair.find('=');
    if (eq != std::string::npos && NamesASecret(pair.substr(0, eq)))
      out += pair.substr(0, eq + 1) + kHidden;
    else
      out += pair;
    if (end == query.size()) break;
    out += '&';
    start = end + 1;
  }
  return out;
}

}  // namespace

std::string RedactCredentials(const std::string& source) {
  const size_t scheme_end = source.find("://");
  if (scheme_end == std::string::npos) return source;
  const size_t host_start = scheme_end + 3;
  const size_t authority_end = std::min(source.find_first_of("/?#", host_start), source.size());
  std::string out = source.substr(0, host_start);
  // The userinfo ends at the authority's last '@' (a password may hold an unescaped '@').
  const size_t at = source.rfind('@', authority_end - 1);
  if (at != std::string::npos && at >= host_start) {
    const size_t colon = source.find(':', host_start);
    out += colon < at ? source.substr(host_start, colon + 1 - host_start) + kHidden : kHidden;
    out += source.substr(at, authority_end - at);
  } else {
    out += source.substr(host_start, authority_end - host_start);
  }
  const size_t query = source.find('?', authority_end);
  const size_t fragment = std::min(source.find('#', authority_end), source.size());
  if (query == std::string::npos || query > fragment) return out + source.substr(authority_end);
  return out + source.substr(authority_end, query + 1 - authority_end) +
         RedactQuery(source.substr(query + 1, fragment - query - 1)) + source.substr(fragment);
}

}  // namespace clogscope::vision
