// A caller's rays from one origin ordered by direction on the device (shaders/direction_order.comp),
// for the packet walk of rays listed in no order it can use: the host never reads them.
#pragma once

#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/shader_modules.hpp"

#include <array>
#include <optional>

namespace vkray {

class DirectionOrderPass {
 public:
  explicit DirectionOrderPass(VulkanContext& context);

  // The `count` rays that `rays` holds (six doubles a ray as the caller gave them, three RGBA32UI
  // texels) ordered into order() by gpu::direction_key: any 64 consecutive entries point into a small
  // patch of directions. Waits for the device; returns its GPU time in ms (the wall time where the
  // device has no timestamps). Every later submission's shaders see order().
  double run(vk::BufferView rays, uint32_t count);

  // The rays' indices in order, from the last run (VKRAY_BINDING_RAY_ORDER).
  const GpuBuffer& order() const { return order_; }

 private:
  VulkanContext& context_;
  std::optional<ShaderBindings> shader_;
  vk::raii::PipelineLayout layout_{nullptr};
  std::array<vk::raii::Pipeline, 3> pipelines_{nullptr, nullptr, nullptr};  // by VKRAY_ORDER_PASS_*
  GpuBuffer cells_, ranks_, order_;  // grown as the calls need
  vk::raii::QueryPool timestamps_{nullptr};
};

}  // namespace vkray
