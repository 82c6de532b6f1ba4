// --suite rays: given rays of every kind against Embree (engine/bench/given_rays_bench.hpp).
#include "cli/bench_suites.hpp"
#include "cli/device_options.hpp"
#include "engine/bench/bench_report.hpp"
#include "engine/bench/given_rays_bench.hpp"
#include "engine/io/image_io.hpp"

#include <cstdio>

namespace vkray::cli {

// --suite rays: every kind of given rays (ray_kinds) on each scene, a table row each; the files
// (--json, --csv) have every figure of each row.
int run_given_rays(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  BenchReport report = new_bench_report(device.info(), options.suite, options.frames);
  std::printf("vkray bench --suite rays on %s\n%zu scene%s, %zu rays a kind, %u timed calls after a first; times are medians\n%s",
              device.info().name.c_str(), scenes.size(), scenes.size() == 1 ? "" : "s", options.rays, options.frames,
              given_rays_table_header().c_str());
  std::fflush(stdout);
  BenchTiming timing;
  timing.frames = options.frames;
  for (const auto& scene : scenes) {
    for (const auto& kind : ray_kinds()) {
      const std::vector<GivenRay> rays = make_rays(kind.kind, scene.scene, options.rays);
      GivenRaysResult result{scene.name, scene_hash(scene.scene),
                             bench_given_rays(device, scene.scene, kind.name, rays, timing)};
      std::fputs(given_rays_table_row(scene.name, result.row).c_str(), stdout);
      std::fflush(stdout);
      report.given_rays.push_back(std::move(result));
    }
  }
  if (!options.json.empty()) write_text_file(options.json, given_rays_json(report));
  if (!options.csv.empty()) write_text_file(options.csv, given_rays_csv(report));
  return 0;
}

}  // namespace vkray::cli
