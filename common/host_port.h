#pragma once

#include <optional>
#include <string>

namespace clogscope {

// A network address's host and port, as written: HOST, HOST:PORT, [IPv6] or [IPv6]:PORT.
struct HostPort {
  std::string host;         // without the brackets
  std::optional<int> port;  // absent when none was written
};

// Splits `authority`. False with *why (a phrase naming what is wrong) when a '[' has no ']', what
// follows ']' is not ':PORT', an unbracketed host holds a ':' (IPv6 goes in brackets), the host
// is empty, a ':' has no port after it, or the port is not a number in [min_port, 65535].
bool SplitHostPort(const std::string& authority, int min_port, HostPort* out, std::string* why);

}  // namespace clogscope
