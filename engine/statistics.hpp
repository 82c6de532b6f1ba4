// Summary statistics of measured values (times, errors).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace vkray {

// Nearest-rank percentile, fraction in [0, 1]; reorders `values`; 0 for none. A selection, not a
// sort: linear time, which at 7680x4320 (33M errors a frame) is seconds less per call.
inline double percentile(std::vector<double>& values, double fraction) {
  if (values.empty()) return 0.0;
  const auto rank = static_cast<size_t>(std::ceil(fraction * static_cast<double>(values.size())));
  const auto nth = values.begin() + static_cast<std::ptrdiff_t>(std::clamp<size_t>(rank, 1, values.size()) - 1);
  std::nth_element(values.begin(), nth, values.end());
  return *nth;
}

// Median (the mean of the middle two for an even count); 0 for none.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// Median and spread (minimum to maximum) of repeated timings, and the timings themselves (so that
// runs made apart can be pooled: pooled_time_stats).
struct TimeStats {
  double median_ms = 0.0;
  double min_ms = 0.0;
  double max_ms = 0.0;
  std::vector<double> samples_ms;

  // Faster than `other` beyond the noise: its slowest run beat the other's fastest. Where the two
  // spreads overlap, neither is faster (a busy machine moved one variant by 1.5x between runs).
  bool clearly_faster_than(const TimeStats& other) const { return max_ms < other.min_ms; }
};

inline TimeStats time_stats(const std::vector<double>& times_ms) {
  if (times_ms.empty()) return {};
  const auto [fastest, slowest] = std::minmax_element(times_ms.begin(), times_ms.end());
  return {median(times_ms), *fastest, *slowest, times_ms};
}

// The statistics of both runs' timings together.
inline TimeStats pooled_time_stats(const TimeStats& a, const TimeStats& b) {
  std::vector<double> both = a.samples_ms;
  both.insert(both.end(), b.samples_ms.begin(), b.samples_ms.end());
  return time_stats(both);
}

}  // namespace vkray
