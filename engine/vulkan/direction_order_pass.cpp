#include "engine/vulkan/direction_order_pass.hpp"

#include "engine/stopwatch.hpp"
#include "shaders/gpu_layout.h"

#include <algorithm>
#include <bit>

namespace vkray {
namespace {

// Bits a side of the keys' cells for `count` rays: about one cell for one to four rays (4^bits
// cells), so that a packet's 64 rays of a whole sphere of directions fall in a few neighbouring
// cells, and a narrow sensor's (a few percent of the map) in one or two, of 0.35 degrees at most: rays
// of one cell keep no order among themselves. At most 4^9 cells, 1 MiB of counts: a million rays'
// atomic counts into 4^10 (4 MiB) took lavapipe 35 ms against 21 (the bunny's sphere of directions).
uint32_t key_bits(uint32_t count) {
  return std::clamp<uint32_t>(static_cast<uint32_t>(std::bit_width(count)) / 2, 4, VKRAY_ORDER_MAX_BITS);
}

}  // namespace

DirectionOrderPass::DirectionOrderPass(VulkanContext& context) : context_(context) {
  with_vulkan_errors("making the ray-ordering pipelines", [&] {
    shader_.emplace(context_.device, embedded_shader("direction_order.comp", {}));
    const vk::PushConstantRange push_range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(gpu::DirectionOrderParams));
    const vk::DescriptorSetLayout set_layout = *shader_->layout;
    layout_ = vk::raii::PipelineLayout(context_.device, vk::PipelineLayoutCreateInfo({}, set_layout, push_range));
    for (uint32_t pass = 0; pass < pipelines_.size(); ++pass) {
      const vk::SpecializationMapEntry entry(0, 0, sizeof(uint32_t));
      const vk::SpecializationInfo specialization(entry, vk::ArrayProxyNoTemporaries<const uint32_t>(pass));
      const vk::PipelineShaderStageCreateInfo stage({}, vk::ShaderStageFlagBits::eCompute, *shader_->module, "main",
                                                    &specialization);
      pipelines_[pass] = vk::raii::Pipeline(context_.device, context_.pipeline_cache->handle(),
                                            vk::ComputePipelineCreateInfo({}, stage, *layout_));
    }
    context_.pipeline_cache->save();
    if (context_.info.timestamp_period_ns > 0.0) {
      timestamps_ = vk::raii::QueryPool(context_.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 2));
    }
  });
}

double DirectionOrderPass::run(vk::BufferView rays, uint32_t count) {
  const uint32_t bits = key_bits(count);
  const uint32_t keys = 1u << (2 * bits);
  auto at_least = [&](GpuBuffer& buffer, vk::DeviceSize bytes, vk::BufferUsageFlags usage) {
    if (buffer.size < bytes) buffer = create_storage_buffer(context_, bytes, usage);
  };
  at_least(cells_, vk::DeviceSize{keys} * sizeof(uint32_t), vk::BufferUsageFlagBits::eTransferDst);
  at_least(ranks_, vk::DeviceSize{count} * 2 * sizeof(uint32_t), {});
  at_least(order_, vk::DeviceSize{count} * sizeof(uint32_t), {});
  const vk::DescriptorBufferInfo cells(*cells_.buffer, 0, VK_WHOLE_SIZE), ranks(*ranks_.buffer, 0, VK_WHOLE_SIZE),
      order(*order_.buffer, 0, VK_WHOLE_SIZE);
  auto binding = [&](uint32_t index) { return vk::WriteDescriptorSet(*shader_->set, index, 0, 1, shader_->types.at(index)); };
  const std::array writes{binding(VKRAY_ORDER_BINDING_RAYS).setPTexelBufferView(&rays),
                          binding(VKRAY_ORDER_BINDING_CELLS).setPBufferInfo(&cells),
                          binding(VKRAY_ORDER_BINDING_RANKS).setPBufferInfo(&ranks),
                          binding(VKRAY_ORDER_BINDING_ORDER).setPBufferInfo(&order)};
  context_.device.updateDescriptorSets(writes, {});

  // One invocation a ray, in rows of at most the device's workgroup count.
  const uint32_t groups = (count + VKRAY_ORDER_GROUP_SIZE - 1) / VKRAY_ORDER_GROUP_SIZE;
  const uint32_t columns = std::min(groups, context_.limits.maxComputeWorkGroupCount[0]);
  const uint32_t rows = (groups + columns - 1) / columns;
  const gpu::DirectionOrderParams params{glm::uvec4(count, bits, keys, 0u)};
  const auto start = Clock::now();
  context_.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    if (*timestamps_) {
      commands.resetQueryPool(*timestamps_, 0, 2);
      commands.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *timestamps_, 0);
    }
    commands.fillBuffer(*cells_.buffer, 0, vk::DeviceSize{keys} * sizeof(uint32_t), 0u);
    const vk::MemoryBarrier cleared(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
    commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {}, cleared, {}, {});
    // Each pass reads what the one before wrote; the last barrier orders the walks of later
    // submissions after the order is written.
    const vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite, vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
    commands.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *layout_, 0, {*shader_->set}, {});
    commands.pushConstants<gpu::DirectionOrderParams>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, params);
    for (uint32_t pass : {VKRAY_ORDER_PASS_COUNT, VKRAY_ORDER_PASS_SCAN, VKRAY_ORDER_PASS_PLACE}) {
      commands.bindPipeline(vk::PipelineBindPoint::eCompute, *pipelines_[pass]);
      if (pass == VKRAY_ORDER_PASS_SCAN) commands.dispatch(1, 1, 1);
      else commands.dispatch(columns, rows, 1);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader, vk::PipelineStageFlagBits::eComputeShader, {},
                               written, {}, {});
    }
    if (*timestamps_) commands.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *timestamps_, 1);
  });
  if (!*timestamps_) return elapsed_ms(start);
  const auto [result, ticks] = timestamps_.getResults<uint64_t>(0, 2, 2 * sizeof(uint64_t), sizeof(uint64_t),
                                                                vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
  return static_cast<double>(ticks[1] - ticks[0]) * context_.info.timestamp_period_ns * 1e-6;
}

}  // namespace vkray
