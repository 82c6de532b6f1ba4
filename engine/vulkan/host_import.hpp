// Host memory the device copies into where it already lies (VK_EXT_external_memory_host): results
// land in their final place (a frame's planes) with no second copy on the host.
#pragma once

#include "engine/vulkan/buffer.hpp"

#include <optional>

namespace vkray {

// A buffer over the whole pages (of the device's import alignment) that hold a host range, and
// where the range starts in it. The range must outlive the buffer.
struct ImportedHostMemory {
  GpuBuffer buffer;
  vk::DeviceSize offset = 0;
};

// The range [data, data + bytes) imported as a buffer for `usage` (by default a copy's
// destination), or none where the device lacks the extension or refuses the import (the caller
// then copies through its own host-visible memory).
std::optional<ImportedHostMemory> import_host_memory(VulkanContext& context, const void* data, size_t bytes,
                                                     vk::BufferUsageFlags usage = vk::BufferUsageFlagBits::eTransferDst);

}  // namespace vkray
