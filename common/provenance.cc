#include "common/provenance.h"

#include <ctime>
#include <mutex>

#include "common/version.h"

namespace clogscope {
namespace {
std::mutex g_mutex;
std::string g_command_line;  // NOLINT: set once from main
}  // namespace

std::string JoinCommandLine(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) {
    if (!out.empty()) out += ' ';
    bool plain = !w.empty() && w.find_first_of(" \t\"'\\$`;&|<>*?()[]{}") == std::string::npos;
    if (plain) {
      out += w;
    } else {
      out += '\'';
      for (char c : w) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
      out += '\'';
    }
  }
  return out;
}

void SetCommandLine(int argc, const char* const* argv) {
  std::vector<std::string> words(argv, argv + argc);
  std::lock_guard<std::mutex> lock(g_mutex);
  g_command_line = JoinCommandLine(words);
}

Provenance CurrentProvenance() {
  Provenance p;
  p.version = kVersion;
  std::time_t now = std::time(nullptr);
  std::tm tm_utc{};
  gmtime_r(&now, &tm_utc);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm_utc);
  p.created_utc = buf;
  std::lock_guard<std::mutex> lock(g_mutex);
  p.command_line = g_command_line;
  return p;
}

std::string ProvenanceCsvComment(const Provenance& p) {
  return "# clogscope " + p.version + "\n# created " + p.created_utc + "\n# command " +
         p.command_line + "\n";
}

}  // namespace clogscope
