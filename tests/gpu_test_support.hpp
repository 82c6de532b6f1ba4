// Rendering on the test machine's Vulkan device and checking the frame against the double-precision
// reference within the error envelope (engine/reference/envelope.hpp). Shared by the GPU tests.
#pragma once

#include "engine/render/renderer.hpp"
#include "engine/render/search.hpp"
#include "engine/reference/envelope.hpp"
#include "tests/test_scenes.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace vkray::test {

using vkray::check_against_reference;
using vkray::EnvelopeReport;

// A renderer's search and shader variant, and its loop budget where it has one, for a test's trace.
inline std::string variant_name(const RendererOptions& options) {
  const ShaderVariant& shader = options.shader;
  return std::string(traversal_name(options.scene.search)) + (shader.generic ? ", generic" : "") +
         (shader.storage_geometry ? ", storage geometry" : "") + (shader.precision == Precision::float64 ? ", float64" : "") +
         (options.loop_budget ? ", loop budget " + std::to_string(options.loop_budget) : "");
}

inline GpuDevice& device() {
  static GpuDevice gpu;  // fails the test with GpuError when no Vulkan device exists
  return gpu;
}

// Whether the device has ray queries for the ray-query traversal. Where the suite is told it must
// (VKRAY_REQUIRE_RAY_QUERY, which ctest sets) and the device is lavapipe, which has them from the
// Mesa that cmake/install-deps.sh installs (25.0), a device without them fails the test instead of
// leaving the traversal untested. A GPU without them (an H100 has no ray-tracing units) tests the rest.
inline bool ray_queries() {
  const GpuDeviceInfo& info = device().info();
  const bool required = std::getenv("VKRAY_REQUIRE_RAY_QUERY") != nullptr && info.type == "cpu" && info.overridden.empty();
  if (required && !info.ray_query) {
    ADD_FAILURE() << info.name << " (" << info.driver << ") has no ray queries; Mesa 25's lavapipe has them "
                  << "(cmake/install-deps.sh installs it from bookworm-backports)";
  }
  return info.ray_query;
}

// The searches of `wanted` this device runs with `shader`, ray queries among them only where it has
// them (ray_queries()). A GPU refuses the packet walk (it takes double edge functions, which only CPU
// devices choose) and may lack ray queries: each search left out is printed with the device's reason,
// so a GPU run tests everything else instead of failing.
inline std::vector<PrimitiveSearch> runnable(const std::vector<PrimitiveSearch>& wanted, const ShaderVariant& shader = {}) {
  std::vector<PrimitiveSearch> kept;
  for (const PrimitiveSearch search : wanted) {
    if (search == PrimitiveSearch::ray_query && !ray_queries()) {
      std::printf("    not run here: traversal 'ray-query' (%s has no ray queries)\n", device().info().name.c_str());
      continue;
    }
    if (const std::string obstacle = search_obstacle(search, device().info(), shader); !obstacle.empty()) {
      std::printf("    not run here: traversal '%s' (%s)\n", traversal_name(search), obstacle.c_str());
      continue;
    }
    kept.push_back(search);
  }
  return kept;
}

// Options for each search that runs on this device (runnable), with `base`'s: brute force, each
// tree walk and ray queries, or the walks alone.
inline std::vector<RendererOptions> searches_with(const RendererOptions& base = {}, bool walks_alone = false) {
  std::vector<PrimitiveSearch> wanted{PrimitiveSearch::bvh_per_ray, PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query};
  if (!walks_alone) wanted.insert(wanted.begin(), PrimitiveSearch::brute_force);
  std::vector<RendererOptions> walks;
  for (const PrimitiveSearch search : runnable(wanted, base.shader)) {
    RendererOptions options = base;
    options.scene.search = search;
    walks.push_back(options);
  }
  return walks;
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

// Every pixel within the envelope derived in engine/reference/envelope.cpp. On ordinary views also the
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
