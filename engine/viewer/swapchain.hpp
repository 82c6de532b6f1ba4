// The window's swapchain: created for the surface's current size, made again when the window is
// resized or the surface reports it out of date.
#pragma once

#include "engine/vulkan/context.hpp"

#include <vector>

namespace vkray {

// What every swapchain of one window shares: chosen once, so a recreated swapchain keeps them.
struct SwapchainFormat {
  vk::SurfaceFormatKHR surface_format;
  vk::PresentModeKHR present_mode;
  // The image's bytes are B, G, R, A (else R, G, B, A): pictures are written in this order.
  bool bgra = false;
};

// An 8-bit UNORM format where the surface has one, so the picture's bytes reach the screen as they
// are (copies never convert); FIFO with vsync, else IMMEDIATE, MAILBOX or FIFO, the first offered.
SwapchainFormat choose_swapchain_format(const VulkanContext& context, vk::SurfaceKHR surface, bool vsync);

struct Swapchain {
  vk::raii::SwapchainKHR swapchain{nullptr};
  vk::Extent2D extent;
  uint32_t min_image_count = 0;
  std::vector<vk::Image> images;
  std::vector<vk::raii::ImageView> views;
  // One per image: presenting it waits for its commands. Per image rather than per frame, as
  // the presentation engine may still hold a frame's semaphore when the next frame signals.
  std::vector<vk::raii::Semaphore> rendered;
};

// A swapchain of `wanted` size (the surface's own size where it fixes one), replacing `old`.
// Images can be copied to (the picture), drawn on (the overlay) and copied from (screenshots).
// Its extent is 0 x 0 while the window is minimized: then nothing is created.
Swapchain create_swapchain(VulkanContext& context, vk::SurfaceKHR surface, const SwapchainFormat& format,
                           vk::Extent2D wanted, vk::SwapchainKHR old);

}  // namespace vkray
