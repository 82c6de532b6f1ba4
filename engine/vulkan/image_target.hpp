// The render core's storage-image target, beside its buffer target (Frame): one output of a render
// left on the device in an RGBA32F storage image (depth in r, the normal in rgb, uv in rg) for
// another compute pass to read, such as the viewer's preview (engine/vulkan/preview_pass.hpp).
// Nothing is read back. No Vulkan type appears here: the CLI never touches Vulkan.
#pragma once

#include "engine/device/gpu_device.hpp"

#include <cstdint>
#include <memory>

namespace vkray {

struct GpuImage;  // engine/vulkan/image.hpp

class ImageTarget {
 public:
  ImageTarget(GpuDevice& device, uint32_t width, uint32_t height);
  ~ImageTarget();
  ImageTarget(const ImageTarget&) = delete;
  ImageTarget& operator=(const ImageTarget&) = delete;

  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  // Tells targets apart for the descriptor sets that point at them (a destroyed image's handle may
  // come back for the next one).
  uint64_t id() const { return id_; }
  // In the GENERAL layout between renders; the render writes it with the compute shader and, for
  // rays the CPU finishes, with transfers.
  const GpuImage& image() const { return *image_; }

 private:
  uint32_t width_, height_;
  uint64_t id_;
  std::unique_ptr<GpuImage> image_;
};

}  // namespace vkray
