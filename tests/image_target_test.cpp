// The storage-image target (Renderer::render into an ImageTarget) and the viewer's preview pass
// (PreviewPass): on the device they must give the bytes the host's PNG preview gives from the
// buffer target's Frame, pixel for pixel, on every output and through every path a ray can take
// (tiles, rays the CPU finishes), and the depth range the host would find.
#include "engine/vulkan/image_target.hpp"
#include "engine/io/preview.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/vulkan/context.hpp"
#include "engine/vulkan/preview_pass.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

namespace vkray::test {
namespace {

// The default scene (planes, spheres, triangles) with a 40x40 grid of quads in the tree.
Scene scene_with_tree(uint32_t width, uint32_t height) {
  Scene scene = sized(default_scene(), width, height);
  scene.meshes.push_back(quad_grid({-3, 0.01, -3}, {6, 0, 0}, {0, 0, 6}, 40));
  return scene;
}

size_t differing_pixels(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  if (a.size() != b.size()) return SIZE_MAX;
  size_t differing = 0;
  for (size_t p = 0; p + 2 < a.size(); p += 3) differing += (a[p] != b[p] || a[p + 1] != b[p + 1] || a[p + 2] != b[p + 2]);
  return differing;
}

// Renders every output of `scene` both ways with `options` and compares; returns the image
// renders' unfinished rays and tiles, summed.
std::pair<uint64_t, uint32_t> expect_image_target_matches_buffers(const Scene& scene, const RendererOptions& options) {
  Renderer renderer(device(), scene, options);
  ImageTarget target(device(), scene.width, scene.height);
  PreviewPass preview(device().vulkan());
  uint64_t unfinished = 0;
  uint32_t tiles = 0;
  for (const Aov aov : {Aov::depth, Aov::normal, Aov::uv}) {
    const Frame frame = renderer.render(scene.camera, scene.width, scene.height, AovSet{aov});
    const DepthRange depths = renderer.render(scene.camera, aov, target);
    unfinished += renderer.timings().unfinished_rays;
    tiles += renderer.timings().tiles;
    if (aov == Aov::depth) {
      const DepthRange expected = finite_depth_range(frame);
      EXPECT_EQ(depths.near, expected.near);
      EXPECT_EQ(depths.far, expected.far);
    }
    preview.run(target, aov, depths, false);
    EXPECT_EQ(differing_pixels(preview.read_rgb(), preview_rgb(frame, aov)), 0u)
        << AovSet{aov}.names() << " at " << scene.width << "x" << scene.height;
  }
  return {unfinished, tiles};
}

TEST(ImageTarget, PreviewMatchesTheHostsPixelForPixel) {
  // Sizes that are no multiple of the 8x8 workgroups, wide and tall (the disk touches other borders).
  for (auto [width, height] : {std::pair{97u, 61u}, std::pair{45u, 83u}}) {
    expect_image_target_matches_buffers(sized(default_scene(), width, height), {});
    expect_image_target_matches_buffers(scene_with_tree(width, height), {});
  }
}

// With a budget of a few iterations most rays run out and are finished on the CPU, which writes
// them into the image and folds their depths into the range; a small tile bound splits the image.
TEST(ImageTarget, RaysTheCpuFinishesAndTilesLandInTheImage) {
  const Scene scene = scene_with_tree(64, 48);
  RendererOptions options;
  options.loop_budget = 3;
  options.max_tile_bytes = 64 * 4 * 10;  // the overflow list of 10 rows
  const auto [unfinished, tiles] = expect_image_target_matches_buffers(scene, options);
  EXPECT_GT(unfinished, 2 * 64 * 48 / 4);  // depth and normal: all that hit the grid
  EXPECT_GE(tiles, 3u * 5u);               // 48 rows in tiles of at most 10, for each output
}

// Degenerate depth ranges: a miss everywhere leaves it empty and the picture black; one pixel has
// a single depth, shown at full brightness.
TEST(ImageTarget, EmptyAndSingleDepthRanges) {
  Scene scene;
  scene.spheres.push_back(Sphere{{0, 0, 10}, 1});  // behind the camera, which looks down -z
  for (const uint32_t side : {16u, 1u}) {
    if (side == 1) scene.spheres[0].center.z = -10;  // in front
    scene = sized(scene, side, side);
    Renderer renderer(device(), scene);
    ImageTarget target(device(), side, side);
    PreviewPass preview(device().vulkan());
    const DepthRange depths = renderer.render(scene.camera, Aov::depth, target);
    preview.run(target, Aov::depth, depths, false);
    const std::vector<uint8_t> rgb = preview.read_rgb();
    if (side == 1) {
      EXPECT_EQ(depths.near, depths.far);
      EXPECT_EQ(rgb, std::vector<uint8_t>(3, 255));
    } else {
      EXPECT_EQ(depths.far, 0.0f);
      EXPECT_EQ(rgb, std::vector<uint8_t>(3 * side * side, 0));
    }
    expect_image_target_matches_buffers(scene, {});
  }
}

// BGRA swapchains get blue first.
TEST(ImageTarget, BlueFirstForBgraSwapchains) {
  const Scene scene = sized(default_scene(), 24, 16);
  Renderer renderer(device(), scene);
  ImageTarget target(device(), 24, 16);
  PreviewPass preview(device().vulkan());
  const DepthRange depths = renderer.render(scene.camera, Aov::normal, target);
  preview.run(target, Aov::normal, depths, false);
  std::vector<uint8_t> swapped = preview.read_rgb();
  for (size_t p = 0; p < swapped.size(); p += 3) std::swap(swapped[p], swapped[p + 2]);
  preview.run(target, Aov::normal, depths, true);
  EXPECT_EQ(preview.read_rgb(), swapped);
}

}  // namespace
}  // namespace vkray::test
