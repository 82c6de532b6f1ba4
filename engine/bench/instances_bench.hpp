// Instances against the same scene flattened (`vkray bench --suite instances`): one mesh of each of
// the suite's models, each scaled to a unit box and placed many times on a grid (turned and scaled
// at random), rendered as instances and as the scene written out with every placement's triangles;
// then every transform changed at once (Renderer::set_transforms) and the moved scene rendered.
// Each render's GPU time and error against the double-precision reference, measured in one run.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/reference/envelope.hpp"
#include "engine/scene/scene.hpp"
#include "engine/statistics.hpp"

#include <string>
#include <vector>

namespace vkray {

struct InstancesRow {
  size_t instances = 0;
  size_t triangles_stored = 0;  // the models' triangles, once each
  size_t triangles_placed = 0;  // as many as the flattened scene holds
  // GPU ms a render (depth and normal) at the scene's size.
  TimeStats instanced, flattened, moved;
  TimeStats moved_built;  // the moved scene on a Renderer made for it
  // Device bytes of the geometry: with instances, the models' meshes alone (each once, in one
  // scene), and the flattened scene.
  size_t instanced_bytes = 0, meshes_bytes = 0, flattened_bytes = 0;
  TimeStats set_transforms;  // every instance's transform at once: the whole call, ms
  // Every `row_step`-th row against the reference: the instanced and flattened frames against the
  // instanced scene's, the moved frame against the moved scene's.
  EnvelopeReport instanced_error, flattened_error, moved_error;
};

// Throws InputError where the scene flattened for `count` instances of `models` would not fit in the
// memory the machine has free (available_host_memory_bytes), naming the most that would: the suite
// holds every placement's triangles once on the host and on the device besides.
void check_instances_fit(const std::vector<Scene>& models, uint32_t count);

// `count` instances of the first mesh of each of `models`, in turn, at width x height; `frames`
// renders of each after a first, `frames` calls of set_transforms after a first.
InstancesRow bench_instances(GpuDevice& device, const std::vector<Scene>& models, uint32_t count, uint32_t width,
                             uint32_t height, uint32_t frames, uint32_t row_step);

// `vkray bench --suite instances`' lines.
std::string instances_report(const InstancesRow& row);

}  // namespace vkray
