#pragma once

#include <cstdint>
#include <vector>

namespace clogscope::synthetic::render {

// Pieces of a realistic scene for the renderer (synthetic.cc). Levels are 8-bit grey levels.

// A sum of plane waves Σ a·sin(kx·x + ky·y + φ) at the pixels of a width_px × height_px frame.
class PlaneWaves {
 public:
  struct Wave {
    double kx, ky, phase, amplitude;  // per px, per px, rad, grey levels
  };
  PlaneWaves(const std::vector<Wave>& waves, int width_px, int height_px);
  double At(int x, int y) const;

 private:
  // Per wave, a·sin(kx·x + φ) and a·cos(kx·x + φ) along x, sin(ky·y) and cos(ky·y) along y:
  // sin(a + b) from them costs no sine per pixel.
  int waves_ = 0, width_ = 0, height_ = 0;
  std::vector<double> sx_, cx_, sy_, cy_;
};

// Low-frequency background texture: six plane waves with wavelengths from 1 to 4 times
// `wavelength_px`, zero mean, peaking near ±amplitude. The same seed gives the same texture.
PlaneWaves Texture(double amplitude, double wavelength_px, uint64_t seed, int width_px,
                   int height_px);

// An opaque disc, or a gear (a disc with trapezoidal teeth), standing behind the strand.
struct ClutterObject {
  double cx = 0, cy = 0;  // centre, image px
  double radius_px = 0;   // disc radius; a gear's root radius
  double level = 0;
  int teeth = 0;  // 0: a disc
  double tooth_depth_px = 0;
  double phase = 0;
  // Fraction of the pixel at (x, y) the object covers, blurred by sigma_px (the edge is treated as
  // locally straight: exact enough for distractors, which carry no truth).
  double Coverage(double x, double y, double sigma_px) const;
};

// `discs` discs and `gears` gears placed beside a strand whose axis passes through (x0, y0) with
// direction (dx, dy) and which is width_px wide, below y_min; some overlap the strand's edges (and
// are hidden behind it). Their levels differ from avoid_level by at least 40 grey levels.
std::vector<ClutterObject> PlaceClutter(int discs, int gears, double x0, double y0, double dx,
                                        double dy, double width_px, double y_min, int image_width,
                                        int image_height, double avoid_level, uint64_t seed);

// The change a lit cylinder's shading makes to a strand of uniform level: inside the strand the
// radiance is level·(ambient + (1 − ambient)·√(1 − (2u/w)²)) instead of level. Tabulated over
// the across-axis distance u as the exact pixel mean of that change blurred by the PSF (cell
// averages of the profile, convolved with cell integrals of PSF ⊗ pixel footprint; the grid puts
// the strand's edges on cell boundaries), then read by linear interpolation.
class ShadingProfile {
 public:
  ShadingProfile(double width_px, double level, double ambient, double sigma_px, double nx,
                 double ny);
  double At(double u_px) const;

 private:
  double u0_ = 0, h_ = 1;
  std::vector<double> values_;
};

// A realistic stage micrometer's marks (a perfect lattice is drawn by synthetic.cc itself). Scene
// frame: u across the lines, s along them (down), both in px from the tip point. Ticks are finite
// segments of width line_width_px centred at u = k·pitch_px, all ending at s = tick_length_px:
// short ones tick_length_px long, every 5th 1.5×, every 10th 2×. With numerals, |k| is written in
// seven-segment digits (half a short tick tall) above each long tick, a quarter tick clear of it.
// Dust: discs of 1–3 line widths' radius and thin curved fibres anywhere in the image. The ticks'
// centres stay exactly at k·pitch_px; numerals and dust carry no truth.
struct MicrometerMarkParams {
  double pitch_px = 0, line_width_px = 0;
  double tick_length_px = 0;  // 0: lines across the whole image (dust only)
  bool numerals = false;
  int dust_specks = 0, dust_fibres = 0;
  double sigma_px = 0;    // PSF
  double nx = 1, ny = 0;  // the u direction in the image (unit)
  double tip_x_px = 0, tip_y_px = 0;
  int image_width = 0, image_height = 0;
  uint64_t seed = 1;
};

class MicrometerMarks {
 public:
  explicit MicrometerMarks(const MicrometerMarkParams& params);
  // Fraction of pixel (x, y) covered by the marks (ticks, numerals and dust), blurred by the PSF.
  double Coverage(double x, double y) const;

 private:
  struct Box {  // u0 < u1, s0 < s1, scene frame
    double u0, u1, s0, s1;
  };
  struct Fibre {
    std::vector<double> x, y;  // polyline, image px
    double width_px, x_min, x_max, y_min, y_max;
  };
  double BoxCoverage(const Box& b, double u, double s) const;
  double NumeralCoverage(long tick, double u, double s) const;
  MicrometerMarkParams p_;
  double reach_px_;        // a mark's blurred edge reaches this far beyond it
  double fibre_sigma_px_;  // the PSF and the pixel's footprint together, across a fibre
  double digit_h_ = 0, digit_w_ = 0, digit_gap_ = 0, numeral_bottom_ = 0;
  std::vector<ClutterObject> specks_;
  std::vector<Fibre> fibres_;
};

}  // namespace clogscope::synthetic::render
