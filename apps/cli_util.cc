#include "apps/cli_util.h"

#include <fmt/format.h>
#include <spdlog/sinks/ansicolor_sink.h>
#include <spdlog/spdlog.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

#include "common/library_text.h"
#include "common/path_check.h"

namespace clogscope::apps {

bool ParseSize(const std::string& text, int* width, int* height) {
  int w = 0, h = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') ||
      w <= 0 || h <= 0) {
    return false;
  }
  *width = w;
  *height = h;
  return true;
}

bool CheckTableAndExtruderPaths(const std::string& diameters, const std::string& extruder,
                                std::string* why) {
  return (diameters.empty() || CheckInputPath("--diameters", diameters, PathExpect::kFile, why)) &&
         CheckInputPath("--extruder", extruder, PathExpect::kPresetOrFile, why);
}

void SetUpLogging(const std::string& level) {
  // To the tool's message stream (common/library_text.h).
  using Sink = spdlog::sinks::ansicolor_sink<spdlog::details::console_mutex>;
  auto logger = std::make_shared<spdlog::logger>(
      "clogscope", std::make_shared<Sink>(ToolStderr(), spdlog::color_mode::automatic));
  logger->set_pattern("%^[%l]%$ %v");
  logger->set_level(spdlog::level::from_str(level));
  spdlog::set_default_logger(logger);
}

bool ParseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --help-all: printed, nothing more to do
    app.exit(e);
    return false;
  } catch (const CLI::ParseError& e) {
    throw std::invalid_argument(std::string(e.what()) + " (see --help)");
  }
  CheckNumbers(app);
  return true;
}

void CheckNumbers(const CLI::App& app) {
  for (const CLI::Option* opt : app.get_options()) {
    for (const std::string& text : opt->results()) {
      const char* begin = text.c_str();
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(begin, &end);
      if (end == begin || *end != '\0') continue;  // not a number: the option's parser judges it
      if (!std::isfinite(v) || errno == ERANGE) {
        throw std::invalid_argument(
            fmt::format("{} {}: not a finite number of usable size", opt->get_name(), text));
      }
    }
  }
}

}  // namespace clogscope::apps
