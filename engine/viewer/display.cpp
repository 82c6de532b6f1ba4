#include "engine/viewer/display.hpp"

#include <cstring>
#include <stdexcept>

namespace vkray {
namespace {

constexpr size_t swapchain_bytes_per_pixel = 4;

vk::raii::RenderPass make_overlay_pass(const vk::raii::Device& device, vk::Format format) {
  // The picture is already in the image (loaded, not cleared); the barriers around the pass
  // (Display::present) order it with the copies, so its layout stays COLOR_ATTACHMENT_OPTIMAL.
  const vk::AttachmentDescription attachment({}, format, vk::SampleCountFlagBits::e1, vk::AttachmentLoadOp::eLoad,
                                             vk::AttachmentStoreOp::eStore, vk::AttachmentLoadOp::eDontCare,
                                             vk::AttachmentStoreOp::eDontCare, vk::ImageLayout::eColorAttachmentOptimal,
                                             vk::ImageLayout::eColorAttachmentOptimal);
  const vk::AttachmentReference reference(0, vk::ImageLayout::eColorAttachmentOptimal);
  const vk::SubpassDescription subpass({}, vk::PipelineBindPoint::eGraphics, {}, reference);
  return vk::raii::RenderPass(device, vk::RenderPassCreateInfo({}, attachment, subpass));
}

}  // namespace

Display::Display(VulkanContext& context, vk::raii::SurfaceKHR surface, bool vsync)
    : context_(context), surface_(std::move(surface)) {
  with_vulkan_errors("opening the window's swapchain", [&] {
    format_ = choose_swapchain_format(context_, *surface_, vsync);
    overlay_pass_ = make_overlay_pass(context_.device, format_.surface_format.format);
    command_pool_ = vk::raii::CommandPool(
        context_.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eTransient, context_.queue_family));
    commands_ = std::move(vk::raii::CommandBuffers(
        context_.device, vk::CommandBufferAllocateInfo(*command_pool_, vk::CommandBufferLevel::ePrimary, 1))[0]);
    done_ = vk::raii::Fence(context_.device, vk::FenceCreateInfo());
    acquired_ = vk::raii::Semaphore(context_.device, vk::SemaphoreCreateInfo());
  });
}

Display::~Display() { context_.queue.waitIdle(); }

void Display::resize(vk::Extent2D window_size) {
  with_vulkan_errors("making the window's swapchain", [&] {
    // The presentation engine may still read the old images.
    context_.queue.waitIdle();
    framebuffers_.clear();
    Swapchain replacement =
        create_swapchain(context_, *surface_, format_, window_size, *swapchain_.swapchain);
    swapchain_ = std::move(replacement);
    if (swapchain_.images.empty()) return;
    for (const auto& view : swapchain_.views) {
      const vk::ImageView attachment = *view;
      framebuffers_.emplace_back(context_.device, vk::FramebufferCreateInfo({}, *overlay_pass_, attachment,
                                                                            swapchain_.extent.width,
                                                                            swapchain_.extent.height, 1));
    }
    const vk::DeviceSize bytes = vk::DeviceSize{swapchain_.extent.width} * swapchain_.extent.height * swapchain_bytes_per_pixel;
    readback_ = create_readback_buffer(context_, bytes);
  });
}

