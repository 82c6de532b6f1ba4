// --suite instances: models placed many times against the scene flattened (engine/bench/instances_bench.hpp).
#include "cli/bench_suites.hpp"
#include "cli/device_options.hpp"
#include "engine/bench/instances_bench.hpp"

#include <cstdio>

namespace vkray::cli {

// --suite instances: the suite's models placed --instances times, against the scene flattened,
// then every transform changed (engine/bench/instances_bench.hpp). The reference checks every 8th row.
int run_instances(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  std::vector<Scene> models;
  std::string names;
  for (const auto& scene : scenes) {
    if (scene.scene.meshes.empty()) throw InputError(scene.name + ": --suite instances places a mesh; the scene has none");
    models.push_back(scene.scene);
    names += (names.empty() ? "" : ", ") + scene.name;
  }
  check_instances_fit(models, options.instances);
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  const uint32_t width = scenes.front().scene.width, height = scenes.front().scene.height;
  std::printf("vkray bench --suite instances on %s\n%s, each scaled to a unit box, placed in turn at %ux%u; medians of %u calls "
              "after a first; render: GPU ms; errors against the reference on every 8th row\n",
              device.info().name.c_str(), names.c_str(), width, height, options.frames);
  std::fflush(stdout);
  const InstancesRow row = bench_instances(device, models, options.instances, width, height, options.frames, 8);
  std::fputs(instances_report(row).c_str(), stdout);
  return 0;
}

}  // namespace vkray::cli
