// A progress line on stderr for long steps, shown only on a terminal and only once the step has
// taken a second, so quick runs and logs stay clean.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>

namespace vkray::cli {

class ProgressLine {
 public:
  explicit ProgressLine(std::string what) : what_(std::move(what)), enabled_(isatty(STDERR_FILENO) == 1) {}
  ~ProgressLine() {
    if (shown_) std::fprintf(stderr, "\r%*s\r", static_cast<int>(what_.size()) + 16, "");
  }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  // A callback for the engine: fraction done in [0, 1], from any thread.
  std::function<void(double)> callback() {
    if (!enabled_) return {};
    return [this](double fraction) { report(fraction); };
  }

 private:
  void report(double fraction) {
    using namespace std::chrono;
    const std::lock_guard lock(mutex_);
    if (steady_clock::now() - start_ < seconds(1)) return;
    shown_ = true;
    std::fprintf(stderr, "\rvkray: %s %3d%%", what_.c_str(), static_cast<int>(fraction * 100.0));
    std::fflush(stderr);
  }

  std::string what_;
  bool enabled_;
  bool shown_ = false;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace vkray::cli
