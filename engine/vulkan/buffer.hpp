// Buffers: allocation with a memory-type choice, upload and host access.
#pragma once

#include "engine/vulkan/context.hpp"

namespace vkray {

// Members are destroyed in reverse order: the buffer goes before the memory bound to it.
struct GpuBuffer {
  vk::raii::DeviceMemory memory{nullptr};
  vk::raii::Buffer buffer{nullptr};
  vk::DeviceSize size = 0;
  void* mapped = nullptr;  // set when the memory is host-visible and coherent
};

// A storage buffer in the shaders' memory (shader_memory_required): with TransferMode::direct
// host-visible and mapped, so uploads and readbacks skip the staging copy; with staging
// device-local, never mapped.
GpuBuffer create_storage_buffer(VulkanContext& context, vk::DeviceSize size, vk::BufferUsageFlags extra_usage = {});

// A buffer in device-local memory where the device has it, for `usage`, mapped as storage buffers
// are (for the acceleration structures and the buffers that build them).
GpuBuffer create_device_buffer(VulkanContext& context, vk::DeviceSize size, vk::BufferUsageFlags usage);

// The device address of a buffer made with eShaderDeviceAddress usage.
vk::DeviceAddress device_address(const VulkanContext& context, const GpuBuffer& buffer);

// A host-visible, coherent buffer (cached where possible) to copy results into for reading.
GpuBuffer create_readback_buffer(VulkanContext& context, vk::DeviceSize size);

// A host-visible, coherent buffer the host writes and the device copies from (pixels the CPU
// finished, into a storage image: no staging copy), or reads with `usage` (the planes and the
// preview's ramps, every render).
GpuBuffer create_upload_buffer(VulkanContext& context, vk::DeviceSize size,
                               vk::BufferUsageFlags usage = vk::BufferUsageFlagBits::eTransferSrc);

// A device-local buffer for `usage` holding `bytes` of `data` (through a staging buffer if needed).
GpuBuffer upload_buffer(VulkanContext& context, const void* data, size_t bytes, vk::BufferUsageFlags usage);

// `bytes` of `data` into `target`, a buffer upload_buffer made, from byte `offset` on: a copy where
// it is mapped, else through a staging buffer; every later shader read sees them.
void write_buffer(VulkanContext& context, GpuBuffer& target, const void* data, size_t bytes, size_t offset = 0);

// A view of a uniform texel buffer as texels of `format`: the whole of it, or `range` bytes from
// `offset` (a multiple of minTexelBufferOffsetAlignment).
vk::raii::BufferView create_texel_view(VulkanContext& context, const GpuBuffer& buffer, vk::Format format,
                                       vk::DeviceSize offset = 0, vk::DeviceSize range = VK_WHOLE_SIZE);

}  // namespace vkray
