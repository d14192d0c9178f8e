#include "common/host_port.h"

#include <fmt/format.h>

namespace clogscope {

bool SplitHostPort(const std::string& authority, int min_port, HostPort* out, std::string* why) {
  const auto fail = [why](std::string text) {
    *why = std::move(text);
    return false;
  };
  *out = HostPort{};
  std::string port;
  bool has_port = false;
  if (!authority.empty() && authority[0] == '[') {
    const size_t close = authority.find(']');
    if (close == std::string::npos) return fail("an IPv6 address needs its closing ']'");
    out->host = authority.substr(1, close - 1);
    const std::string after = authority.substr(close + 1);
    if (!after.empty() && after[0] != ':') return fail("expected ':PORT' after ']'");
    has_port = !after.empty();
    if (has_port) port = after.substr(1);
  } else {
    const size_t colon = authority.find(':');
    out->host = authority.substr(0, colon);
    has_port = colon != std::string::npos;
    if (has_port) port = authority.substr(colon + 1);
    if (port.find(':') != std::string::npos)
      return fail("expected HOST:PORT (an IPv6 address goes in brackets)");
  }
  if (out->host.empty()) return fail("no host");
  if (!has_port) return true;
  if (port.empty()) return fail("an empty port");
  if (port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoi(port) < min_port || std::stoi(port) > 65535)
    return fail(fmt::format("the port must be a number in [{}, 65535]", min_port));
  out->port = std::stoi(port);
  return true;
}

}  // namespace clogscope
