// Rendering on the test machine's Vulkan device and checking the frame against the double-precision
// reference within the error envelope (tests/reference_envelope.hpp). Shared by the GPU tests.
#pragma once

#include "engine/renderer.hpp"
#include "tests/reference_envelope.hpp"
#include "tests/test_scenes.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace vkray::test {

inline GpuDevice& device() {
  static GpuDevice gpu;  // fails the test with GpuError when no Vulkan device exists
  return gpu;
}

inline Frame render(const Scene& scene, AovSet aovs = {Aov::depth, Aov::normal}) {
  Renderer renderer(device(), scene);
  return renderer.render(scene.camera, scene.width, scene.height, aovs);
}

// Depth and normals rendered with `shader`.
inline Frame render(const Scene& scene, const ShaderVariant& shader) {
  RendererOptions options;
  options.shader = shader;
  Renderer renderer(device(), scene, options);
  return renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
}

enum class Percentiles { checked, ill_conditioned };

// Every pixel within the envelope derived in reference_envelope.cpp. On ordinary views also the
// acceptance bar of the issue: 99th percentiles of the relative depth error below 1e-5 and of the
// normal error below 0.01 degrees. Views dominated by ill-conditioned pixels are held to the
// envelope alone: there the exact answer moves by more than that within float32's direction
// uncertainty (normals of a sphere 1e5 times smaller than its distance turn by eta * t / r, about
// 0.1 degrees; depth near a curved horizon changes like t * tan(theta) per radian).
inline void expect_frame_matches_reference(const Scene& scene, const Frame& frame,
                                           Percentiles percentiles = Percentiles::checked) {
  const EnvelopeReport report = check_against_reference(scene, frame);
  EXPECT_EQ(report.failures, 0u) << report.describe();
  if (percentiles == Percentiles::checked) {
    EXPECT_LT(report.stats.depth_p99, 1e-5) << report.describe();
    EXPECT_LT(report.stats.normal_deg_p99, 0.01) << report.describe();
  }
  std::printf("    %ux%u: %s\n", scene.width, scene.height, report.stats.summary().c_str());
}

inline void expect_matches_reference(const Scene& scene, Percentiles percentiles = Percentiles::checked) {
  expect_frame_matches_reference(scene, render(scene), percentiles);
}

}  // namespace vkray::test
