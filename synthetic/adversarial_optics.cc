#include "synthetic/adversarial_optics.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "common/angle.h"

namespace clogscope::synthetic {

double LensTransmission(double x, double n, double acceptance_rad, double floor) {
  const double ax = std::min(std::abs(x), 1.0);
  const double delta = 2 * (std::asin(ax) - std::asin(ax / n));
  const double pass = 0.5 * std::erfc((delta - acceptance_rad) / (0.12 * acceptance_rad + 1e-9));
  return 0.92 * (floor + (1 - floor) * pass);
}

double StrandEmission(const AdversarialScene& p, double x) {
  // Lambertian: the surface's normal (x, √(1 − x²)) against the light's (sin θ, cos θ).
  const double bulge = std::sqrt(std::max(0.0, 1 - x * x));
  const double theta = p.light_deg * kDegToRad;
  const double lit = std::max(0.0, x * std::sin(theta) + bulge * std::cos(theta));
  return p.strand_level * (p.shading_ambient + (1 - p.shading_ambient) * lit);
}

namespace {

// cv::GaussianBlur's kernel for a float image: 2·round(4σ)+1 taps.
std::vector<double> GaussianTaps(double sigma_px) {
  const int taps = cvRound(sigma_px * 4 * 2 + 1) | 1;
  const cv::Mat g = cv::getGaussianKernel(taps, sigma_px, CV_64F);
  return {g.begin<double>(), g.end<double>()};
}

// Down the columns: `in` blurred by the Gaussian, each blurred hi-res row times its weight
// (`weights`, empty for 1s), then each F rows averaged and added to `out`. Output row y is
// Σ_t k_y[t]·(input row F·y + t − r): the blur's taps convolved with the F-row mean, so only the
// output rows are computed. In strips of columns, so that the input rows that neighbouring output
// rows share stay in the cache.
void AddBinnedRows(const cv::Mat& in, const std::vector<double>& taps, int F,
                   const std::vector<float>& weights, cv::Mat* out) {
  const int r = static_cast<int>(taps.size()) / 2, n = in.rows;
  constexpr int kStrip = 256;  // columns: ~100 input rows of them fit in L2
  cv::parallel_for_(cv::Range(0, out->rows), [&](const cv::Range& range) {
    const int nk = static_cast<int>(taps.size()) + F - 1;
    std::vector<float> k(static_cast<size_t>(nk) * range.size(), 0.f);
    for (int y = range.start; y < range.end; ++y) {
      float* ky = &k[static_cast<size_t>(nk) * (y - range.start)];
      for (int j = 0; j < F; ++j) {
        const double w = (weights.empty() ? 1.0 : weights[F * y + j]) / F;
        for (size_t a = 0; a < taps.size(); ++a) ky[j + a] += static_cast<float>(w * taps[a]);
      }
    }
    std::vector<const float*> rows(nk);
    for (int x0 = 0; x0 < in.cols; x0 += kStrip) {
      const int x1 = std::min(in.cols, x0 + kStrip);
      for (int y = range.start; y < range.end; ++y) {
        const float* ky = &k[static_cast<size_t>(nk) * (y - range.start)];
        for (int t = 0; t < nk; ++t)
          rows[t] = in.ptr<float>(cv::borderInterpolate(F * y + t - r, n, cv::BORDER_REFLECT_101));
        float* o = out->ptr<float>(y);
        // 16 outputs summed in registers over every tap, then added to the row once (gcc does
        // not keep such a block in vector registers by itself).
        int x = x0;
        for (; x + 16 <= x1; x += 16) {
          cv::v_float32x4 a0 = cv::v_setzero_f32(), a1 = a0, a2 = a0, a3 = a0;
          for (int t = 0; t < nk; ++t) {
            const cv::v_float32x4 kt = cv::v_setall_f32(ky[t]);
            const float* s = rows[t] + x;
            a0 += kt * cv::v_load(s);
            a1 += kt * cv::v_load(s + 4);
            a2 += kt * cv::v_load(s + 8);
            a3 += kt * cv::v_load(s + 12);
          }
          cv::v_store(o + x, cv::v_load(o + x) + a0);
          cv::v_store(o + x + 4, cv::v_load(o + x + 4) + a1);
          cv::v_store(o + x + 8, cv::v_load(o + x + 8) + a2);
          cv::v_store(o + x + 12, cv::v_load(o + x + 12) + a3);
        }
        for (; x < x1; ++x) {
          float acc = 0;
          for (int t = 0; t < nk; ++t) acc += ky[t] * rows[t][x];
          o[x] += acc;
        }
      }
    }
  });
}

// Along the rows: the same on the transposed layer.
cv::Mat BinColumns(const cv::Mat& in, const std::vector<double>& taps, int F) {
  cv::Mat t, binned, out;
  cv::transpose(in, t);
  binned = cv::Mat::zeros(in.cols / F, in.rows, CV_32F);
  AddBinnedRows(t, taps, F, {}, &binned);
  cv::transpose(binned, out);
  return out;
}

}  // namespace

cv::Mat BlurAndBin(const cv::Mat& hires, int oversample, double sigma_hi_px,
                   double sigma_bottom_hi_px, const std::vector<float>& bottom_weight) {
  // The blur along the rows and the mean of F columns act within each row, so they commute with
  // the blend of rows: both are done first, at a third of the columns.
  const int F = oversample;
  CV_Assert(hires.type() == CV_32F && hires.rows % F == 0 && hires.cols % F == 0);
  cv::Mat out = cv::Mat::zeros(hires.rows / F, hires.cols / F, CV_32F);
  const std::vector<double> taps = GaussianTaps(sigma_hi_px);
  if (bottom_weight.empty()) {
    AddBinnedRows(BinColumns(hires, taps, F), taps, F, {}, &out);
    return out;
  }
  CV_Assert(static_cast<int>(bottom_weight.size()) == hires.rows);
  std::vector<float> top_weight(bottom_weight.size());
  for (size_t i = 0; i < top_weight.size(); ++i) top_weight[i] = 1 - bottom_weight[i];
  const std::vector<double> bottom_taps = GaussianTaps(sigma_bottom_hi_px);
  AddBinnedRows(BinColumns(hires, taps, F), taps, F, top_weight, &out);
  AddBinnedRows(BinColumns(hires, bottom_taps, F), bottom_taps, F, bottom_weight, &out);
  return out;
}

}  // namespace clogscope::synthetic
