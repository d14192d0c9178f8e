#include "synthetic/edge_profile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace clogscope::synthetic {
namespace {

// Exact area of the unit pixel [-0.5, 0.5]² where nx·x + ny·y + t > 0, by clipping the square
// (Sutherland–Hodgman) and the shoelace formula: an independent check of the hard-edge limit.
double ClippedSquareArea(double t, double nx, double ny) {
  std::vector<std::pair<double, double>> poly = {{-.5, -.5}, {.5, -.5}, {.5, .5}, {-.5, .5}}, out;
  auto f = [&](std::pair<double, double> p) { return nx * p.first + ny * p.second + t; };
  for (size_t i = 0; i < poly.size(); ++i) {
    auto a = poly[i], b = poly[(i + 1) % poly.size()];
    const double fa = f(a), fb = f(b);
    if (fa > 0) out.push_back(a);
    if ((fa > 0) != (fb > 0)) {
      const double k = fa / (fa - fb);
      out.push_back({a.first + k * (b.first - a.first), a.second + k * (b.second - a.second)});
    }
  }
  double area = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    auto a = out[i], b = out[(i + 1) % out.size()];
    area += a.first * b.second - b.first * a.second;
  }
  return 0.5 * std::abs(area);
}

// Midpoint rule over the pixel on a fine grid: the blurred step is smooth, so the error is ~1e-8.
double BruteForcePixelMean(double t, double sigma, double nx, double ny) {
  const int n = 600;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double x = -0.5 + (i + 0.5) / n;
    for (int j = 0; j < n; ++j) {
      const double y = -0.5 + (j + 0.5) / n;
      sum += NormalCdf((t + nx * x + ny * y) / sigma);
    }
  }
  return sum / (double(n) * n);
}

TEST(EdgeProfileTest, HardEdgeIsExactArea) {
  for (double deg : {0.0, 3.0, 17.0, 30.0, 45.0, 61.0, 90.0, 133.0}) {
    const double nx = std::cos(deg * M_PI / 180), ny = std::sin(deg * M_PI / 180);
    for (double t = -1.2; t <= 1.2; t += 0.0625) {
      EXPECT_NEAR(PixelMeanOfBlurredStep(t, 0.0, nx, ny), ClippedSquareArea(t, nx, ny), 1e-9)
          << "deg " << deg << " t " << t;
    }
  }
}

TEST(EdgeProfileTest, BlurredEdgeMatchesFineIntegration) {
  for (double sigma : {0.3, 1.5, 3.0}) {
    for (double deg : {0.0, 10.0, 20.0, 45.0}) {
      const double nx = std::cos(deg * M_PI / 180), ny = std::sin(deg * M_PI / 180);
      for (double t : {-4.0, -1.3, -0.4, 0.0, 0.25, 0.9, 2.2}) {
        EXPECT_NEAR(PixelMeanOfBlurredStep(t, sigma, nx, ny), BruteForcePixelMean(t, sigma, nx, ny),
                    2e-7)
            << "sigma " << sigma << " deg " << deg << " t " << t;
      }
    }
  }
}

TEST(EdgeProfileTest, SymmetricAboutTheEdge) {
  // A symmetric PSF and footprint put the 50 % level exactly on the edge: no bias in the truth.
  for (double sigma : {0.0, 0.8, 2.0}) {
    for (double t : {0.1, 0.37, 0.8, 1.9}) {
      const double a = PixelMeanOfBlurredStep(t, sigma, 0.94, 0.342);
      const double b = PixelMeanOfBlurredStep(-t, sigma, 0.94, 0.342);
      EXPECT_NEAR(a + b, 1.0, 1e-12);
    }
    EXPECT_NEAR(PixelMeanOfBlurredStep(0.0, sigma, 0.6, 0.8), 0.5, 1e-12);
  }
}

}  // namespace
}  // namespace clogscope::synthetic
