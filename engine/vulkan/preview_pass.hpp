// The viewer's picture, made on the device: shaders/preview.comp maps one output in a storage-image
// target to 8-bit RGBA through the PNG preview's ramps (engine/io/preview.hpp), so the bytes are the
// ones `vkray render` writes, and nothing goes through the host.
#pragma once

#include "engine/frame.hpp"
#include "engine/vulkan/image_target.hpp"
#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/image.hpp"
#include "engine/vulkan/shader_modules.hpp"

#include <optional>
#include <vector>

namespace vkray {

class PreviewPass {
 public:
  explicit PreviewPass(VulkanContext& context);

  // Maps `aov` of `values` (as Renderer::render wrote it, with the depth range it returned) into
  // picture(), which takes the size of `values`; blue before red when `bgra`, as such swapchains
  // store it. Waits for the device.
  void run(const ImageTarget& values, Aov aov, DepthRange depths, bool bgra);

  // RGBA8UI, in the TRANSFER_SRC_OPTIMAL layout after run(): the bytes a UNORM swapchain image shows.
  const GpuImage& picture() const { return *picture_; }

  // The picture as 8-bit RGB, 3 bytes a pixel, row-major from the top row (from a run() in RGBA
  // order): for screenshots without a window.
  std::vector<uint8_t> read_rgb();

 private:
  VulkanContext& context_;
  std::optional<ShaderBindings> shader_;  // preview.comp and its descriptor set
  vk::raii::PipelineLayout layout_{nullptr};
  vk::raii::Pipeline pipeline_{nullptr};
  GpuBuffer ramps_;  // GpuPreviewRamps, host-visible: rewritten every run
  std::optional<GpuImage> picture_;
  uint64_t bound_values_ = 0;  // ImageTarget::id the descriptor set points at; 0: none yet
};

}  // namespace vkray
