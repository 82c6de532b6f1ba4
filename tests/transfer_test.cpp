// The suite runs every GPU test twice (tests/CMakeLists.txt): once as the device chooses, once with
// VKRAY_TRANSFER=staging. This proves the second run really takes the staging path; the setting
// once got lost in a ctest property list and both runs took the direct one unnoticed.
#include "engine/device/gpu_device.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/test_scenes.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
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

// Staging's readback copies each tile's planes on the device straight into the frame's own memory
// where the device imports host memory (lavapipe does, as NVIDIA's driver), and through a host
// buffer and a host copy where it does not (VKRAY_DEVICE_OVERRIDE=no-host-import): both give the
// direct transfer's frame bit for bit, in tiles of an odd width whose planes start anywhere in a
// page, in float and in double.
TEST(StagingReadback, LandsInTheFramesPlanesAsTheDirectTransferReadsThem) {
  const Scene scene = test::sized(default_scene(), 67, 41);
  const AovSet outputs{Aov::depth, Aov::normal, Aov::uv};
  for (const Precision precision : {Precision::float32, Precision::float64}) {
    RendererOptions options;
    options.shader.precision = precision;
    options.max_tile_bytes = 67 * 12 * 5;  // 5 rows of float normals a tile (2 of double normals)
    GpuDevice direct_device({}, TransferMode::direct);
    if (precision == Precision::float64 && !direct_device.info().shader_float64) continue;
    Renderer direct(direct_device, scene, options);
    const Frame expected = direct.render(scene.camera, 67, 41, outputs);
    for (const bool import : {true, false}) {
      SCOPED_TRACE(testing::Message() << (precision == Precision::float64 ? "double" : "float")
                                      << (import ? ", imported" : ", through a host buffer"));
      if (!import) setenv("VKRAY_DEVICE_OVERRIDE", "no-host-import", 1);
      GpuDevice device({}, TransferMode::staging);
      unsetenv("VKRAY_DEVICE_OVERRIDE");
      if (import && device.info().host_import_alignment == 0) {
        // Mesa's lavapipe has had VK_EXT_external_memory_host since 20.x: there it must be taken.
        EXPECT_EQ(device.info().type, "cpu") << device.info().name << " imports no host memory";
        std::printf("    not run here: imported readback (%s has no VK_EXT_external_memory_host)\n", device.info().name.c_str());
        continue;
      }
      Renderer staged(device, scene, options);
      const Frame frame = staged.render(scene.camera, 67, 41, outputs);
      const RenderTimings& timings = staged.timings();
      EXPECT_GE(timings.tiles, 9u);
      const uint64_t plane_bytes = 67 * 41 * (precision == Precision::float64 ? 8 : 4);
      // Depth, three normal planes and two uv planes (float), each copied once; the rest (the list
      // of rays the CPU finishes) through a host buffer.
      const uint64_t frame_bytes = 4 * plane_bytes + 2 * 67 * 41 * 4;
      EXPECT_EQ(timings.readback_in_place_bytes, import ? frame_bytes : 0);
      EXPECT_GE(timings.readback_bytes, frame_bytes);
      for (const auto& [got, want] : {std::pair{&frame.depth, &expected.depth}, {&frame.normal, &expected.normal},
                                      {&frame.uv, &expected.uv}}) {
        ASSERT_EQ(got->size(), want->size());
        if (!got->empty()) {
          EXPECT_EQ(0, std::memcmp(got->data(), want->data(), got->size() * sizeof(float)));
        }
      }
      for (const auto& [got, want] : {std::pair{&frame.depth64, &expected.depth64}, {&frame.normal64, &expected.normal64}}) {
        ASSERT_EQ(got->size(), want->size());  // the double planes: empty for the float shader
        if (!got->empty()) {
          EXPECT_EQ(0, std::memcmp(got->data(), want->data(), got->size() * sizeof(double)));
        }
      }
    }
  }
}

}  // namespace
}  // namespace vkray
