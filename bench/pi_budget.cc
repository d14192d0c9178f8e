#include "bench/pi_budget.h"

#include <fmt/format.h>

namespace clogscope::bench {
namespace {

struct PiModel {
  const char* name;
  double slower;  // this machine's frames/s over the Pi's, one core each
};
constexpr PiModel kPis[] = {{"Pi 5", 3.0}, {"Pi 4", 4.0}};
constexpr double kCameraFps = 30.0;  // the camera a budget is judged against
bool pi_columns = false;

}  // namespace

void EnablePiColumns() { pi_columns = true; }

std::string TableHead(const std::string& columns, const std::string& rule) {
  std::string head = columns, line = rule;
  if (pi_columns) {
    for (const PiModel& m : kPis) {
      head += fmt::format(" {} (÷{:g}) |", m.name, m.slower);
      line += "---|";
    }
  }
  return head + "\n" + line + "\n";
}

std::string PiCells(double fps) {
  std::string out;
  if (!pi_columns) return out;
  for (const PiModel& m : kPis) {
    const double pi_fps = fps / m.slower;
    out += fmt::format(" {:.0f} ({}) |", pi_fps,
                       pi_fps >= kCameraFps ? "keeps up at 30/s" : "falls behind at 30/s");
  }
  return out;
}

}  // namespace clogscope::bench
