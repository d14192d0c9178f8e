#pragma once

// Headless Chromium (Debian's package chromium) for the page's tests, and reading back what a page
// drew from the DOM it left.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <opencv2/core.hpp>
#include <regex>
#include <string>
#include <vector>

#include "common/atomic_file.h"
#include "common/spawn.h"
#include "tests/apps/cli_test_util.h"
#include "tests/apps/external_process.h"

namespace clogscope::apps::testing {

// Headless Chromium on `url` with a profile of its own in `dir` (number `run`, removed after),
// `mode` one of --dump-dom (the DOM is returned) or --screenshot=PATH. Virtual time: the page's
// requests and timers run until `budget_ms` of its time passed, however fast.
inline std::string Chromium(const std::filesystem::path& dir, int run, const std::string& url,
                            const std::string& mode, int budget_ms = 3000) {
  namespace fs = std::filesystem;
  const fs::path profile = dir / fmt::format("profile{}", run);
  const fs::path errors = dir / "chromium.err";
  const auto t0 = std::chrono::steady_clock::now();
  const ProgramResult r = RunWithInput(
      {FindOnPath("chromium"), "--headless=new",
       // root in a container has no user namespace for Chromium's sandbox; the page is ours.
       "--no-sandbox", "--disable-gpu", "--user-data-dir=" + profile.string(), "--no-first-run",
       "--no-default-browser-check", "--disable-background-networking",
       "--disable-component-update", "--disable-sync", "--hide-scrollbars",
       "--window-size=1280,1000", fmt::format("--virtual-time-budget={}", budget_ms), mode, url},
      "", errors.string());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "chromium " << mode << ": exit " << r.exit_code << ", " << seconds << " s\n";
  fs::remove_all(profile);
  EXPECT_EQ(r.exit_code, 0) << ReadFile(errors.string());
  return r.output;
}

// One element's opening tag in serialized HTML: the one with id="ID", or the first <TAG.
inline std::string Tag(const std::string& html, const std::string& id_or_tag) {
  size_t at = id_or_tag[0] == '<' ? html.find(id_or_tag) : html.find("id=\"" + id_or_tag + "\"");
  if (at == std::string::npos) return "";
  const size_t start = html.rfind('<', at), end = html.find('>', at);
  return html.substr(start, end - start + 1);
}

// The text of the element with id="ID" (up to its first child).
inline std::string Text(const std::string& html, const std::string& id) {
  const size_t at = html.find("id=\"" + id + "\"");
  if (at == std::string::npos) return "";
  const size_t start = html.find('>', at) + 1;
  return html.substr(start, html.find('<', start) - start);
}

// An attribute of a tag; a failure when it is absent.
inline std::string Attr(const std::string& tag, const std::string& name) {
  std::smatch m;
  if (std::regex_search(tag, m, std::regex("\\s" + name + "=\"([^\"]*)\""))) return m[1];
  ADD_FAILURE() << name << " is not in " << tag;
  return "";
}
inline double NumAttr(const std::string& tag, const std::string& name) {
  const std::string v = Attr(tag, name);
  return v.empty() ? NAN : std::stod(v);
}

// The vertices of an SVG path written as "M x y L x y … [Z]".
inline std::vector<cv::Point2d> PathVertices(const std::string& d) {
  std::vector<cv::Point2d> out;
  static const std::regex vertex("[ML]\\s*(-?[0-9.]+)\\s+(-?[0-9.]+)");
  for (auto it = std::sregex_iterator(d.begin(), d.end(), vertex); it != std::sregex_iterator();
       ++it)
    out.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  return out;
}

// The plot's axes as the page wrote them on the <svg>: SVG coordinates back to time and value.
struct Axes {
  double left, right, top, bottom, t_min, t_max, y_min, y_max;
  explicit Axes(const std::string& svg)
      : left(NumAttr(svg, "data-area-left")),
        right(NumAttr(svg, "data-area-right")),
        top(NumAttr(svg, "data-area-top")),
        bottom(NumAttr(svg, "data-area-bottom")),
        t_min(NumAttr(svg, "data-t-min")),
        t_max(NumAttr(svg, "data-t-max")),
        y_min(NumAttr(svg, "data-y-min")),
        y_max(NumAttr(svg, "data-y-max")) {}
  double Time(double x) const { return t_min + (x - left) / (right - left) * (t_max - t_min); }
  double Value(double y) const { return y_min + (bottom - y) / (bottom - top) * (y_max - y_min); }
};

}  // namespace clogscope::apps::testing
