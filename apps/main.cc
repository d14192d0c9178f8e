// clogscope: one binary, subcommands dispatched to RunX(argc, argv).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <stdexcept>
#include <string>

#include "apps/calibrate_command.h"
#include "apps/cli_util.h"
#include "apps/drive_command.h"
#include "apps/inspect_command.h"
#include "apps/lag_command.h"
#include "apps/measure_command.h"
#include "apps/predict_command.h"
#include "apps/render_command.h"
#include "apps/run_command.h"
#include "apps/thermal_command.h"
#include "apps/watch_command.h"
#include "calib/solver_log.h"
#include "common/library_text.h"
#include "common/provenance.h"
#include "common/version.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

const Command kCommands[] = {
    {"render", clogscope::apps::RunRender, "synthetic frames with exact ground truth"},
    {"calibrate", clogscope::apps::RunCalibrate,
     "pixel scale from pin gauges or a stage micrometer"},
    {"measure", clogscope::apps::RunMeasure, "strand width per frame from images or videos"},
    {"run", clogscope::apps::RunRun,
     "the whole pipeline from one manifest: calibrate, measure, predict"},
    {"predict", clogscope::apps::RunPredict,
     "diameter table -> predicted vibration and motor current; fits"},
    {"inspect", clogscope::apps::RunInspect,
     "camera set-up: what the tool sees in one frame, and the options to use"},
    {"thermal", clogscope::apps::RunThermal,
     "hot-end cooling: heat-sink temperature, clog risk, critical softened length"},
    {"drive", clogscope::apps::RunDrive, "roller-drive slip against feed and pinch force"},
    {"lag", clogscope::apps::RunLag,
     "extrusion lag K from video widths and a commanded flow; linear advance"},
    {"watch", clogscope::apps::RunWatch,
     "live camera or stream: diameter drift, clog index, alerts (JSON lines, HTTP)"},
};

void PrintUsage() {
  std::printf(
      "clogscope %s — effective nozzle diameter from microscope video\n\n"
      "Usage: clogscope COMMAND [OPTIONS]   (clogscope COMMAND --help for its options)\n\n"
      "Commands:\n",
      clogscope::kVersion);
  for (const auto& c : kCommands) std::printf("  %-10s %s\n", c.name, c.summary);
  std::printf(
      "\nExamples:\n"
      "  clogscope render --out frames/ --frames 10 --tilt-deg 5\n"
      "  clogscope calibrate --pins pins/pins.csv --out calib.yaml\n"
      "  clogscope measure frames/ --scale-um-per-px 3 --out-frames frames.csv --overlay ov/\n"
      "  clogscope run experiment.yaml --out results/\n"
      "  clogscope predict --extruder direct-pla --diameters diameters.csv --out pred/\n"
      "  clogscope thermal --material pla --fan-velocity-m-s 0.3\n"
      "  clogscope drive --roller 3 --pinch-force-n 80 --feed-force-n 20\n"
      "  clogscope watch http://printer.local/webcam/?action=stream --calib calib.yaml --http "
      "8090\n"
      "  clogscope lag --frames frames.csv --commanded profile.csv --out lag/\n"
      "\nEnvironment: CLOGSCOPE_LOG=debug|info|warn|error sets the log level (default info).\n");
}

}  // namespace

int main(int argc, char** argv) {
  clogscope::SetCommandLine(argc, argv);
  const char* level = std::getenv("CLOGSCOPE_LOG");
  clogscope::apps::SetUpLogging(level ? level : "info");
  // Libraries speak only when asked (CLOGSCOPE_LOG=debug): the tool says what went wrong itself.
  const bool debug = level && !std::strcmp(level, "debug");
  cv::utils::logging::setLogLevel(debug ? cv::utils::logging::LOG_LEVEL_DEBUG
                                        : cv::utils::logging::LOG_LEVEL_SILENT);
  clogscope::calib::SetSolverLogging(debug);
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    PrintUsage();
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version")) {
    std::printf("clogscope %s\n", clogscope::kVersion);
    return 0;
  }
  for (const auto& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    try {
      return c.run(argc - 1, argv + 1);
    } catch (const std::invalid_argument& e) {
      std::fprintf(clogscope::ToolStderr(), "clogscope %s: error: %s\n", c.name, e.what());
      return 1;
    } catch (const cv::Exception& e) {
      // A bug or an input no check foresaw: one line, not OpenCV's multi-line text.
      std::fprintf(clogscope::ToolStderr(), "clogscope %s: failed: image library error in %s: %s\n",
                   c.name, e.func.c_str(), e.err.c_str());
      return 1;
    } catch (const std::exception& e) {
      std::fprintf(clogscope::ToolStderr(), "clogscope %s: failed: %s\n", c.name, e.what());
      return 1;
    }
  }
  std::fprintf(clogscope::ToolStderr(), "clogscope: unknown command '%s' (try clogscope --help)\n",
               argv[1]);
  return 2;
}
