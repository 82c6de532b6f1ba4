// Vulkan failures as the front ends see them: a lost device is its own error, so a bench stops
// instead of going on to its next row on a device that no longer answers.
#include "engine/vulkan/context.hpp"

#include <gtest/gtest.h>

#include <string>

namespace vkray {
namespace {

TEST(VulkanErrors, ALostDeviceIsDeviceLostErrorWithAdvice) {
  try {
    with_vulkan_errors("rendering", [] { throw vk::DeviceLostError("vkQueueSubmit"); });
    FAIL() << "no error";
  } catch (const DeviceLostError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("rendering: the device was lost", 0), 0u) << message;
    EXPECT_NE(message.find("--device"), std::string::npos) << message;
  }
}

TEST(VulkanErrors, OtherFailuresAreGpuErrorsButNotDeviceLost) {
  try {
    with_vulkan_errors("uploading the scene", [] { throw vk::OutOfDeviceMemoryError("vkAllocateMemory"); });
    FAIL() << "no error";
  } catch (const DeviceLostError&) {
    FAIL() << "out of memory is not a lost device";
  } catch (const GpuError& error) {
    EXPECT_NE(std::string(error.what()).find("out of device memory"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace vkray
