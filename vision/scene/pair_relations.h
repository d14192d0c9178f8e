#pragma once

#include <string>
#include <utility>

#include "vision/scene/scene.h"

// How two candidate pairs stand to each other across the view: side by side, one inside the
// other, on one edge line, rivals as the strand. The search (scene.cc) and the contest between
// pairs that held up (pair_contest.cc) judge by these.
namespace clogscope::vision {

// Two pairs' edges this close across the axis at mid-stretch are one line, px.
inline constexpr double kSameEdgePx = 1.5;

// Whether two pairs' axes are parallel (within 2°).
bool Parallel(const PairCandidate& a, const PairCandidate& b);

// Whether `c` could be the strand as much as `b` where the tip does not decide: it scores at
// least half as well, or it is wider than `b` and one of its edges is longer than it is wide.
bool CouldRival(const PairCandidate& b, const PairCandidate& c);

// The u-interval (left edge, right edge) of `c` in another pair's axis frame, at the middle of
// its stretch.
std::pair<double, double> Interval(const PairCandidate& c, const AxisFrame& frame);

// Two pairs with no edge in common, side by side (across b's axis at mid-stretch).
bool Disjoint(const PairCandidate& b, const PairCandidate& c);

// A bright pair and a dark one.
bool OppositeKinds(const PairCandidate& a, const PairCandidate& b);

// Both bright on dark or both dark on bright (not mixed).
bool SameKind(const PairCandidate& a, const PairCandidate& b);

// Whether `inner` lies across the axis inside `outer`, a wider pair, or shares one edge with it
// and lies inside with the other.
bool Contains(const PairCandidate& outer, const PairCandidate& inner);

// Whether `outer` contains `inner` and is comparable to it, so that the outer silhouette is the
// object.
bool Encloses(MeasureTarget target, const PairCandidate& outer, const PairCandidate& inner);

// Whether `b` lies inside `c`, parallel to it, and `c` could rival it as the strand.
bool InsideARival(const PairCandidate& b, const PairCandidate& c);

// Whether a strand pair `b` may be the inside of the wider pair `c` of the other kind, one that
// could rival it (a stripe or a lens's core inside a strand whose own pair is faint).
bool MayBeInsideOf(const PairCandidate& b, const PairCandidate& c);

// Whether an edge of `c` lies on one of `b`'s edge lines: across b's axis, each pair's edges read
// at its own mid-stretch.
bool OnAnEdgeLineOf(const PairCandidate& b, const PairCandidate& c);

// A pair in words: width, length, tilt, edge SNR, score.
std::string Describe(const PairCandidate& c);

}  // namespace clogscope::vision
