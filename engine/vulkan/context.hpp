// Vulkan instance, the chosen physical device, a logical device with one compute queue, and
// one-shot command submission. Only engine/ code includes this file.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/vulkan/loader.hpp"
#include "engine/vulkan/pipeline_cache.hpp"

#include <vulkan/vulkan_raii.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace vkray {

// Memory the host maps and reads or writes without flushing: what direct transfers and staging need.
inline constexpr vk::MemoryPropertyFlags host_access_flags =
    vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;

// What showing images in a window asks of Vulkan (see engine/viewer/window.hpp): the instance
// extensions of its kind of surface, and whether a queue family of a device can present there.
struct PresentationSupport {
  std::vector<const char*> instance_extensions;
  std::function<bool(vk::Instance, vk::PhysicalDevice, uint32_t queue_family)> can_present;
};

// The longest vkray waits for one submission: a headless GPU has no watchdog, so a shader that
// never ends would hang the run. A submission is one dispatch (at most RendererOptions'
// dispatch budget, 200 ms by default, measured as it runs), an upload or a structure build; a
// minute is far past any of them, also under the sanitizers on lavapipe.
inline constexpr uint64_t default_fence_timeout_ms = 60'000;

// VKRAY_FENCE_TIMEOUT_MS, in ns, or the default; throws GpuError for anything but a whole number >= 1.
uint64_t fence_timeout_from_environment();

struct VulkanContext {
  vk::raii::Context context{vulkan_loader_entry()};
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
  // The memory type buffers the shaders use take, in words (see describe_memory_type).
  std::string shader_memory;
  uint32_t queue_family = 0;
  vk::raii::Device device{nullptr};
  vk::raii::Queue queue{nullptr};
  vk::raii::CommandPool command_pool{nullptr};
  vk::raii::CommandBuffer command_buffer{nullptr};
  vk::raii::Fence fence{nullptr};
  // How long submit_and_wait waits for the device (default_fence_timeout_ms, or VKRAY_FENCE_TIMEOUT_MS);
  // once it has waited in vain, the device is treated as lost.
  uint64_t fence_timeout_ns = default_fence_timeout_ms * 1'000'000;
  bool timed_out = false;
  // Every pipeline is made with it, and saves it (engine/vulkan/pipeline_cache.hpp).
  std::unique_ptr<PipelineCache> pipeline_cache;

  // Records commands into the context's command buffer, submits them and waits for completion, at
  // most fence_timeout_ns: past it, DeviceLostError.
  void submit_and_wait(const std::function<void(const vk::raii::CommandBuffer&)>& record);
  // Throws DeviceLostError once a submission has timed out.
  void check_usable() const;
};

// First memory type allowed by `type_bits` with all `required` flags, preferring one that also has
// all `preferred` flags. Throws GpuError where none has the required ones.
uint32_t find_memory_type(const VulkanContext& context, uint32_t type_bits, vk::MemoryPropertyFlags required,
                          vk::MemoryPropertyFlags preferred);

// What the memory of the buffers the shaders use must have: host-visible and coherent with
// TransferMode::direct (mapped: the host reads and writes it), nothing with staging. Device-local is
// preferred either way.
vk::MemoryPropertyFlags shader_memory_required(const VulkanContext& context);

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
