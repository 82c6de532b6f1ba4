// Vulkan instance, the chosen physical device, a logical device with one compute queue, and
// one-shot command submission. Only engine/ code includes this file.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/vulkan/pipeline_cache.hpp"

#include <vulkan/vulkan_raii.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace vkray {

// What showing images in a window asks of Vulkan (see engine/viewer/window.hpp): the instance
// extensions of its kind of surface, and whether a queue family of a device can present there.
struct PresentationSupport {
  std::vector<const char*> instance_extensions;
  std::function<bool(vk::Instance, vk::PhysicalDevice, uint32_t queue_family)> can_present;
};

struct VulkanContext {
  vk::raii::Context context;
  vk::raii::Instance instance{nullptr};
  // Only under VKRAY_VALIDATION (see create_instance): destroyed after the device, so it sees the
  // device's destruction too.
  vk::raii::DebugUtilsMessengerEXT validation_messenger{nullptr};
  vk::raii::PhysicalDevice physical_device{nullptr};
  GpuDeviceInfo info;
  vk::PhysicalDeviceLimits limits;
  vk::PhysicalDeviceMemoryProperties memory_properties;
  // TransferMode::staging: buffers the shaders use are never mapped, even where their memory is
  // host-visible; data goes through host buffers and device copies (engine/vulkan/buffer.cpp).
  bool staging = false;
  uint32_t queue_family = 0;
  vk::raii::Device device{nullptr};
  vk::raii::Queue queue{nullptr};
  vk::raii::CommandPool command_pool{nullptr};
  vk::raii::CommandBuffer command_buffer{nullptr};
  vk::raii::Fence fence{nullptr};
  // Every pipeline is made with it, and saves it (engine/vulkan/pipeline_cache.hpp).
  std::unique_ptr<PipelineCache> pipeline_cache;

  // Records commands into the context's command buffer, submits them and waits for completion.
  void submit_and_wait(const std::function<void(const vk::raii::CommandBuffer&)>& record);
};

// What went wrong, in words, with the advice that fits: out of memory, a lost device, or Vulkan's
// own text for the rest.
std::string describe_vulkan_failure(const vk::SystemError& error);

// Runs `body`, turning Vulkan's exceptions into GpuError with `what` as context.
template <typename Body>
auto with_vulkan_errors(const char* what, Body&& body) {
  try {
    return body();
  } catch (const vk::SystemError& error) {
    const std::string message = std::string(what) + ": " + describe_vulkan_failure(error);
    if (static_cast<vk::Result>(error.code().value()) == vk::Result::eErrorDeviceLost) throw DeviceLostError(message);
    throw GpuError(message);
  }
}

}  // namespace vkray
