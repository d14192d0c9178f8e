#include "common/plot.h"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "common/atomic_file.h"
#include "common/spawn.h"

namespace clogscope {
namespace {

// A gnuplot string literal in single quotes: gnuplot expands backquotes (`command`) inside double
// quotes, never inside single ones, where only '' stands for a quote.
std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += '\'';
    if (c != '\n') out += c;
  }
  return out + "'";
}

bool IsCompletePng(const std::string& path) {
  std::string bytes;
  try {
    bytes = ReadFile(path);
  } catch (const std::exception&) {
    return false;
  }
  static const char kSignature[] = "\x89PNG\r\n\x1a\n";
  static const char kIend[] = "\0\0\0\0IEND\xae\x42\x60\x82";
  return bytes.size() >= 20 && bytes.compare(0, 8, std::string(kSignature, 8)) == 0 &&
         bytes.compare(bytes.size() - 12, 12, std::string(kIend, 12)) == 0;
}

}  // namespace

bool PlotToPng(const PlotSpec& spec, const std::string& png_path, std::string* why) {
  const std::string gnuplot = FindOnPath("gnuplot");
  if (gnuplot.empty()) {
    *why = "gnuplot is not installed (apt-get install gnuplot-nox)";
    return false;
  }
  const std::string partial = png_path + ".partial.png";
  std::string script = fmt::format(
      "set terminal pngcairo size {},{} enhanced font 'sans,11'\nset output {}\nset title {}\n"
      "set xlabel {}\nset ylabel {}\nset grid\nset key outside right top\nset autoscale xfix\n"
      "set offsets graph 0.02, graph 0.02, graph 0.05, graph 0.05\n",
      spec.width_px, spec.height_px, Quote(partial), Quote(spec.title), Quote(spec.x_label),
      Quote(spec.y_label));
  if (spec.zero_line) script += "set xzeroaxis lt -1\n";
  for (size_t i = 0; i < spec.series.size(); ++i) {
    const PlotSeries& s = spec.series[i];
    script += fmt::format("$d{} << EOD\n", i);
    for (size_t k = 0; k < s.x.size(); ++k) {
      script += fmt::format("{:.10g} {:.10g}", s.x[k], s.y[k]);
      if (!s.y_error.empty()) script += fmt::format(" {:.10g}", s.y_error[k]);
      script += "\n";
    }
    script += "EOD\n";
  }
  script += "plot ";
  for (size_t i = 0; i < spec.series.size(); ++i) {
    const PlotSeries& s = spec.series[i];
    if (i) script += ", \\\n     ";
    if (!s.y_error.empty()) {
      script += fmt::format("$d{} using 1:2:3 with yerrorbars title {}", i, Quote(s.title));
    } else {
      script += fmt::format("$d{} using 1:2 with {} title {}", i, s.style, Quote(s.title));
    }
  }
  script += "\n";
  const std::string script_path = png_path + ".gnuplot";
  try {
    WriteFileAtomically(script_path, script);
  } catch (const std::exception& e) {
    *why = e.what();
    return false;
  }
  // No shell. The script as gnuplot's argument (it stops at the first error; read from standard
  // input it would go on and plot to standard output), never taken for an option.
  SpawnOptions run;
  run.argv = {gnuplot, script_path.front() == '-' ? "./" + script_path : script_path};
  run.stdout_path = "/dev/null";
  run.stderr_path = script_path + ".err";
  std::string spawn_why;
  const pid_t pid = Spawn(run, &spawn_why);
  const bool ok = pid > 0 && WaitForExit(pid, &spawn_why);
  std::string err;
  try {
    err = ReadFile(script_path + ".err");
  } catch (const std::exception&) {
  }
  std::remove(script_path.c_str());
  std::remove((script_path + ".err").c_str());
  if (!ok || !std::filesystem::exists(partial)) {
    std::remove(partial.c_str());
    *why = "gnuplot failed: " + (err.empty() ? spawn_why : err.substr(0, err.find('\n')));
    return false;
  }
  // gnuplot may exit 0 after a failed write (a full disk): only a PNG that ends in its IEND
  // chunk is complete.
  if (!IsCompletePng(partial)) {
    std::remove(partial.c_str());
    *why = "gnuplot wrote an incomplete PNG (disk full?)";
    return false;
  }
  if (std::rename(partial.c_str(), png_path.c_str()) != 0) {
    *why = "cannot rename " + partial;
    return false;
  }
  return true;
}

}  // namespace clogscope
