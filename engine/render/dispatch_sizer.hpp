// Rows of the next dispatch, from the time the earlier ones took (RendererOptions::dispatch_budget_ms).
#pragma once

#include <algorithm>
#include <cstdint>

namespace vkray {

class DispatchSizer {
 public:
  // `max_rows`: what the output buffers hold; rows are counted in `width`-wide rows, and taken in
  // whole `row_step`s (the rows of a workgroup) where `max_rows` allows. `known_ms_per_pixel`: the
  // slowest pixels of the renderer's last render, 0 for none.
  DispatchSizer(uint32_t width, uint32_t max_rows, double budget_ms, double known_ms_per_pixel, uint32_t row_step = 1)
      : width_(width), max_rows_(max_rows), budget_ms_(budget_ms), known_ms_per_pixel_(known_ms_per_pixel),
        row_step_(row_step) {}

  uint32_t next_rows() const {
    if (budget_ms_ <= 0.0) return max_rows_;
    uint64_t rows = first_dispatch_pixels / width_;
    // After a render of the same scene, the first dispatch takes what a quarter of the budget holds
    // at its slowest pixels' cost (another camera can cost more): one dispatch a frame where the
    // frame fits, as many views in a row do, where three cost the bunny at 1920x1080 about 5 ms more.
    if (last_rows_ == 0 && known_ms_per_pixel_ > 0.0) {
      rows = static_cast<uint64_t>(0.25 * budget_ms_ / (known_ms_per_pixel_ * width_));
    }
    if (last_rows_ > 0) {
      // Growth bounded, so a jump in cost shows before it costs much; sixteen, since on lavapipe
      // every dispatch beyond three cost the bunny at 1920x1080 about 3 ms (four times: 4
      // dispatches, 160 ms).
      rows = uint64_t{16} * last_rows_;
      if (slowest_ms_per_row_ > 0.0) rows = std::min<uint64_t>(rows, static_cast<uint64_t>(0.5 * budget_ms_ / slowest_ms_per_row_));
    }
    rows = std::max<uint64_t>(rows / row_step_, 1) * row_step_;
    return static_cast<uint32_t>(std::clamp<uint64_t>(rows, 1, max_rows_));
  }

  void measured(uint32_t rows, double ms) {
    last_rows_ = rows;
    slowest_ms_per_row_ = std::max(slowest_ms_per_row_, ms / rows);
  }
  double slowest_ms_per_pixel() const { return slowest_ms_per_row_ / width_; }

 private:
  // The first dispatch: 65536 pixels, a few ms on lavapipe's two cores even where every ray walks a
  // tree, and far less on a GPU.
  static constexpr uint32_t first_dispatch_pixels = 65536;
  uint32_t width_, max_rows_;
  double budget_ms_;
  double known_ms_per_pixel_;
  uint32_t row_step_;
  uint32_t last_rows_ = 0;
  double slowest_ms_per_row_ = 0.0;
};

}  // namespace vkray
