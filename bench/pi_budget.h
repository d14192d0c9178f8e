#pragma once

#include <string>

namespace clogscope::bench {

// `clogscope_bench … --pi`: each frames/s figure of a table also as a Raspberry Pi's single core
// would give it, and whether that keeps up with a 30 frames/s camera. The factors are issue 26's
// estimate of a Pi's core against this machine's (a third for a Pi 5, a quarter for a Pi 4), not
// a measurement: run clogscope_bench on the Pi to know.
void EnablePiColumns();

// A Markdown table's two head lines ("| a | b |\n|---|---|\n"), with the Pi columns when enabled.
std::string TableHead(const std::string& columns, const std::string& rule);

// A row's Pi cells for `fps` frames/s here (" 1137 (keeps up at 30/s) | …"); empty when disabled.
std::string PiCells(double fps);

}  // namespace clogscope::bench
