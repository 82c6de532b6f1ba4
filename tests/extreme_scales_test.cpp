// Geometry from 1e-20 to 1e14 across, in the world and placed by instances, in every walk and in the
// float arithmetic GPUs run: every pixel within the reference's envelope (hostile campaign 3 found a
// cube 1e-15 across 5% off in the per-ray and brute-force walks, and at 1e-16 gone). And placements
// at the edges of what check_transform accepts (flattened 2^31 times, sheared, 1e-6 and 1e6 far from
// the origin) drawn as the reference draws them.
#include "engine/bench/bench.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "tests/gpu_test_support.hpp"

#include <glm/matrix.hpp>

#include <cmath>
#include <string>

namespace vkray {
namespace {

using namespace test;

// Each search this device runs, with the default arithmetic and with the GPUs' float edge functions.
std::vector<RendererOptions> every_walk_and_arithmetic() {
  std::vector<RendererOptions> variants = searches_with();
  const std::vector<RendererOptions> float_edges = searches_with(find_bench_variant("float-edges").options);
  variants.insert(variants.end(), float_edges.begin(), float_edges.end());
  return variants;
}

void expect_every_walk_as_the_reference(const Scene& scene) {
  for (const RendererOptions& options : every_walk_and_arithmetic()) {
    SCOPED_TRACE(variant_name(options) + (options.shader.edges == EdgeArithmetic::float_error_free ? ", float edges" : ""));
    Renderer renderer(device(), scene, options);
    const Frame frame = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
    expect_frame_matches_reference(scene, frame);
  }
}

// A faceted ball of radius `size` / 2 off the origin, a sphere beside it and a floor below, seen from
// four sizes away.
Scene scene_of_size(double size) {
  Scene scene;
  scene.width = 48, scene.height = 32;
  scene.meshes.push_back(make_sphere_mesh(160, glm::dvec3(0.2, -0.1, 0.0) * size, 0.5 * size));
  scene.spheres.push_back({glm::dvec3(1.1, 0.1, -0.3) * size, 0.35 * size});
  scene.planes.push_back({glm::dvec3(0.0, -0.7 * size, 0.0), glm::dvec3(0.0, 1.0, 0.0)});
  scene.camera = {glm::dvec3(0.6, 1.2, 4.0) * size, glm::dvec3(0.3, 0.0, 0.0) * size, glm::dvec3(0.0, 1.0, 0.0), 45.0};
  check_scene(scene);
  return scene;
}

TEST(ExtremeScales, TinyAndHugeGeometryInEveryWalk) {
  for (const double size : {1e-20, 1e-16, 1e-15, 1e-6, 1e6, 1e14}) {
    SCOPED_TRACE("size " + std::to_string(size));
    std::printf("  size %g\n", size);
    expect_every_walk_as_the_reference(scene_of_size(size));
  }
}

// The same ball, a unit mesh placed by instances: scaled to `size`, one turned and unevenly scaled.
TEST(ExtremeScales, TinyAndHugeInstancesInEveryWalk) {
  for (const double size : {1e-20, 1e-15, 1e-6, 1e6, 1e14}) {
    SCOPED_TRACE("size " + std::to_string(size));
    std::printf("  size %g\n", size);
    Scene scene = scene_of_size(size);
    scene.meshes[0] = make_sphere_mesh(160, glm::dvec3(0.0), 0.5);
    scene.meshes[0].instanced = true;
    const double c = std::cos(0.6), s = std::sin(0.6);
    const glm::dmat3 turned(glm::dvec3(c, 0.0, -s), glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(s, 0.0, c));
    scene.instances = {{0, glm::dmat3(size), glm::dvec3(0.2, -0.1, 0.0) * size},
                       {0, turned * glm::dmat3(glm::dvec3(0.3 * size, 0, 0), glm::dvec3(0, 0.6 * size, 0), glm::dvec3(0, 0, 0.3 * size)),
                        glm::dvec3(-0.8, 0.3, 0.5) * size}};
    check_scene(scene);
    expect_every_walk_as_the_reference(scene);
  }
}

// Placements at the edges of what float32 walks (check_transform): a cube flattened 2^31 times into a
// sheet, turned; a shear; a ball 1e-6 across and one 1e6 across, each 1e5 of their sizes from the
// origin.
TEST(ExtremeScales, PlacementsAtTheEdgesOfWhatIsAccepted) {
  const double c = std::cos(0.5), s = std::sin(0.5);
  const glm::dmat3 turned(glm::dvec3(1.0, 0.0, 0.0), glm::dvec3(0.0, c, s), glm::dvec3(0.0, -s, c));
  glm::dmat3 sheared(1.0);
  sheared[1][0] = 1.0;  // x += y
  for (const auto& [name, linear, size] :
       {std::tuple{"sheet", turned * glm::dmat3(glm::dvec3(1.0, 0, 0), glm::dvec3(0, 1.0, 0), glm::dvec3(0, 0, 0x1p-31)), 1.0},
        std::tuple{"sheared", sheared * glm::dmat3(0.5), 1.0}, std::tuple{"micro", glm::dmat3(1e-6), 1e-6},
        std::tuple{"mega", glm::dmat3(1e6), 1e6}}) {
    SCOPED_TRACE(name);
    ASSERT_EQ(float32_placement_fault(linear), "");
    Scene scene;
    scene.width = 48, scene.height = 32;
    Mesh ball = make_sphere_mesh(160, glm::dvec3(0.0), 0.5);
    ball.instanced = true;
    scene.meshes.push_back(ball);
    const glm::dvec3 at = glm::dvec3(1e5, -2e4, 3e4) * size;
    scene.instances = {{0, linear, at}};
    scene.camera = {at + glm::dvec3(0.4, 0.9, 2.5) * size, at, glm::dvec3(0.0, 1.0, 0.0), 50.0};
    check_scene(scene);
    expect_every_walk_as_the_reference(scene);
  }
}

}  // namespace
}  // namespace vkray
