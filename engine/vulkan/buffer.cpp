#include "engine/vulkan/buffer.hpp"

#include <cstddef>
#include <cstring>

namespace vkray {
namespace {

// What a buffer is for: the shaders' (mapped only with TransferMode::direct) or the host's (always
// mapped: uploads, readbacks).
enum class Side { device, host };

GpuBuffer create_buffer(VulkanContext& context, vk::DeviceSize size, vk::BufferUsageFlags usage,
                        vk::MemoryPropertyFlags required, vk::MemoryPropertyFlags preferred, Side side) {
  GpuBuffer result;
  result.size = size;
  result.buffer = vk::raii::Buffer(context.device, vk::BufferCreateInfo({}, size, usage));
  const vk::MemoryRequirements requirements = result.buffer.getMemoryRequirements();
  const uint32_t type = find_memory_type(context, requirements.memoryTypeBits, required, preferred);
  // Buffers the device finds by address (acceleration structures and what builds them) need memory
  // allocated for that.
  const vk::MemoryAllocateFlagsInfo addressable(vk::MemoryAllocateFlagBits::eDeviceAddress);
  const bool by_address = static_cast<bool>(usage & vk::BufferUsageFlagBits::eShaderDeviceAddress);
  result.memory = vk::raii::DeviceMemory(context.device,
                                         vk::MemoryAllocateInfo(requirements.size, type, by_address ? &addressable : nullptr));
  result.buffer.bindMemory(*result.memory, 0);
  const bool host_visible = (context.memory_properties.memoryTypes[type].propertyFlags & host_access_flags) == host_access_flags;
  if (host_visible && (side == Side::host || !context.staging)) {
    result.mapped = result.memory.mapMemory(0, VK_WHOLE_SIZE);
  }
  return result;
}

}  // namespace

GpuBuffer create_storage_buffer(VulkanContext& context, vk::DeviceSize size, vk::BufferUsageFlags extra_usage) {
  return create_buffer(context, size, vk::BufferUsageFlagBits::eStorageBuffer | extra_usage,
                       shader_memory_required(context), vk::MemoryPropertyFlagBits::eDeviceLocal, Side::device);
}

vk::DeviceAddress device_address(const VulkanContext& context, const GpuBuffer& buffer) {
  return context.device.getBufferAddress(vk::BufferDeviceAddressInfo(*buffer.buffer));
}

GpuBuffer create_device_buffer(VulkanContext& context, vk::DeviceSize size, vk::BufferUsageFlags usage) {
  return create_buffer(context, size, usage, {}, vk::MemoryPropertyFlagBits::eDeviceLocal, Side::device);
}

GpuBuffer create_readback_buffer(VulkanContext& context, vk::DeviceSize size) {
  return create_buffer(context, size, vk::BufferUsageFlagBits::eTransferDst, host_access_flags,
                       vk::MemoryPropertyFlagBits::eHostCached, Side::host);
}

GpuBuffer create_upload_buffer(VulkanContext& context, vk::DeviceSize size, vk::BufferUsageFlags usage) {
  return create_buffer(context, size, usage, host_access_flags, {}, Side::host);
}

GpuBuffer upload_buffer(VulkanContext& context, const void* data, size_t bytes, vk::BufferUsageFlags usage) {
  GpuBuffer target = create_buffer(context, bytes, usage | vk::BufferUsageFlagBits::eTransferDst,
                                   shader_memory_required(context), vk::MemoryPropertyFlagBits::eDeviceLocal, Side::device);
  write_buffer(context, target, data, bytes);
  return target;
}

void write_buffer(VulkanContext& context, GpuBuffer& target, const void* data, size_t bytes, size_t offset) {
  if (target.mapped) {
    std::memcpy(static_cast<std::byte*>(target.mapped) + offset, data, bytes);
    return;
  }
  GpuBuffer staging = create_buffer(context, bytes, vk::BufferUsageFlagBits::eTransferSrc, host_access_flags, {}, Side::host);
  std::memcpy(staging.mapped, data, bytes);
  context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    commands.copyBuffer(*staging.buffer, *target.buffer, vk::BufferCopy(0, offset, bytes));
    // The copy's writes made available to every later shader read on this queue: a fence wait
    // orders the submissions but makes no device write visible to another stage.
    const vk::MemoryBarrier copied(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eShaderRead);
    commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {}, copied,
                             {}, {});
  });
}

vk::raii::BufferView create_texel_view(VulkanContext& context, const GpuBuffer& buffer, vk::Format format,
                                       vk::DeviceSize offset, vk::DeviceSize range) {
  return vk::raii::BufferView(context.device, vk::BufferViewCreateInfo({}, *buffer.buffer, format, offset, range));
}

}  // namespace vkray
