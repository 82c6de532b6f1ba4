// The suite runs every GPU test twice (tests/CMakeLists.txt): once as the device chooses, once with
// VKRAY_TRANSFER=staging. This proves the second run really takes the staging path; the setting
// once got lost in a ctest property list and both runs took the direct one unnoticed.
#include "engine/device/gpu_device.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string_view>

namespace vkray {
namespace {

TEST(TransferSetting, TheEnvironmentAndExplicitChoicesAreTaken) {
  const char* forced = std::getenv("VKRAY_TRANSFER");
  if (forced && std::string_view(forced) == "staging") {
    EXPECT_EQ(GpuDevice().transfer(), TransferMode::staging);
  } else {
    EXPECT_EQ(GpuDevice({}, TransferMode::staging).transfer(), TransferMode::staging);
    EXPECT_EQ(GpuDevice({}, TransferMode::direct).transfer(), TransferMode::direct);
  }
}

}  // namespace
}  // namespace vkray
