// Showing pictures in the window: the swapchain, the commands that copy the picture (made on the
// device by PreviewPass) onto the acquired image and draw the overlay on top, presentation, and
// reading back what was presented.
// One frame in flight: the renderer waits for its own work anyway, and a viewer that redraws
// only on change gains nothing from a deeper queue.
#pragma once

#include "engine/viewer/swapchain.hpp"
#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/image.hpp"

#include <functional>
#include <optional>

namespace vkray {

class Display {
 public:
  Display(VulkanContext& context, vk::raii::SurfaceKHR surface, bool vsync);
  ~Display();
  Display(const Display&) = delete;
  Display& operator=(const Display&) = delete;

  // Makes the swapchain again for the window's framebuffer size (after a resize, or when present()
  // said so). Its extent is 0 x 0 while the window is minimized.
  void resize(vk::Extent2D window_size);
  vk::Extent2D extent() const { return swapchain_.extent; }
  uint32_t min_image_count() const { return swapchain_.min_image_count; }
  uint32_t image_count() const { return static_cast<uint32_t>(swapchain_.images.size()); }
  // The render pass the overlay draws in: one colour attachment, the swapchain image, kept.
  vk::RenderPass overlay_pass() const { return *overlay_pass_; }

  // Whether swapchain images store blue first: the picture must come in their order.
  bool bgra() const { return format_.bgra; }

  using OverlayDraw = std::function<void(vk::CommandBuffer)>;
  // Shows `picture` (8-bit, in the swapchain's channel order, extent() in size, TRANSFER_SRC_OPTIMAL layout),
  // copied bit for bit, with `overlay` recorded on top inside overlay_pass() when given. With
  // `capture`, also returns what was presented, 8-bit RGB. Returns false when the swapchain is out
  // of date or suboptimal: resize() and draw again.
  bool present(const GpuImage& picture, const OverlayDraw* overlay, std::vector<uint8_t>* capture);

 private:
  VulkanContext& context_;
  vk::raii::SurfaceKHR surface_;
  SwapchainFormat format_;
  Swapchain swapchain_;
  vk::raii::RenderPass overlay_pass_{nullptr};
  std::vector<vk::raii::Framebuffer> framebuffers_;
  vk::raii::CommandPool command_pool_{nullptr};
  vk::raii::CommandBuffer commands_{nullptr};
  vk::raii::Fence done_{nullptr};
  vk::raii::Semaphore acquired_{nullptr};
  std::optional<GpuBuffer> readback_;  // the presented image, for captures
};

}  // namespace vkray
