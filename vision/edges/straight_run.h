#pragma once

#include <vector>

#include "vision/edges/caliper.h"

namespace clogscope::vision {

// Where a filament's edges are straight. A drive gear's knurl presses teeth marks into the
// filament below the point where it grips: there the silhouette is a saw tooth several px deep and
// its mean width is the gear's mark, not the feedstock's diameter. The measurement keeps to the
// longest straight part of the stretch.
struct StraightRunOptions {
  int half_window_calipers = 4;  // a caliper's edge is judged against the line through ±this many
  double max_residual_px = 1.0;  // farther from that line than this: rough
  int min_rough_calipers = 3;    // a rough section has at least this many rough calipers
  int min_window_fits = 5;       // fewer fitted calipers in a window: not judged
  // Calipers [prefer_begin, prefer_end) (tracking: the part measured last frame): the part with
  // most straight calipers among them is kept, within that range, if it has min_kept_calipers
  // there, however long the others.
  int prefer_begin = 0, prefer_end = 0;
  int min_kept_calipers = 8;
};

struct StraightRun {
  int begin = 0, end = 0;  // calipers [begin, end) of the longest straight part
  int rough = 0;           // calipers judged rough over the whole band
  int sections = 0;        // rough sections that split the band (0: the whole band is straight)
  std::vector<int> state;  // per caliper: 1 straight, −1 rough, 0 not judged (unfitted, too few)
};

// The longest part of `calipers` (in order along the axis, fitted ones with edges) not split by a
// rough section: a run of calipers, unfitted or rough, holding at least min_rough_calipers rough
// ones. Isolated rough calipers (a speck, one bad fit) do not split it; the width's outlier cut
// deals with them. Longest = most straight calipers (or, with a preferred range, most of them
// inside it).
StraightRun FindStraightRun(const std::vector<Caliper>& calipers,
                            const StraightRunOptions& options = {});

}  // namespace clogscope::vision
