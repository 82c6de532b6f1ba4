// Storage images: the viewer's frame, written by compute shaders and copied onto the swapchain.
#pragma once

#include "engine/vulkan/context.hpp"

namespace vkray {

// Members are destroyed in reverse order: the view, then the image, then its memory.
struct GpuImage {
  vk::raii::DeviceMemory memory{nullptr};
  vk::raii::Image image{nullptr};
  vk::raii::ImageView view{nullptr};
  vk::Extent2D extent;
};

inline constexpr vk::ImageSubresourceRange whole_color_image(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);
inline constexpr vk::ImageSubresourceLayers color_layer(vk::ImageAspectFlagBits::eColor, 0, 0, 1);

// A 2D storage image of `format` in device-local memory, with `extra_usage` (transfers), already in
// the GENERAL layout, where shaders read and write it.
GpuImage create_storage_image(VulkanContext& context, vk::Extent2D extent, vk::Format format,
                              vk::ImageUsageFlags extra_usage = {});

// Records a barrier on the whole colour `image`: after `source_access` in `source_stage`, moving
// it from `old_layout` to `new_layout`, before `target_access` in `target_stage`.
void transition_image(const vk::raii::CommandBuffer& commands, vk::Image image, vk::PipelineStageFlags source_stage,
                      vk::AccessFlags source_access, vk::ImageLayout old_layout, vk::PipelineStageFlags target_stage,
                      vk::AccessFlags target_access, vk::ImageLayout new_layout);

}  // namespace vkray
