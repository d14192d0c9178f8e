#pragma once

// Where a frame's data is clipped, shared by the pixels' gathering and the edge fits.
namespace clogscope::vision {

// The values at which a frame's data is clipped: its black and white, or where a codec put them. A
// clipped plateau passed through a codec keeps a spike in the histogram near its white (x264 in
// limited range decodes clipped white at ~233 of 235; the same read as full-range BGR at ~252 of
// 255); such a spike is the clip level.
struct ClipLevels {
  float low = 0, high = 255;
  double clipped_low_fraction = 0, clipped_high_fraction = 0;  // of the slab's pixels at or beyond
};

// Whether a value is at or beyond the clip levels.
inline bool Clipped(float v, const ClipLevels& clip) { return v <= clip.low || v >= clip.high; }

}  // namespace clogscope::vision
