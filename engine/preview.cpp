#include "engine/preview.hpp"

#include <algorithm>
#include <cmath>

namespace vkray {

std::vector<uint8_t> preview_rgb(const Frame& frame, Aov aov) {
  std::vector<uint8_t> rgb(frame.pixel_count() * 3, 0);
  auto to_byte = [](double v) { return static_cast<uint8_t>(std::lround(255.0 * std::clamp(v, 0.0, 1.0))); };
  auto put = [&](size_t p, double r, double g, double b) {
    uint8_t* out = &rgb[p * 3];
    out[0] = to_byte(r), out[1] = to_byte(g), out[2] = to_byte(b);
  };

  switch (aov) {
    case Aov::depth: {
      // Grey from inverse depth, which keeps near detail visible when a ground plane runs to the
      // horizon; every hit stays at 10% or brighter so it never reads as a miss.
      double near = INFINITY, far = 0.0;
      for (float z : frame.depth) {
        if (std::isfinite(z)) near = std::min<double>(near, z), far = std::max<double>(far, z);
      }
      for (size_t p = 0; p < frame.pixel_count(); ++p) {
        const double z = frame.depth[p];
        if (!std::isfinite(z)) continue;
        const double span = 1.0 / near - 1.0 / far;
        const double grey = span > 0.0 ? 0.1 + 0.9 * (1.0 / z - 1.0 / far) / span : 1.0;
        put(p, grey, grey, grey);
      }
      break;
    }
    case Aov::normal:
      for (size_t p = 0; p < frame.pixel_count(); ++p) {
        if (!frame.hit(p)) continue;
        const glm::vec3 n = frame.normal_at(p);
        put(p, 0.5 * (n.x + 1.0), 0.5 * (n.y + 1.0), 0.5 * (n.z + 1.0));
      }
      break;
    case Aov::uv:
      for (size_t p = 0; p < frame.pixel_count(); ++p) {
        const double u = frame.uv_at(p).x, v = frame.uv_at(p).y;
        const double brightness = u * u + v * v <= 1.0 ? 1.0 : 0.3;
        put(p, brightness * 0.5 * (u + 1.0), brightness * 0.5 * (v + 1.0), brightness * 0.5);
      }
      break;
  }
  return rgb;
}

}  // namespace vkray
