// `vkray bench`: render a scene with several configurations (variants) and report, for each, its
// time beside its error against the double-precision reference, measured in the same run.
#pragma once

#include "engine/compare.hpp"
#include "engine/gpu_device.hpp"
#include "engine/renderer.hpp"

#include <string>
#include <vector>

namespace vkray {

struct BenchVariant {
  std::string name;
  RendererOptions options;
};

// Every variant, by name: brute-force, bvh-per-ray, bvh-packet.
const std::vector<BenchVariant>& bench_variants();

struct BenchRow {
  std::string variant;
  uint32_t width = 0, height = 0;
  SceneStats stats;
  double upload_ms = 0, bvh_build_ms = 0, pipeline_ms = 0;  // once per variant, not in frame times
  double dispatch_median_ms = 0, dispatch_min_ms = 0;       // GPU time per frame (timestamps)
  double frame_median_ms = 0;                               // host wall time per frame, readback included
  double mrays_per_s = 0;                                   // pixels / median dispatch time
  uint64_t unfinished_rays = 0;                             // finished on the CPU (loop budget), last frame
  FrameError error;
};

// Renders `frames` timed frames after one warm-up with `variant` and measures the last against
// `reference` (hits of the same scene, camera and size).
BenchRow run_bench_variant(GpuDevice& device, const Scene& scene, const BenchVariant& variant, uint32_t frames,
                           const std::vector<ReferenceHit>& reference);

}  // namespace vkray
