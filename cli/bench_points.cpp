// --suite points: point queries against Embree's rtcPointQuery (engine/bench/points_bench.hpp).
#include "cli/bench_suites.hpp"
#include "cli/device_options.hpp"
#include "engine/bench/points_bench.hpp"

#include <cstdio>

namespace vkray::cli {

// --suite points: on each scene, --points points uniform in its box and as many near its surface; the
// unsigned and the signed distance, medians of --frames calls after a first, beside Embree's; errors
// against the reference on every 64th point.
int run_points(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  std::printf("vkray bench --suite points on %s\nwall ms of a whole call, medians of %u calls after a first; Embree: rtcPointQuery "
              "on every core; error: the largest distance error over the box's diagonal, flips: signs unlike the fp64 winding "
              "number's, on every 64th point\n",
              device.info().name.c_str(), options.frames);
  std::fputs(points_table_header().c_str(), stdout);
  std::fflush(stdout);
  BenchTiming timing;
  timing.frames = options.frames;
  for (const BenchScene& scene : scenes) {
    for (const PointSet set : {PointSet::uniform, PointSet::near_surface}) {
      const PointsRow row = bench_point_queries(device, scene.scene, set, options.points, timing, 64);
      std::fputs(points_table_row(scene.name, row).c_str(), stdout);
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace vkray::cli
