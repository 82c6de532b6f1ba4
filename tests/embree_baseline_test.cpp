// The Embree baseline traces the same rays as vkray: its answers agree with the double-precision
// reference up to float32 rounding, so the bench compares times of the same work.
#include "engine/reference/compare.hpp"
#include "engine/bench/embree_baseline.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/reference/reference.hpp"
#include "engine/scene/scene_loader.hpp"

#include <gtest/gtest.h>

namespace vkray {
namespace {

// Embree's float32 triangle test is not watertight and its depth carries float32 rounding: hit/miss
// may differ on a pixel whose ray passes within rounding of an edge or silhouette (a handful in a
// few thousand), and depth agrees to float32 precision (the GPU tests' bar: p99 below 1e-5).
void expect_close_to_reference(Scene scene, uint32_t width, uint32_t height) {
  const EmbreeResult embree = trace_with_embree(scene, width, height, 1);
  scene.width = width, scene.height = height;
  const ReferenceScene reference(scene);
  const FrameError error =
      measure_error(embree.frame, render_reference_hits(reference, scene.camera, width, height));
  EXPECT_LE(error.mismatch_fraction(), 0.005) << error.summary();
  EXPECT_GT(error.both_hit, error.pixels / 10) << "the view must show the scene";
  EXPECT_LT(error.depth_p99, 1e-5) << error.summary();
  EXPECT_LT(error.normal_deg_p99, 0.01) << error.summary();
  EXPECT_GT(embree.single.min_ms, 0.0);
  EXPECT_GT(embree.packet.min_ms, 0.0);
}

TEST(EmbreeBaseline, DefaultSceneWithPlaneAndSphere) { expect_close_to_reference(default_scene(), 64, 48); }

TEST(EmbreeBaseline, SphereFieldAndSoup) {
  Scene scene;
  SoupOptions soup;
  soup.triangles = 500;
  scene.meshes.push_back(make_uniform_soup(soup));
  scene.spheres = make_sphere_field(500, 3);
  scene.camera = {{0.3, 0.4, 3.5}, {0, 0, 0}, {0, 1, 0}, 45};
  expect_close_to_reference(scene, 61, 47);
}

}  // namespace
}  // namespace vkray
