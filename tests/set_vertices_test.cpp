// Renderer::set_vertices: a deformed mesh renders as a Renderer made from the deformed scene renders
// it, bit for bit, and within the reference's envelope, in every search the device runs; the tree
// is refitted while every triangle keeps a non-zero area and built anew where one does not; bad
// input leaves the scene as it was.
#include "engine/scene/mesh_generators.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <tuple>

namespace vkray {
namespace {

using test::device;

constexpr uint32_t width = 96, height = 72;

// A sphere of about 4000 triangles above a grid, a plane below both, the camera seeing all three.
Scene two_meshes() {
  Scene scene;
  scene.meshes.push_back(make_sphere_mesh(4000, glm::dvec3(0.0), 1.0));
  scene.meshes.push_back(test::quad_grid({-3, -1.5, -3}, {6, 0, 0}, {0, 0, 6}, 8));
  scene.planes.push_back({{0.0, -2.0, 0.0}, {0.0, 1.0, 0.0}});
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

// Rays from origins of their own (each walks alone, and reads the planes' offsets from the anchor)
// toward the sphere, the grid and the plane beyond the grid's edge.
std::vector<GivenRay> rays_from_above() {
  std::mt19937_64 random(9);
  std::uniform_real_distribution<double> spread(-1.0, 1.0);
  std::vector<GivenRay> rays;
  for (int k = 0; k < 2048; ++k) {
    rays.push_back({2.0 * spread(random), 3.0 + spread(random), 2.0 * spread(random), 2.0 * spread(random), -1.0, 2.0 * spread(random)});
  }
  return rays;
}

void expect_same_hits(const RayHits& got, const RayHits& want) {
  EXPECT_EQ(got.t, want.t);
  EXPECT_EQ(got.normal, want.normal);
  EXPECT_EQ(got.object, want.object);
  EXPECT_EQ(got.primitive, want.primitive);
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

    // Later moves refit in place (the arrays the first one kept, written into the same buffers):
    // still what a Renderer made from the moved scene renders. The grid (mesh 1) moves as well.
    for (uint32_t seed : {11u, 13u}) {
      moved.meshes[0].positions = moved_positions(scene.meshes[0], 0.01, seed);
      moved.meshes[1].positions = moved_positions(scene.meshes[1], 0.002, seed);
      renderer.set_vertices(0, moved.meshes[0].positions);
      renderer.set_vertices(1, moved.meshes[1].positions);
      EXPECT_EQ(renderer.timings().tree_refitted, has_tree);
      const Frame again = renderer.render(moved.camera, width, height, outputs);
      Renderer fresh_again(device(), moved, options);
      expect_same_frame(again, fresh_again.render(moved.camera, width, height, outputs));
      expect_same_hits(renderer.cast_rays(rays_from_above()), fresh_again.cast_rays(rays_from_above()));
    }

    // A triangle of zero area (its corners on one line along x, so exactly: they share y and z) is
    // left out, as a new Renderer leaves it out: the primitives change, and the tree is built anew.
    const auto& corners = moved.meshes[0].triangles[5];
    const glm::dvec3 first = moved.meshes[0].positions[corners[0]];
    moved.meshes[0].positions[corners[1]] = first + glm::dvec3(0.01, 0.0, 0.0);
    moved.meshes[0].positions[corners[2]] = first + glm::dvec3(0.02, 0.0, 0.0);
    renderer.set_vertices(0, moved.meshes[0].positions);
    EXPECT_FALSE(renderer.timings().tree_refitted);
    const Frame collapsed = renderer.render(moved.camera, width, height, outputs);
    test::expect_frame_matches_reference(moved, collapsed);
    Renderer fresh_collapsed(device(), moved, options);
    expect_same_frame(collapsed, fresh_collapsed.render(moved.camera, width, height, outputs));
    // And opened again: the triangle is back, and the tree built anew once more.
    moved.meshes[0].positions = moved_positions(scene.meshes[0], 0.01, 17);
    renderer.set_vertices(0, moved.meshes[0].positions);
    EXPECT_FALSE(renderer.timings().tree_refitted);
    const Frame reopened = renderer.render(moved.camera, width, height, outputs);
    Renderer fresh_reopened(device(), moved, options);
    expect_same_frame(reopened, fresh_reopened.render(moved.camera, width, height, outputs));
  }
}

// Two vertices at one position share one stored vertex. Moved together they still do (the second
// move refits in place); moved apart, they cannot, and the scene is converted anew: either way it
// renders as a Renderer made from the moved scene (which shares what coincides).
TEST(SetVertices, VerticesThatSharedAPositionMovedApart) {
  Scene scene = two_meshes();
  Mesh& sphere = scene.meshes[0];
  // The triangle the camera looks at most directly: its first corner gets a vertex of its own.
  const glm::dvec3 toward_eye = glm::normalize(scene.camera.from);
  size_t facing = 0;
  auto facing_by = [&](size_t t) {
    const auto& corners = sphere.triangles[t];
    return glm::dot(sphere.positions[corners[0]] + sphere.positions[corners[1]] + sphere.positions[corners[2]], toward_eye);
  };
  for (size_t t = 1; t < sphere.triangles.size(); ++t) facing = facing_by(t) > facing_by(facing) ? t : facing;
  const uint32_t original = sphere.triangles[facing][0], copy = static_cast<uint32_t>(sphere.positions.size());
  sphere.positions.push_back(sphere.positions[original]);  // a second vertex at the same place
  sphere.triangles[facing][0] = copy;
  Renderer renderer(device(), scene);
  for (const auto& [seed, apart] : {std::pair{3u, 0.0}, {5u, 0.0}, {7u, 0.1}}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed << ", apart " << apart);
    Scene moved = scene;
    moved.meshes[0].positions = moved_positions(sphere, 0.005, seed);
    moved.meshes[0].positions[copy] = moved.meshes[0].positions[original] + apart * toward_eye;  // a spike toward the camera
    renderer.set_vertices(0, moved.meshes[0].positions);
    const Frame frame = renderer.render(moved.camera, width, height, {Aov::depth, Aov::normal});
    test::expect_frame_matches_reference(moved, frame);
    Renderer fresh(device(), moved);
    expect_same_frame(frame, fresh.render(moved.camera, width, height, {Aov::depth, Aov::normal}));
  }
}

// The float64 shader stores positions from the world origin and two texels a normal: its refits in
// place too render what a Renderer made from the moved scene renders.
TEST(SetVertices, InDoublePrecision) {
  if (!device().info().shader_float64) {
    std::printf("    not run here: %s has no shaderFloat64\n", device().info().name.c_str());
    return;
  }
  const Scene scene = two_meshes();
  RendererOptions options;
  options.shader.precision = Precision::float64;
  Renderer renderer(device(), scene, options);
  Scene moved = scene;
  for (uint32_t seed : {21u, 23u}) {  // the second refits in place
    moved.meshes[0].positions = moved_positions(scene.meshes[0], 0.01, seed);
    renderer.set_vertices(0, moved.meshes[0].positions);
    EXPECT_TRUE(renderer.timings().tree_refitted);
  }
  Renderer fresh(device(), moved, options);
  const Frame frame = renderer.render(moved.camera, width, height, {Aov::depth, Aov::normal});
  const Frame expected = fresh.render(moved.camera, width, height, {Aov::depth, Aov::normal});
  ASSERT_EQ(frame.depth64.size(), size_t{width} * height);
  EXPECT_EQ(frame.depth64, expected.depth64);
  EXPECT_EQ(frame.normal64, expected.normal64);
  expect_same_hits(renderer.cast_rays(rays_from_above()), fresh.cast_rays(rays_from_above()));
}

// two_meshes() with two small triangles at opposite corners, out of the camera's view: they hold the
// scene's box (and its centre, the anchor every stored position is relative to) while the sphere
// and the grid move within it.
Scene boxed_meshes() {
  Scene scene = two_meshes();
  Mesh corners;
  corners.positions = {{-6, -3, -6}, {-5.9, -3, -6}, {-6, -3, -5.9}, {6, 3, 6}, {5.9, 3, 6}, {6, 3, 5.9}};
  corners.triangles = {{0, 1, 2}, {3, 4, 5}};
  scene.meshes.push_back(corners);
  return scene;
}

// The sphere turned about y by `angle` and carried by `offset`, then jittered (moved_positions).
std::vector<glm::dvec3> carried(const Mesh& mesh, double angle, glm::dvec3 offset, uint32_t seed) {
  std::vector<glm::dvec3> positions = moved_positions(mesh, 0.002, seed);
  for (glm::dvec3& p : positions) {
    p = glm::dvec3(std::cos(angle) * p.x + std::sin(angle) * p.z, p.y, -std::sin(angle) * p.x + std::cos(angle) * p.z) + offset;
  }
  return positions;
}

// Where the anchor stays, refit_in_place redoes only the moved mesh's vertices, slots and the nodes
// above them, and leaves the arrays as make_gpu_scene leaves them with the same tree, bit for bit;
// where the anchor moves, everything.
TEST(SetVertices, OneMeshMovedWithinTheScenesBoxIsRedoneAlone) {
  Scene scene = boxed_meshes();
  for (int k = 0; k < 12; ++k) {  // more than are tested apart: the tree holds them beside the triangles
    scene.spheres.push_back({{-2.5 + 0.4 * k, -1.0, -2.5}, 0.15});
  }
  GpuSceneOptions options;
  options.search = PrimitiveSearch::bvh_per_ray;
  const ShaderVariant shader;
  GpuScene gpu = make_gpu_scene(scene, options, shader);
  const GpuScene built = gpu;  // its tree and slots, for the conversions compared with
  Scene moved = scene;
  struct Move {
    uint32_t mesh;
    std::vector<glm::dvec3> positions;
    bool one_mesh;
  };
  const std::vector<Move> moves{
      {0, carried(scene.meshes[0], 0.3, {0.2, 0.1, 0.0}, 31), false},   // the first call makes what the next ones keep
      {0, carried(scene.meshes[0], 0.9, {-0.4, 0.0, 0.3}, 37), true},
      {1, moved_positions(scene.meshes[1], 0.002, 41), true},
      {0, carried(scene.meshes[0], 1.5, {0.1, -0.2, -0.3}, 43), true},
      {2, {{-7, -3, -6}, {-5.9, -3, -6}, {-6, -3, -5.9}, {6, 3, 6}, {5.9, 3, 6}, {6, 3, 5.9}}, false},  // the box grows
  };
  for (size_t k = 0; k < moves.size(); ++k) {
    SCOPED_TRACE(testing::Message() << "move " << k << " (mesh " << moves[k].mesh << ")");
    moved.meshes[moves[k].mesh].positions = moves[k].positions;
    const SceneExtent extent = scene_extent(moved);
    ASSERT_TRUE(refit_in_place(gpu, moved, shader, extent, moves[k].mesh));
    EXPECT_EQ(gpu.rewritten.mesh_alone, moves[k].one_mesh);
    const GpuScene want = make_gpu_scene(moved, options, shader, extent, RefitSource{*built.tree, built.hit_sources});
    ASSERT_TRUE(want.refitted);
    EXPECT_EQ(gpu.anchor, want.anchor);
    EXPECT_EQ(gpu.radius, want.radius);
    auto same_bytes = [](const auto& got, const auto& expected) {
      return got.size() == expected.size() && std::memcmp(got.data(), expected.data(), got.size() * sizeof(got[0])) == 0;
    };
    // Each slot's record with its corners' stored points (the vertex buffer keeps its former order in
    // a refit, where a conversion numbers the vertices as the moved triangles first name them).
    auto corners = [](const GpuScene& g) {
      std::vector<std::array<gpu::GpuPoint, 3>> points;
      for (const gpu::GpuPrimitive& record : g.primitives) {
        const bool sphere = (record.indices.w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_SPHERE;  // its centre and radius alone
        points.push_back({g.vertices[record.indices.x], sphere ? gpu::GpuPoint{} : g.vertices[record.indices.y],
                          sphere ? gpu::GpuPoint{} : g.vertices[record.indices.z]});
      }
      return points;
    };
    EXPECT_TRUE(same_bytes(corners(gpu), corners(want)));
    EXPECT_TRUE(same_bytes(gpu.normal_texels, want.normal_texels));
    EXPECT_TRUE(same_bytes(gpu.bvh_nodes, want.bvh_nodes));
    EXPECT_TRUE(same_bytes(gpu.planes, want.planes));
    if (moves[k].one_mesh) {  // the rewritten slots begin and end with the mesh's
      ASSERT_FALSE(gpu.rewritten.slots.empty());
      EXPECT_EQ(gpu.hit_sources.slots[gpu.rewritten.slots.first].object, moves[k].mesh);
      EXPECT_EQ(gpu.hit_sources.slots[gpu.rewritten.slots.end - 1].object, moves[k].mesh);
    }
  }
  // A triangle of the moved mesh collapsed on the one-mesh path: the tree cannot keep its shape.
  moved.meshes[0].positions = carried(scene.meshes[0], 0.2, {0.0, 0.1, 0.0}, 47);
  ASSERT_TRUE(refit_in_place(gpu, moved, shader, scene_extent(moved), 0));
  const auto& collapsed = moved.meshes[0].triangles[3];
  moved.meshes[0].positions[collapsed[1]] = moved.meshes[0].positions[collapsed[2]] = moved.meshes[0].positions[collapsed[0]];
  EXPECT_FALSE(refit_in_place(gpu, moved, shader, scene_extent(moved), 0));
}

// A mesh with a vertex at a position another mesh's vertex has (stored once, shared): moving it
// redoes the whole scene, which checks that the shared position still coincides.
TEST(SetVertices, AMeshSharingAStoredVertexIsNotRedoneAlone) {
  Scene scene = boxed_meshes();
  Mesh touching;  // a triangle with a corner on a vertex of the grid
  const glm::dvec3 shared = scene.meshes[1].positions[10];
  touching.positions = {shared, shared + glm::dvec3(0.3, 0.2, 0.0), shared + glm::dvec3(0.0, 0.2, 0.3)};
  touching.triangles = {{0, 1, 2}};
  scene.meshes.push_back(touching);
  GpuSceneOptions options;
  options.search = PrimitiveSearch::bvh_per_ray;
  GpuScene gpu = make_gpu_scene(scene, options, ShaderVariant{});
  Scene moved = scene;
  for (const double lift : {0.01, 0.02, 0.03}) {  // the shared corner stays; the others rise
    moved.meshes[3].positions[1].y = scene.meshes[3].positions[1].y + lift;
    ASSERT_TRUE(refit_in_place(gpu, moved, ShaderVariant{}, scene_extent(moved), 3));
    EXPECT_FALSE(gpu.rewritten.mesh_alone);
  }
  moved.meshes[3].positions[0].y += 0.01;  // the shared corner leaves the grid's vertex
  EXPECT_FALSE(refit_in_place(gpu, moved, ShaderVariant{}, scene_extent(moved), 3));
}

// The same moves through a Renderer: each render and cast after a move is a Renderer made from the
// moved scene's, bit for bit (what write_refitted uploads of the rewritten ranges is all that changed).
TEST(SetVertices, MovesWithinTheScenesBoxRenderAsTheMovedScene) {
  const Scene scene = boxed_meshes();
  Renderer renderer(device(), scene);
  Scene moved = scene;
  int call = 0;
  for (const auto& [angle, offset, seed] : {std::tuple{0.3, glm::dvec3(0.2, 0.1, 0.0), 51u},
                                            {0.9, glm::dvec3(-0.4, 0.0, 0.3), 53u}, {2.0, glm::dvec3(0.5, 0.2, -0.2), 57u}}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    moved.meshes[0].positions = carried(scene.meshes[0], angle, offset, seed);
    renderer.set_vertices(0, moved.meshes[0].positions);
    // The first call converts the scene, the second refits all of it, the third the sphere alone.
    EXPECT_TRUE(renderer.timings().tree_refitted);
    EXPECT_EQ(renderer.timings().refit_mesh_alone, ++call == 3);
    const Frame frame = renderer.render(moved.camera, width, height, {Aov::depth, Aov::normal});
    test::expect_frame_matches_reference(moved, frame);
    Renderer fresh(device(), moved);
    expect_same_frame(frame, fresh.render(moved.camera, width, height, {Aov::depth, Aov::normal}));
    expect_same_hits(renderer.cast_rays(rays_from_above()), fresh.cast_rays(rays_from_above()));
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