bool Display::present(const GpuImage& picture, const OverlayDraw* overlay, std::vector<uint8_t>* capture) {
  if (swapchain_.images.empty()) return false;
  if (picture.extent != swapchain_.extent) throw std::logic_error("the picture does not match the swapchain's size");
  return with_vulkan_errors("showing a frame", [&] {
    uint32_t index = 0;
    bool current = true;
    try {
      const auto [result, acquired_index] = swapchain_.swapchain.acquireNextImage(UINT64_MAX, *acquired_);
      index = acquired_index;
      current = result == vk::Result::eSuccess;  // suboptimal: still shown, then made again
    } catch (const vk::OutOfDateKHRError&) {
      return false;  // nothing acquired, the semaphore stays unsignaled
    }
    const vk::Image image = swapchain_.images[index];
    const vk::Extent2D extent = swapchain_.extent;

    command_pool_.reset();  // its one command buffer, recorded anew every frame
    commands_.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
    // The submission waits for the acquire at the transfer stage: the first barrier chains to it.
    transition_image(commands_, image, vk::PipelineStageFlagBits::eTransfer, {}, vk::ImageLayout::eUndefined,
                     vk::PipelineStageFlagBits::eTransfer, vk::AccessFlagBits::eTransferWrite,
                     vk::ImageLayout::eTransferDstOptimal);
    // RGBA8UI onto the swapchain's 8-bit UNORM (or sRGB) format: the same 32-bit size class, so the
    // copy moves the bytes unchanged (PreviewPass wrote them in this image's channel order).
    const vk::ImageCopy copy(color_layer, {0, 0, 0}, color_layer, {0, 0, 0}, vk::Extent3D(extent, 1));
    commands_.copyImage(*picture.image, vk::ImageLayout::eTransferSrcOptimal, image, vk::ImageLayout::eTransferDstOptimal, copy);
    vk::PipelineStageFlags last_stage = vk::PipelineStageFlagBits::eTransfer;
    vk::AccessFlags last_access = vk::AccessFlagBits::eTransferWrite;
    vk::ImageLayout layout = vk::ImageLayout::eTransferDstOptimal;
    if (overlay) {
      transition_image(commands_, image, last_stage, last_access, layout, vk::PipelineStageFlagBits::eColorAttachmentOutput,
                       vk::AccessFlagBits::eColorAttachmentRead | vk::AccessFlagBits::eColorAttachmentWrite,
                       vk::ImageLayout::eColorAttachmentOptimal);
      commands_.beginRenderPass(vk::RenderPassBeginInfo(*overlay_pass_, *framebuffers_[index], vk::Rect2D({0, 0}, extent)),
                                vk::SubpassContents::eInline);
      (*overlay)(*commands_);
      commands_.endRenderPass();
      last_stage = vk::PipelineStageFlagBits::eColorAttachmentOutput;
      last_access = vk::AccessFlagBits::eColorAttachmentWrite;
      layout = vk::ImageLayout::eColorAttachmentOptimal;
    }
    if (capture) {
      transition_image(commands_, image, last_stage, last_access, layout, vk::PipelineStageFlagBits::eTransfer,
                       vk::AccessFlagBits::eTransferRead, vk::ImageLayout::eTransferSrcOptimal);
      const vk::BufferImageCopy region(0, 0, 0, color_layer, {0, 0, 0}, vk::Extent3D(extent, 1));
      commands_.copyImageToBuffer(image, vk::ImageLayout::eTransferSrcOptimal, *readback_->buffer, region);
      // A fence wait alone does not make device writes visible to the host.
      const vk::MemoryBarrier to_host(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
      commands_.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, to_host, {},
                                {});
      last_stage = vk::PipelineStageFlagBits::eTransfer;
      last_access = {};
      layout = vk::ImageLayout::eTransferSrcOptimal;
    }
    // Presentation needs no access mask: the semaphore it waits on makes the writes visible.
    transition_image(commands_, image, last_stage, last_access, layout, vk::PipelineStageFlagBits::eBottomOfPipe, {},
                     vk::ImageLayout::ePresentSrcKHR);
    commands_.end();

    const vk::PipelineStageFlags wait_stage = vk::PipelineStageFlagBits::eTransfer;
    const vk::Semaphore wait = *acquired_, signal = *swapchain_.rendered[index];
    const vk::CommandBuffer buffer = *commands_;
    context_.device.resetFences(*done_);
    context_.queue.submit(vk::SubmitInfo(wait, wait_stage, buffer, signal), *done_);
    const vk::SwapchainKHR swapchain = *swapchain_.swapchain;
    try {
      if (context_.queue.presentKHR(vk::PresentInfoKHR(signal, swapchain, index)) != vk::Result::eSuccess) current = false;
    } catch (const vk::OutOfDateKHRError&) {
      current = false;
    }
    if (context_.device.waitForFences(*done_, VK_TRUE, UINT64_MAX) != vk::Result::eSuccess) {
      throw GpuError("waiting for the GPU failed");
    }
    if (capture) {
      const auto* bytes = static_cast<const uint8_t*>(readback_->mapped);
      const size_t pixels = size_t{extent.width} * extent.height;
      const size_t red = format_.bgra ? 2 : 0, blue = format_.bgra ? 0 : 2;
      capture->resize(pixels * 3);
      for (size_t p = 0; p < pixels; ++p) {
        (*capture)[3 * p] = bytes[4 * p + red];
        (*capture)[3 * p + 1] = bytes[4 * p + 1];
        (*capture)[3 * p + 2] = bytes[4 * p + blue];
      }
    }
    return current;
  });
}

}  // namespace vkray
