// The shader variants the bench compares (engine/vulkan/shader_variant.hpp): those that must not change a
// single bit (workgroup shape and order, the generic pipeline) do not, and the precision variants
// differ from the defaults where the numerical analysis says they must.
#include "engine/bench/bench.hpp"
#include "engine/bench/bench_suites.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"

#include <cstring>

namespace vkray {
namespace {

Frame render_with(const Scene& scene, const ShaderVariant& shader, PrimitiveSearch search = PrimitiveSearch::automatic) {
  RendererOptions options;
  options.shader = shader;
  options.scene.search = search;
  Renderer renderer(test::device(), scene, options);
  return renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
}

void expect_same_bits(const Frame& expected, const Frame& actual) {
  ASSERT_EQ(expected.depth.size(), actual.depth.size());
  ASSERT_EQ(expected.normal.size(), actual.normal.size());
  size_t differing = 0;
  for (size_t p = 0; p < expected.depth.size(); ++p) {
    differing += std::memcmp(&expected.depth[p], &actual.depth[p], sizeof(float)) != 0 ? 1 : 0;
  }
  for (size_t k = 0; k < expected.normal.size(); ++k) {
    differing += std::memcmp(&expected.normal[k], &actual.normal[k], sizeof(float)) != 0 ? 1 : 0;
  }
  EXPECT_EQ(differing, 0u) << "values differing from the default variant";
}

// Each pixel's ray and tests are the same whatever workgroup computes it, the generic pipeline
// runs the same code with counts read at run time, the tree walk's stack holds the same
// entries in registers as in memory, and storage buffers hold the texels' bits: every bit must
// match (with either edge arithmetic). The workgroup, generic and stack variants walk the tree
// per ray, so they are held to the default shader walking per ray; storage geometry to the default
// as it is (the packet walk where the device favours it). 37x29 leaves partial workgroups on two
// borders; the basic suite covers brute force (the built-in scene's six triangles and one sphere),
// spheres alone, spheres in a tree with a plane, and a mesh in a tree.
TEST(ShaderVariants, LayoutAndGenericVariantsChangeNoBit) {
  ShaderVariant generic, stack_in_memory, storage_geometry, storage_float_edges, float_edges;
  generic.generic = true;
  stack_in_memory.stack_in_registers = false;
  storage_geometry.storage_geometry = true;
  storage_float_edges.storage_geometry = true;
  storage_float_edges.edges = float_edges.edges = EdgeArithmetic::float_error_free;
  const std::vector<std::pair<const char*, ShaderVariant>> variants = {
      {"rows-8x8", with_workgroup(8, 8, false)},
      {"wg-16x16", with_workgroup(16, 16, true)},
      {"wg-64x1", with_workgroup(64, 1, false)},
      {"wg-4x16", with_workgroup(4, 16, false)},
      {"generic", generic},
      {"stack-in-memory", stack_in_memory},
  };
  for (const auto& scene : basic_scenes(37, 29)) {
    SCOPED_TRACE(scene.name);
    const bool tree = choose_search(scene.scene.triangle_count(), scene.scene.spheres.size()) != PrimitiveSearch::brute_force;
    const Frame per_ray = render_with(scene.scene, ShaderVariant{}, tree ? PrimitiveSearch::bvh_per_ray : PrimitiveSearch::automatic);
    for (const auto& [name, shader] : variants) {
      SCOPED_TRACE(name);
      expect_same_bits(per_ray, render_with(scene.scene, shader));
    }
    SCOPED_TRACE("storage-geometry");
    expect_same_bits(render_with(scene.scene, ShaderVariant{}), render_with(scene.scene, storage_geometry));
    SCOPED_TRACE("storage-geometry with float edges");
    expect_same_bits(render_with(scene.scene, float_edges), render_with(scene.scene, storage_float_edges));
  }
}

// Morton order needs a square power-of-two workgroup: anything else is refused, not mis-rendered.
TEST(ShaderVariants, MortonOrderRefusesOtherShapes) {
  const Scene scene = test::sized(default_scene(), 16, 16);
  EXPECT_THROW(render_with(scene, with_workgroup(16, 4, true)), std::invalid_argument);
  EXPECT_THROW(render_with(scene, with_workgroup(32, 32, true)), std::invalid_argument);
}

}  // namespace
}  // namespace vkray
