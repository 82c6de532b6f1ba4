// --suite moving: a deforming mesh refitted against rebuilt (engine/bench/moving_bench.hpp).
#include "cli/bench_suites.hpp"
#include "cli/device_options.hpp"
#include "engine/bench/moving_bench.hpp"

#include <cstdio>

namespace vkray::cli {

// --suite moving: each model's first mesh deformed, refitted against rebuilt, and rendered after
// (engine/bench/moving_bench.hpp), a table row each.
int run_moving(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  std::printf("vkray bench --suite moving on %s\n%zu model%s at %ux%u, every vertex moved by up to 1%% of the model's size; "
              "medians of %u calls after a first; render: GPU ms; the depth's relative error p99 against the reference, and the "
              "pixels outside the error envelope, on the refitted tree and on one built for the moved model\n%s",
              device.info().name.c_str(), scenes.size(), scenes.size() == 1 ? "" : "s", scenes.front().scene.width,
              scenes.front().scene.height, options.frames, moving_table_header().c_str());
  std::fflush(stdout);
  for (const auto& scene : scenes) {
    if (scene.scene.meshes.empty()) throw InputError(scene.name + ": --suite moving deforms a mesh; the scene has none");
    std::fputs(moving_table_row(scene.name, bench_moving(device, scene.scene, options.frames)).c_str(), stdout);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace vkray::cli
