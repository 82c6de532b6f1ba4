// What a scene's pipelines are specialized on (PipelineSpecialization), and how many iterations a
// tree walk may take on a device that caps a shader's loops.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/vulkan/raycast_pipeline.hpp"

#include <cstdint>

namespace vkray {

// Iterations a tree walk may take on this device (0: no limit): a tree walk has no static bound on
// its iterations; where the device caps them, the walk gets what the other loops leave and rays
// that need more are finished on the CPU. `requested`: RendererOptions::loop_budget. Throws where
// the other loops alone pass the cap.
uint32_t tree_loop_budget(const GpuSceneShape& shape, const GpuDeviceInfo& device, uint32_t requested);

// The pipelines' specialization for a scene of `shape` whose tree is `depth` deep. The packet walk
// always takes the most registers for its stack, so that its pipeline can be made before the tree
// exists (measured: 16 or 32 registers gave the bunny the same time).
PipelineSpecialization specialization_for(const GpuSceneShape& shape, uint32_t depth, uint32_t loop_budget,
                                          const ShaderVariant& shader);

}  // namespace vkray
