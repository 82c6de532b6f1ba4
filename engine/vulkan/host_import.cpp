#include "engine/vulkan/host_import.hpp"

#include <cstdint>

namespace vkray {

std::optional<ImportedHostMemory> import_host_memory(VulkanContext& context, const void* data, size_t bytes,
                                                     vk::BufferUsageFlags usage) {
  const vk::DeviceSize alignment = context.info.host_import_alignment;
  if (alignment == 0 || bytes == 0) return std::nullopt;
  // The import takes whole aligned blocks: those holding the range are mapped memory of this
  // process (the range's own pages), and the device writes only where it is told to (a copy, or
  // a shader's writes at the caller's indices). A range the caller only gives to read is imported
  // as writable memory all the same (the extension has no read-only import); nothing writes it.
  const auto address = reinterpret_cast<uintptr_t>(data);
  const uintptr_t first = address / alignment * alignment;
  const vk::DeviceSize size = (address + bytes - first + alignment - 1) / alignment * alignment;
  void* const base = reinterpret_cast<void*>(first);
  constexpr auto handle = vk::ExternalMemoryHandleTypeFlagBits::eHostAllocationEXT;
  try {
    ImportedHostMemory imported;
    imported.offset = address - first;
    imported.buffer.size = size;
    const vk::ExternalMemoryBufferCreateInfo external(handle);
    imported.buffer.buffer = vk::raii::Buffer(
        context.device,
        vk::BufferCreateInfo({}, size, usage, vk::SharingMode::eExclusive, {}, &external));
    const vk::MemoryRequirements requirements = imported.buffer.buffer.getMemoryRequirements();
    if (requirements.size > size) return std::nullopt;
    const uint32_t type_bits =
        context.device.getMemoryHostPointerPropertiesEXT(handle, base).memoryTypeBits & requirements.memoryTypeBits;
    // Coherent, so that the fence wait alone (with the copy's host-read barrier) makes the writes visible.
    const uint32_t type = find_memory_type(context, type_bits, host_access_flags, vk::MemoryPropertyFlagBits::eHostCached);
    const vk::ImportMemoryHostPointerInfoEXT host_pointer(handle, base);
    imported.buffer.memory = vk::raii::DeviceMemory(context.device, vk::MemoryAllocateInfo(size, type, &host_pointer));
    imported.buffer.buffer.bindMemory(*imported.buffer.memory, 0);
    return imported;
  } catch (const vk::SystemError&) {
    return std::nullopt;  // e.g. memory the driver cannot pin
  } catch (const GpuError&) {
    return std::nullopt;  // no coherent memory type takes it
  }
}

}  // namespace vkray
