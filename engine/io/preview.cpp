#include "engine/io/preview.hpp"

#include "engine/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace vkray {
namespace {

constexpr double byte_max = VKRAY_RAMP_LEVELS - 1;

// The ramp of round(255 * clamp(f(v), 0, 1)) for a rising f, from its inverse: byte k starts where
// f reaches (k - 1/2) / 255. The inverse is evaluated in double and rounded to float once.
template <typename Inverse>
PreviewRamp ramp_from_inverse(Inverse inverse) {
  PreviewRamp ramp;
  ramp.thresholds[0] = -INFINITY;
  for (int k = 1; k < VKRAY_RAMP_LEVELS; ++k) ramp.thresholds[k] = static_cast<float>(inverse((k - 0.5) / byte_max));
  return ramp;
}

}  // namespace

uint8_t PreviewRamp::byte(float v) const {
  // The same 8 steps as preview.comp's ramp_byte.
  int level = 0;
  for (int step = VKRAY_RAMP_LEVELS / 2; step >= 1; step /= 2) {
    if (thresholds[level + step] <= v) level += step;
  }
  return static_cast<uint8_t>(level);
}

std::string depth_legend(DepthRange depths) {
  if (!(depths.near <= depths.far)) return "depth: no hit (black)";
  char text[120];  // short enough for the overlay of a small window
  std::snprintf(text, sizeof text, "depth %.5g white .. %.5g dark grey (grey ~ 1/depth)", depths.near, depths.far);
  return text;
}

std::array<PreviewRamp, 2> preview_ramps(Aov aov, DepthRange depths) {
  switch (aov) {
    case Aov::depth: {
      // grey = 0.1 + 0.9 (1/z - 1/far) / (1/near - 1/far), on -z so that it rises toward the camera.
      // Inverse depth keeps near detail visible when a ground plane runs to the horizon.
      constexpr double darkest = 0.1;
      const double span = 1.0 / depths.near - 1.0 / depths.far;
      const bool one_depth = !(span > 0.0);  // all hits at one depth (or none): full brightness
      return {ramp_from_inverse([&](double grey) {
                if (one_depth || grey <= darkest) return -double(INFINITY);
                return -1.0 / (1.0 / depths.far + (grey - darkest) / (1.0 - darkest) * span);
              }),
              PreviewRamp{}};
    }
    case Aov::normal:
      return {ramp_from_inverse([](double channel) { return 2.0 * channel - 1.0; }), PreviewRamp{}};
    case Aov::uv: {
      constexpr double outside_brightness = 0.3;
      auto brightened = [](double brightness) {
        return ramp_from_inverse([=](double channel) { return 2.0 * channel / brightness - 1.0; });
      };
      return {brightened(1.0), brightened(outside_brightness)};
    }
    default: break;  // the other outputs are not previewed: the depth they come with stands for them
  }
  throw std::invalid_argument("no preview for " + AovSet{aov}.names());
}

bool inside_unit_disk(uint32_t i, uint32_t j, uint32_t width, uint32_t height) {
  // uv = (2i + 1 - width, height - 2j - 1) / min(width, height); see pixel_uv.
  const int64_t x = int64_t{2} * i + 1 - width, y = int64_t{height} - 2 * int64_t{j} - 1;
  const int64_t shorter = std::min(width, height);
  return x * x + y * y <= shorter * shorter;
}

uint32_t preview_scale(uint32_t width, uint32_t height) {
  return std::max({1u, (width + max_preview_panel_width - 1) / max_preview_panel_width,
                   (height + max_preview_panel_height - 1) / max_preview_panel_height});
}

std::vector<uint8_t> preview_rgb(const Frame& frame, Aov aov, uint32_t scale) {
  const uint32_t width = (frame.width + scale - 1) / scale, height = (frame.height + scale - 1) / scale;
  std::vector<uint8_t> rgb(size_t{width} * height * 3, 0);
  const auto ramps = preview_ramps(aov, aov == Aov::depth ? finite_depth_range(frame) : DepthRange{});
  // The bytes of frame pixel (i, j), black on a miss.
  const auto bytes = [&](uint32_t i, uint32_t j) -> std::array<uint8_t, 3> {
    const size_t p = size_t{j} * frame.width + i;
    switch (aov) {
      case Aov::depth: {
        const float z = frame.depth[p];
        if (!std::isfinite(z)) return {0, 0, 0};
        const uint8_t grey = ramps[0].byte(-z);
        return {grey, grey, grey};
      }
      case Aov::normal: {
        if (!frame.hit(p)) return {0, 0, 0};
        const glm::vec3 n = frame.normal_at(p);
        return {ramps[0].byte(n.x), ramps[0].byte(n.y), ramps[0].byte(n.z)};
      }
      case Aov::uv: {
        const PreviewRamp& ramp = ramps[inside_unit_disk(i, j, frame.width, frame.height) ? 0 : 1];
        const glm::vec2 uv = frame.uv_at(p);
        return {ramp.byte(uv.x), ramp.byte(uv.y), ramp.byte(0.0f)};
      }
      default: return {0, 0, 0};  // the other outputs: preview_ramps refused them
    }
  };
  // Each preview pixel the rounded mean of its scale x scale block's (cut at the frame's edges).
  parallel_for_chunks(height, [&](size_t first_row, size_t end_row) {
    for (auto y = static_cast<uint32_t>(first_row); y < end_row; ++y) {
      for (uint32_t x = 0; x < width; ++x) {
        std::array<uint32_t, 3> sum{};
        uint32_t count = 0;
        for (uint32_t j = y * scale; j < std::min(frame.height, (y + 1) * scale); ++j) {
          for (uint32_t i = x * scale; i < std::min(frame.width, (x + 1) * scale); ++i, ++count) {
            const auto pixel = bytes(i, j);
            for (size_t c = 0; c < 3; ++c) sum[c] += pixel[c];
          }
        }
        uint8_t* out = &rgb[(size_t{y} * width + x) * 3];
        for (size_t c = 0; c < 3; ++c) out[c] = static_cast<uint8_t>((sum[c] + count / 2) / count);
      }
    }
  }, 8);
  return rgb;
}

}  // namespace vkray
