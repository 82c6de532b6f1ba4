// The overlay: a few lines of text in a corner of the window (timings, the output shown, the
// camera, a reload error), drawn with Dear ImGui (Debian's libimgui-dev, with its GLFW and
// Vulkan backends) on top of the picture. It takes no input.
#pragma once

#include "engine/vulkan/context.hpp"

#include <string>
#include <vector>

struct GLFWwindow;
struct ImGuiContext;

namespace vkray {

class Overlay {
 public:
  // `pass` is the render pass draw() records in; `min_images` and `images` the swapchain's counts.
  Overlay(VulkanContext& context, GLFWwindow* window, vk::RenderPass pass, uint32_t min_images, uint32_t images);
  ~Overlay();
  Overlay(const Overlay&) = delete;
  Overlay& operator=(const Overlay&) = delete;

  void set_min_image_count(uint32_t min_images);
  // Lays out `lines`, then `error` (when not empty) in red, and records their drawing.
  void draw(const std::vector<std::string>& lines, const std::string& error, vk::CommandBuffer commands);

 private:
  vk::raii::DescriptorPool pool_{nullptr};
  ImGuiContext* imgui_ = nullptr;
};

}  // namespace vkray
