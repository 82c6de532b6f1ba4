// Renderer::set_vertices: a deformed mesh renders as a Renderer made from the deformed scene renders
// it, bit for bit, and within the reference's envelope, in every search the device runs; the tree
// is refitted while every triangle keeps a non-zero area and built anew where one does not; bad
// input leaves the scene as it was.
#include "engine/scene/mesh_generators.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace vkray {
namespace {

using test::device;

constexpr uint32_t width = 96, height = 72;

// A sphere of about 4000 triangles beside a plane-like grid, the camera seeing both.
Scene two_meshes() {
  Scene scene;
  scene.meshes.push_back(make_sphere_mesh(4000, glm::dvec3(0.0), 1.0));
  scene.meshes.push_back(test::quad_grid({-3, -1.5, -3}, {6, 0, 0}, {0, 0, 6}, 8));
  scene.camera = {{0.4, 0.9, 3.6}, {0, 0, 0}, {0, 1, 0}, 50};
  return test::sized(scene, width, height);
}

// Every vertex of mesh 0 moved by up to `fraction` of the mesh's size, each axis, from a fixed seed.
std::vector<glm::dvec3> moved_positions(const Mesh& mesh, double fraction, uint32_t seed) {
  const Box box = test::mesh_bounds(mesh);
  const double size = glm::length(box.upper - box.lower);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> offset(-fraction * size, fraction * size);
  std::vector<glm::dvec3> positions = mesh.positions;
  for (glm::dvec3& p : positions) p += glm::dvec3(offset(random), offset(random), offset(random));
  return positions;
}

void expect_same_frame(const Frame& got, const Frame& want) {
  ASSERT_EQ(got.depth.size(), want.depth.size());
  EXPECT_EQ(0, std::memcmp(got.depth.data(), want.depth.data(), got.depth.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(got.normal.data(), want.normal.data(), got.normal.size() * sizeof(float)));
}

TEST(SetVertices, AMovedMeshRendersAsTheMovedSceneInEverySearch) {
  const Scene scene = two_meshes();
  const AovSet outputs{Aov::depth, Aov::normal};
  for (const PrimitiveSearch search : test::runnable({PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray,
                                                      PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query})) {
    SCOPED_TRACE(testing::Message() << "search " << traversal_name(search));
    RendererOptions options;
    options.scene.search = search;
    Renderer renderer(device(), scene, options);
    const Frame before = renderer.render(scene.camera, width, height, outputs);

    Scene moved = scene;
    moved.meshes[0].positions = moved_positions(scene.meshes[0], 0.01, 7);
    renderer.set_vertices(0, moved.meshes[0].positions);
    const bool has_tree = search == PrimitiveSearch::bvh_per_ray || search == PrimitiveSearch::bvh_packet;
    EXPECT_EQ(renderer.timings().tree_refitted, has_tree);
    EXPECT_GT(renderer.timings().scene_update_ms, 0.0);
    const Frame frame = renderer.render(moved.camera, width, height, outputs);
    test::expect_frame_matches_reference(moved, frame);
    EXPECT_NE(0, std::memcmp(frame.depth.data(), before.depth.data(), frame.depth.size() * sizeof(float)))
        << "the move shows in the image";
    Renderer fresh(device(), moved, options);
    expect_same_frame(frame, fresh.render(moved.camera, width, height, outputs));
    EXPECT_EQ(renderer.scene().meshes[0].positions, moved.meshes[0].positions);

    // A triangle of zero area (its second and third corners on its first) is left out, as a new
    // Renderer leaves it out: the primitives change, and the tree is built anew.
    const auto& corners = moved.meshes[0].triangles[5];
    moved.meshes[0].positions[corners[1]] = moved.meshes[0].positions[corners[0]];
    moved.meshes[0].positions[corners[2]] = moved.meshes[0].positions[corners[0]];
    renderer.set_vertices(0, moved.meshes[0].positions);
    EXPECT_FALSE(renderer.timings().tree_refitted);
    const Frame collapsed = renderer.render(moved.camera, width, height, outputs);
    test::expect_frame_matches_reference(moved, collapsed);
    Renderer fresh_collapsed(device(), moved, options);
    expect_same_frame(collapsed, fresh_collapsed.render(moved.camera, width, height, outputs));
  }
}

TEST(SetVertices, BadInputLeavesTheSceneAsItWas) {
  const Scene scene = two_meshes();
  Renderer renderer(device(), scene);
  const Frame before = renderer.render(scene.camera, width, height, {Aov::depth, Aov::normal});
  std::vector<glm::dvec3> positions = scene.meshes[1].positions;
  EXPECT_THROW(renderer.set_vertices(2, positions), InputError);  // two meshes
  EXPECT_THROW(renderer.set_vertices(0, positions), InputError);  // the grid's count, not the sphere's
  positions[3].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(renderer.set_vertices(1, positions), InputError);
  positions[3].y = 2e15;  // beyond max_coordinate
  EXPECT_THROW(renderer.set_vertices(1, positions), InputError);
  EXPECT_EQ(renderer.scene().meshes[1].positions, scene.meshes[1].positions);
  expect_same_frame(renderer.render(scene.camera, width, height, {Aov::depth, Aov::normal}), before);
}

}  // namespace
}  // namespace vkray
