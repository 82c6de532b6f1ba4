#include "engine/vulkan/image.hpp"

#include "engine/vulkan/buffer.hpp"

namespace vkray {

void transition_image(const vk::raii::CommandBuffer& commands, vk::Image image, vk::PipelineStageFlags source_stage,
                      vk::AccessFlags source_access, vk::ImageLayout old_layout, vk::PipelineStageFlags target_stage,
                      vk::AccessFlags target_access, vk::ImageLayout new_layout) {
  const vk::ImageMemoryBarrier barrier(source_access, target_access, old_layout, new_layout, VK_QUEUE_FAMILY_IGNORED,
                                       VK_QUEUE_FAMILY_IGNORED, image, whole_color_image);
  commands.pipelineBarrier(source_stage, target_stage, {}, {}, {}, barrier);
}

GpuImage create_storage_image(VulkanContext& context, vk::Extent2D extent, vk::Format format,
                              vk::ImageUsageFlags extra_usage) {
  GpuImage result;
  result.extent = extent;
  const vk::ImageCreateInfo info({}, vk::ImageType::e2D, format, vk::Extent3D(extent, 1), 1, 1,
                                 vk::SampleCountFlagBits::e1, vk::ImageTiling::eOptimal,
                                 vk::ImageUsageFlagBits::eStorage | extra_usage);
  result.image = vk::raii::Image(context.device, info);
  const vk::MemoryRequirements requirements = result.image.getMemoryRequirements();
  const uint32_t type = find_memory_type(context, requirements.memoryTypeBits, {}, vk::MemoryPropertyFlagBits::eDeviceLocal);
  result.memory = vk::raii::DeviceMemory(context.device, vk::MemoryAllocateInfo(requirements.size, type));
  result.image.bindMemory(*result.memory, 0);
  result.view = vk::raii::ImageView(context.device, vk::ImageViewCreateInfo({}, *result.image, vk::ImageViewType::e2D,
                                                                            format, {}, whole_color_image));
  context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    transition_image(commands, *result.image, vk::PipelineStageFlagBits::eTopOfPipe, {}, vk::ImageLayout::eUndefined,
                     vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer,
                     vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eTransferWrite,
                     vk::ImageLayout::eGeneral);
  });
  return result;
}

}  // namespace vkray
