#include "vision/edges/straight_run.h"

#include <algorithm>
#include <cmath>

namespace clogscope::vision {
namespace {

struct Point {
  double s, u;
  bool centre;
};

// Least-squares line through the points; then, while the worst point lies beyond `tol` and more
// than `min_points` remain, drops it and fits again. Trimming keeps a straight caliper beside a
// rough section straight: the rough neighbours leave the fit instead of tilting it.
struct WindowLine {
  double slope = 0;
  bool centre_on_line = false;  // the window's centre caliper is still in, within tol
};

WindowLine FitWindowLine(std::vector<Point> pts, double tol, int min_points) {
  WindowLine out;
  while (true) {
    double n = 0, ss = 0, su = 0, sss = 0, ssu = 0;
    for (const Point& p : pts) {
      n += 1;
      ss += p.s;
      su += p.u;
      sss += p.s * p.s;
      ssu += p.s * p.u;
    }
    const double var = sss - ss * ss / n;
    out.slope = var > 1e-12 ? (ssu - ss * su / n) / var : 0.0;
    const double a = (su - out.slope * ss) / n;
    size_t worst = 0;
    double worst_r = -1, centre_r = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      const double r = std::abs(pts[i].u - a - out.slope * pts[i].s);
      if (pts[i].centre) centre_r = r;
      if (r > worst_r) {
        worst_r = r;
        worst = i;
      }
    }
    if (worst_r <= tol) {
      out.centre_on_line = true;
      return out;
    }
    if (pts[worst].centre) return out;
    if (static_cast<int>(pts.size()) <= min_points) {
      out.centre_on_line = centre_r <= tol;
      return out;
    }
    pts.erase(pts.begin() + static_cast<long>(worst));
  }
}

}  // namespace

StraightRun FindStraightRun(const std::vector<Caliper>& calipers,
                            const StraightRunOptions& options) {
  const int n = static_cast<int>(calipers.size());
  const int h = options.half_window_calipers;
  // 1 straight, 0 not judged (unfitted, or too few fitted neighbours), −1 rough.
  StraightRun run;
  std::vector<int>& state = run.state;
  state.assign(n, 0);
  std::vector<Point> left, right;
  for (int k = 0; k < n; ++k) {
    if (!calipers[k].fitted) continue;
    left.clear();
    right.clear();
    double s_min = calipers[k].s_px, s_max = s_min;
    for (int j = std::max(0, k - h); j <= std::min(n - 1, k + h); ++j) {
      const Caliper& c = calipers[j];
      if (!c.fitted) continue;
      left.push_back({c.s_px, c.left_u_px, j == k});
      right.push_back({c.s_px, c.right_u_px, j == k});
      s_min = std::min(s_min, c.s_px);
      s_max = std::max(s_max, c.s_px);
    }
    if (static_cast<int>(left.size()) < options.min_window_fits) continue;
    // Each edge on a line, and the two parallel (the width changes by less than the tolerance
    // over the window): the long flank of a knurl mark is a straight edge too, but it closes on
    // the other.
    const double tol = options.max_residual_px;
    const WindowLine l = FitWindowLine(left, tol, options.min_window_fits);
    const WindowLine r = FitWindowLine(right, tol, options.min_window_fits);
    const bool straight = l.centre_on_line && r.centre_on_line &&
                          std::abs(l.slope - r.slope) * (s_max - s_min) <= tol;
    state[k] = straight ? 1 : -1;
    run.rough += !straight;
  }
  // Split at every stretch of calipers that are not straight and hold enough rough ones; keep the
  // part with the most straight calipers.
  // Parts ranked by (straight calipers in the preferred range if that reaches the minimum, all
  // straight calipers).
  std::pair<int, int> best{-1, -1};
  int part_begin = 0, part_count = 0, part_preferred = 0;
  const auto close_part = [&](int end) {
    const std::pair<int, int> rank{part_preferred >= options.min_kept_calipers ? part_preferred : 0,
                                   part_count};
    if (rank > best) {
      best = rank;
      run.begin = part_begin;
      run.end = end;
    }
  };
  for (int k = 0; k < n;) {
    if (state[k] == 1) {
      ++part_count;
      part_preferred += k >= options.prefer_begin && k < options.prefer_end;
      ++k;
      continue;
    }
    int j = k, rough = 0;
    while (j < n && state[j] != 1) rough += state[j++] == -1;
    if (rough >= options.min_rough_calipers) {
      close_part(k);
      ++run.sections;
      part_begin = j;
      part_count = part_preferred = 0;
    }
    k = j;
  }
  close_part(n);
  // Kept where it was: the same calipers frame after frame, so that the width changes only when
  // the filament does.
  if (best.first > 0) {
    run.begin = std::max(run.begin, options.prefer_begin);
    run.end = std::min(run.end, options.prefer_end);
  }
  // A part ends at its last straight caliper, not at the rough section's first.
  while (run.end > run.begin && state[run.end - 1] != 1) --run.end;
  while (run.begin < run.end && state[run.begin] != 1) ++run.begin;
  // No rough section: the whole band, unless the preferred range was kept (then the band may be
  // just that range and its margins, as tracking measures it).
  if (run.sections == 0 && best.first == 0) {
    run.begin = 0;
    run.end = n;
  }
  return run;
}

}  // namespace clogscope::vision
