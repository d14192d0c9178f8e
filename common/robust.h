#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace clogscope {

// σ of normally distributed data per unit of its median absolute deviation (1/Φ⁻¹(0.75)).
inline constexpr double kMadToSigma = 1.4826;
// The standard normal's 97.5 % quantile: a two-sided 95 % interval is ±kZ95 σ.
inline constexpr double kZ95 = 1.959963984540054;

// Median of *v, reordering it (no copy: for a scratch buffer refilled in a loop).
inline double MedianInPlace(std::vector<double>* v) {
  if (v->empty()) return 0;
  const size_t mid = v->size() / 2;
  std::nth_element(v->begin(), v->begin() + mid, v->end());
  double m = (*v)[mid];
  if (v->size() % 2 == 0) m = 0.5 * (m + *std::max_element(v->begin(), v->begin() + mid));
  return m;
}

// Medians of a few values by compare-exchange networks (a min and a max each, no branches), for
// the row medians every profile across an edge takes: the values MedianInPlace and nth_element
// give, at a third of nth_element's instructions. Both reorder v. Each is a sorting network (19
// exchanges for 8 inputs, 39 for 12) less the exchanges that never reach its middle outputs;
// robust_test checks them on every input of 0s and 1s, which by the 0-1 principle covers all.
namespace median_network {
inline void Exchange(double* v, int a, int b) {
  const double lo = std::min(v[a], v[b]), hi = std::max(v[a], v[b]);
  v[a] = lo;
  v[b] = hi;
}
}  // namespace median_network
// The mean of the 4th and 5th smallest of v[0..7] (MedianInPlace of 8 values).
inline double MedianOf8(double* v) {
  using median_network::Exchange;
  Exchange(v, 0, 2), Exchange(v, 1, 3), Exchange(v, 4, 6), Exchange(v, 5, 7);
  Exchange(v, 0, 4), Exchange(v, 1, 5), Exchange(v, 2, 6), Exchange(v, 3, 7);
  Exchange(v, 0, 1), Exchange(v, 2, 3), Exchange(v, 4, 5), Exchange(v, 6, 7);
  Exchange(v, 2, 4), Exchange(v, 3, 5);
  Exchange(v, 1, 4), Exchange(v, 3, 6);
  Exchange(v, 3, 4);
  return 0.5 * (v[4] + v[3]);
}
// The 7th smallest of v[0..11], the upper of its two middle values (nth_element's v[6]).
inline double UpperMedianOf12(double* v) {
  using median_network::Exchange;
  Exchange(v, 0, 8), Exchange(v, 1, 7), Exchange(v, 2, 6), Exchange(v, 3, 11), Exchange(v, 4, 10);
  Exchange(v, 5, 9);
  Exchange(v, 0, 1), Exchange(v, 2, 5), Exchange(v, 3, 4), Exchange(v, 6, 9), Exchange(v, 7, 8);
  Exchange(v, 10, 11);
  Exchange(v, 0, 2), Exchange(v, 1, 6), Exchange(v, 5, 10), Exchange(v, 9, 11);
  Exchange(v, 0, 3), Exchange(v, 1, 2), Exchange(v, 4, 6), Exchange(v, 5, 7), Exchange(v, 8, 11);
  Exchange(v, 9, 10);
  Exchange(v, 1, 4), Exchange(v, 3, 5), Exchange(v, 6, 8), Exchange(v, 7, 10);
  Exchange(v, 2, 5), Exchange(v, 6, 9);
  Exchange(v, 4, 5), Exchange(v, 6, 7);
  Exchange(v, 4, 6), Exchange(v, 5, 7);
  Exchange(v, 5, 6);
  return v[6];
}

// Median (the mean of the two middle values for an even count); 0 for no values.
inline double Median(std::vector<double> v) { return MedianInPlace(&v); }

// Median(v) of values given as counts: count_at(k) of them equal k, for k < levels, n of them in
// all. In a pass over the counts up to the median, not a selection over the values (a frame's
// 50 000 noise samples, each a small integer, whose median is a few levels up).
template <typename CountAt>
double MedianOfCounts(size_t levels, long long n, CountAt count_at) {
  if (n == 0) return 0;
  // The values at ranks n/2 (upper middle) and, for an even count, n/2 − 1 (lower middle).
  const long long upper = n / 2, lower = n % 2 == 0 ? upper - 1 : upper;
  long long seen = 0;
  double lower_value = -1;
  for (size_t k = 0; k < levels; ++k) {
    seen += count_at(k);
    if (lower_value < 0 && seen > lower) lower_value = static_cast<double>(k);
    if (seen > upper) return 0.5 * (lower_value + static_cast<double>(k));
  }
  return lower_value;  // not reached when the counts hold n values
}

inline double MedianOfCounts(const std::vector<int>& counts) {
  long long n = 0;
  for (int c : counts) n += c;
  return MedianOfCounts(counts.size(), n, [&](size_t k) { return counts[k]; });
}

// The middle value, the upper of the two middle ones for an even count (no mean of them: always a
// value of `v`); 0 for no values.
inline double UpperMedian(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Median absolute deviation from `median` (unscaled: σ ≈ kMadToSigma·MAD for normal data).
inline double Mad(const std::vector<double>& v, double median) {
  std::vector<double> dev;
  dev.reserve(v.size());
  for (double x : v) dev.push_back(std::abs(x - median));
  return Median(std::move(dev));
}

// The standard error of `v`'s median `median`, for normal scatter: sqrt(pi/2) times the mean's,
// the scatter taken from the MAD. 0 when `v` is empty.
inline double MedianStandardError(const std::vector<double>& v, double median) {
  if (v.empty()) return 0;
  constexpr double kMedianOverMeanError = 1.2533;  // sqrt(pi/2)
  return kMedianOverMeanError * kMadToSigma * Mad(v, median) /
         std::sqrt(static_cast<double>(v.size()));
}

}  // namespace clogscope
