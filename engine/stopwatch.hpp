// Wall time, as every timing of vkray reads it: one clock, milliseconds as doubles.
#pragma once

#include <chrono>

namespace vkray {

using Clock = std::chrono::steady_clock;

// Milliseconds from `start` to `end` (now, by default).
inline double elapsed_ms(Clock::time_point start, Clock::time_point end = Clock::now()) {
  return std::chrono::duration<double, std::milli>(end - start).count();
}

// The time point `ms` milliseconds after `start`.
inline Clock::time_point after_ms(Clock::time_point start, double ms) {
  return start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(ms));
}

// Times the steps of a run: each lap the milliseconds since the last (or since it was made).
class Stopwatch {
 public:
  double lap_ms() {
    const auto now = Clock::now();
    const double ms = elapsed_ms(last_, now);
    last_ = now;
    return ms;
  }
  double total_ms() const { return elapsed_ms(start_); }

 private:
  Clock::time_point start_ = Clock::now();
  Clock::time_point last_ = start_;
};

}  // namespace vkray
