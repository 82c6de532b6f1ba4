#include "engine/viewer/swapchain.hpp"

#include <algorithm>

namespace vkray {

SwapchainFormat choose_swapchain_format(const VulkanContext& context, vk::SurfaceKHR surface, bool vsync) {
  const auto formats = context.physical_device.getSurfaceFormatsKHR(surface);
  if (formats.empty()) throw GpuError("the window's surface offers no image format");
  SwapchainFormat chosen{formats.front(), vk::PresentModeKHR::eFifo, false};
  const vk::Format preferred[] = {vk::Format::eB8G8R8A8Unorm, vk::Format::eR8G8B8A8Unorm, vk::Format::eB8G8R8A8Srgb,
                                  vk::Format::eR8G8B8A8Srgb};
  const auto found = std::find_first_of(formats.begin(), formats.end(), std::begin(preferred), std::end(preferred),
                                        [](const vk::SurfaceFormatKHR& offered, vk::Format format) {
                                          return offered.format == format;
                                        });
  if (found == formats.end()) throw GpuError("the window's surface offers no 8-bit RGBA or BGRA format");
  chosen.surface_format = *found;
  chosen.bgra = found->format == vk::Format::eB8G8R8A8Unorm || found->format == vk::Format::eB8G8R8A8Srgb;
  if (!vsync) {
    const auto modes = context.physical_device.getSurfacePresentModesKHR(surface);
    for (const auto mode : {vk::PresentModeKHR::eImmediate, vk::PresentModeKHR::eMailbox}) {
      if (std::find(modes.begin(), modes.end(), mode) != modes.end()) {
        chosen.present_mode = mode;
        break;
      }
    }
  }
  return chosen;
}

Swapchain create_swapchain(VulkanContext& context, vk::SurfaceKHR surface, const SwapchainFormat& format,
                           vk::Extent2D wanted, vk::SwapchainKHR old) {
  const auto capabilities = context.physical_device.getSurfaceCapabilitiesKHR(surface);
  Swapchain result;
  // UINT32_MAX: the surface takes the swapchain's size; else it is the window's.
  result.extent = capabilities.currentExtent.width != UINT32_MAX
                      ? capabilities.currentExtent
                      : vk::Extent2D{std::clamp(wanted.width, capabilities.minImageExtent.width, capabilities.maxImageExtent.width),
                                     std::clamp(wanted.height, capabilities.minImageExtent.height,
                                                capabilities.maxImageExtent.height)};
  if (result.extent.width == 0 || result.extent.height == 0) return result;

  const vk::ImageUsageFlags usage = vk::ImageUsageFlagBits::eTransferDst | vk::ImageUsageFlagBits::eColorAttachment |
                                    vk::ImageUsageFlagBits::eTransferSrc;
  if ((capabilities.supportedUsageFlags & usage) != usage) {
    throw GpuError("the window's surface cannot be copied to, drawn on and copied from");
  }
  // One image more than the minimum, so acquiring never waits for the presentation engine.
  result.min_image_count = capabilities.minImageCount + 1;
  if (capabilities.maxImageCount > 0) result.min_image_count = std::min(result.min_image_count, capabilities.maxImageCount);
  const auto alpha = capabilities.supportedCompositeAlpha & vk::CompositeAlphaFlagBitsKHR::eOpaque
                         ? vk::CompositeAlphaFlagBitsKHR::eOpaque
                         : static_cast<vk::CompositeAlphaFlagBitsKHR>(
                               static_cast<uint32_t>(capabilities.supportedCompositeAlpha) &
                               -static_cast<uint32_t>(capabilities.supportedCompositeAlpha));  // lowest bit offered
  result.swapchain = vk::raii::SwapchainKHR(
      context.device,
      vk::SwapchainCreateInfoKHR({}, surface, result.min_image_count, format.surface_format.format,
                                 format.surface_format.colorSpace, result.extent, 1, usage, vk::SharingMode::eExclusive,
                                 {}, capabilities.currentTransform, alpha, format.present_mode, VK_TRUE, old));
  result.images = result.swapchain.getImages();
  for (const vk::Image image : result.images) {
    result.views.emplace_back(context.device,
                              vk::ImageViewCreateInfo({}, image, vk::ImageViewType::e2D, format.surface_format.format, {},
                                                      vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1)));
    result.rendered.emplace_back(context.device, vk::SemaphoreCreateInfo());
  }
  return result;
}

}  // namespace vkray
