#include "engine/bench.hpp"

#include <algorithm>
#include <chrono>

namespace vkray {
namespace {

BenchVariant variant(std::string name, PrimitiveSearch search) {
  BenchVariant result{std::move(name), {}};
  result.options.scene.search = search;
  return result;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace

const std::vector<BenchVariant>& bench_variants() {
  static const std::vector<BenchVariant> variants = {
      variant("brute-force", PrimitiveSearch::brute_force),
      variant("bvh-per-ray", PrimitiveSearch::bvh_per_ray),
      variant("bvh-packet", PrimitiveSearch::bvh_packet),
  };
  return variants;
}

BenchRow run_bench_variant(GpuDevice& device, const Scene& scene, const BenchVariant& variant, uint32_t frames,
                           const std::vector<ReferenceHit>& reference) {
  const AovSet aovs{Aov::depth, Aov::normal};
  Renderer renderer(device, scene, variant.options);
  BenchRow row;
  row.variant = variant.name;
  row.width = scene.width;
  row.height = scene.height;
  row.stats = renderer.scene_stats();
  Frame frame = renderer.render(scene.camera, scene.width, scene.height, aovs);  // warm-up, creates the pipeline
  row.upload_ms = renderer.timings().upload_ms;
  row.bvh_build_ms = renderer.timings().bvh_build_ms;
  row.pipeline_ms = renderer.timings().pipeline_ms;
  std::vector<double> dispatch_ms, frame_ms;
  for (uint32_t i = 0; i < std::max(frames, 1u); ++i) {
    const auto start = std::chrono::steady_clock::now();
    frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
    frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    dispatch_ms.push_back(renderer.timings().has_gpu_times ? renderer.timings().dispatch_gpu_ms : frame_ms.back());
  }
  row.dispatch_median_ms = median(dispatch_ms);
  row.dispatch_min_ms = *std::min_element(dispatch_ms.begin(), dispatch_ms.end());
  row.frame_median_ms = median(frame_ms);
  row.mrays_per_s = static_cast<double>(frame.pixel_count()) / (row.dispatch_median_ms * 1e3);
  row.unfinished_rays = renderer.timings().unfinished_rays;
  row.error = measure_error(frame, reference);
  return row;
}

}  // namespace vkray
