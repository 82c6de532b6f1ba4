#include "engine/vulkan/image_target.hpp"

#include "engine/vulkan/image.hpp"

#include <atomic>

namespace vkray {

ImageTarget::ImageTarget(GpuDevice& device, uint32_t width, uint32_t height) : width_(width), height_(height) {
  static std::atomic<uint64_t> targets_made{0};
  id_ = ++targets_made;
  image_ = with_vulkan_errors("making a storage image", [&] {
    return std::make_unique<GpuImage>(create_storage_image(device.vulkan(), vk::Extent2D(width, height),
                                                           vk::Format::eR32G32B32A32Sfloat,
                                                           vk::ImageUsageFlagBits::eTransferDst));
  });
}

ImageTarget::~ImageTarget() = default;

}  // namespace vkray
