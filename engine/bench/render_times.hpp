// GPU times of a camera's renders, for the benches that time a scene after it changed.
#pragma once

#include "engine/render/renderer.hpp"
#include "engine/statistics.hpp"

#include <vector>

namespace vkray {

// GPU ms of `frames` renders of depth and normal after a first (which pays for first uses), and the
// last frame.
inline TimeStats render_times(Renderer& renderer, const Scene& scene, uint32_t frames, Frame& last) {
  std::vector<double> times;
  for (uint32_t n = 0; n <= frames; ++n) {
    last = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
    if (n > 0) times.push_back(renderer.timings().dispatch_gpu_ms);
  }
  return time_stats(times);
}

}  // namespace vkray
