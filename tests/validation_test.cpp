// The suite runs under the Khronos validation layer (VKRAY_VALIDATION=1, tests/CMakeLists.txt). These
// tests prove the harness catches what it is there for: a misuse of the API and a synchronization
// hazard each abort with the layer's message. They skip when the layer is not installed.
#include "engine/device/gpu_device.hpp"
#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/context.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

namespace vkray {
namespace {

bool validation_layer_installed() {
  vk::raii::Context context(vulkan_loader_entry());
  for (const auto& layer : context.enumerateInstanceLayerProperties()) {
    if (std::string_view(layer.layerName.data()) == "VK_LAYER_KHRONOS_validation") return true;
  }
  return false;
}

class ValidationDeathTest : public testing::Test {
 protected:
  void SetUp() override {
    if (!validation_layer_installed()) GTEST_SKIP() << "the Khronos validation layer is not installed";
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    setenv("VKRAY_VALIDATION", "1", 1);
  }
};

TEST_F(ValidationDeathTest, ApiMisuseAbortsWithTheLayersMessage) {
  EXPECT_DEATH(
      {
        GpuDevice device;
        // A buffer of size 0 is invalid (VUID-VkBufferCreateInfo-size-00912).
        vk::raii::Buffer buffer(device.vulkan().device,
                                vk::BufferCreateInfo({}, 0, vk::BufferUsageFlagBits::eStorageBuffer));
      },
      "Vulkan validation error.*VkBufferCreateInfo-size");
}

TEST_F(ValidationDeathTest, SynchronizationHazardAbortsWithTheLayersMessage) {
  EXPECT_DEATH(
      {
        GpuDevice device;
        VulkanContext& context = device.vulkan();
        const GpuBuffer source = create_storage_buffer(context, 256, vk::BufferUsageFlagBits::eTransferSrc |
                                                                         vk::BufferUsageFlagBits::eTransferDst);
        const GpuBuffer target = create_storage_buffer(context, 256, vk::BufferUsageFlagBits::eTransferDst);
        context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
          commands.fillBuffer(*source.buffer, 0, 256, 1u);
          // No barrier between the fill's write and the copy's read: a read-after-write hazard.
          commands.copyBuffer(*source.buffer, *target.buffer, vk::BufferCopy(0, 0, 256));
        });
      },
      "Vulkan validation error.*SYNC-HAZARD-READ.AFTER.WRITE");
}

}  // namespace
}  // namespace vkray
