// Counting crossings (Renderer::count_intersections): in every search and shader variant, each
// ray's count is the reference's (ReferenceScene::count_crossings), an edge or vertex passed exactly
// through counts once, and a closed surface's count is odd exactly where the ray starts inside it.
#include "engine/reference/reference.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

namespace vkray {
namespace {

using namespace test;

const std::vector<PrimitiveSearch> every_search{PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray,
                                                PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query};

// The searches and shader variants each test counts with: every search that runs here, then the
// per-ray walk as the generic shader, in float64, with geometry in storage buffers, and with a loop
// budget small enough that the host finishes rays.
std::vector<RendererOptions> counting_variants() {
  std::vector<RendererOptions> variants;
  for (const PrimitiveSearch search : runnable(every_search)) {
    variants.emplace_back().scene.search = search;
  }
  for (int k = 0; k < 4; ++k) variants.emplace_back().scene.search = PrimitiveSearch::bvh_per_ray;
  variants[variants.size() - 4].shader.generic = true;
  variants[variants.size() - 3].shader.precision = Precision::float64;
  variants[variants.size() - 2].shader.storage_geometry = true;
  variants.back().loop_budget = 6;
  return variants;
}

std::string variant_name(const RendererOptions& options) {
  const ShaderVariant& shader = options.shader;
  return std::string(traversal_name(options.scene.search)) + (shader.generic ? ", generic" : "") +
         (shader.storage_geometry ? ", storage geometry" : "") + (shader.precision == Precision::float64 ? ", float64" : "") +
         (options.loop_budget ? ", loop budget 6" : "");
}

GivenRay ray_toward(const glm::dvec3& from, const glm::dvec3& to) {
  const glm::dvec3 d = to - from;
  return {from.x, from.y, from.z, d.x, d.y, d.z};
}

// The points of the cube [-1, 1]^3's surface whose coordinates are multiples of 1/2: its corners,
// points on its edges and on its faces' diagonals (each face is two triangles), and face centres.
std::vector<glm::dvec3> cube_surface_points() {
  std::vector<glm::dvec3> points;
  for (int x = -2; x <= 2; ++x) {
    for (int y = -2; y <= 2; ++y) {
      for (int z = -2; z <= 2; ++z) {
        if (std::max({std::abs(x), std::abs(y), std::abs(z)}) == 2) points.push_back(glm::dvec3(x, y, z) / 2.0);
      }
    }
  }
  return points;
}

// Rays from the cube's centre through each of those points: each passes through a vertex, an edge
// or a face's diagonal, or a face's inside; a ray from inside a closed convex mesh crosses it once,
// however many triangles share the point it passes. Rays from outside toward the points halfway
// in cross it twice. Both exactly, on the GPU and in the reference (whose rule this also checks).
// Ray queries count what the device proposes, which at an edge is its own test's choice
// (ray_query_walk.glsl): they are left out here.
TEST(Crossings, EdgesAndVerticesCountOnce) {
  const Scene scene = cube_scene();
  std::vector<GivenRay> rays;
  std::vector<uint32_t> expected;
  for (const glm::dvec3& point : cube_surface_points()) {
    rays.push_back(ray_toward(glm::dvec3(0.0), point));
    expected.push_back(1);
    rays.push_back(ray_toward(3.0 * point, 0.5 * point));
    expected.push_back(2);
  }
  const ReferenceScene reference(scene);
  for (size_t k = 0; k < rays.size(); ++k) {
    EXPECT_EQ(count_reference_crossings(reference, rays[k], 0.0, no_hit), expected[k]) << "reference, ray " << k;
  }
  for (const RendererOptions& options : counting_variants()) {
    if (options.scene.search == PrimitiveSearch::ray_query) continue;
    SCOPED_TRACE(variant_name(options));
    Renderer renderer(device(), scene, options);
    const std::vector<uint32_t> counts = renderer.count_intersections(rays);
    size_t wrong = 0;
    for (size_t k = 0; k < rays.size(); ++k) wrong += counts[k] != expected[k];
    EXPECT_EQ(wrong, 0u) << "of " << rays.size() << " rays";
  }
}

// A closed geodesic sphere of triangles, an analytic sphere beside it and a plane below both, crossed
// by random rays from random origins: every count is the reference's, and its parity without the
// plane tells whether the origin lies inside a sphere (origins within rounding of a surface are
// left out: none lie closer than 1e-3 to one).
TEST(Crossings, RandomRaysCountAsTheReference) {
  Scene scene = mesh_scene(make_sphere_mesh(2000));
  scene.spheres.push_back({{2.5, 0.0, 0.0}, 1.0});
  scene.planes.push_back({{0.0, 0.0, -2.0}, {0.0, 0.0, 1.0}});
  const ReferenceScene reference(scene);
  PortableRandom random(7);
  std::vector<GivenRay> rays;
  std::vector<int> inside;  // 1 inside a sphere, 0 outside both
  while (rays.size() < 4096) {
    const glm::dvec3 origin(random.uniform(-1.5, 4.0), random.uniform(-1.5, 1.5), random.uniform(-1.5, 1.5));
    const glm::dvec3 direction = random.unit_vector();
    // The mesh lies between its circumscribed sphere (radius 1) and the sphere through its faces'
    // centres: about 1 - 1e-3 at 2000 triangles (the sagitta of its ~0.09-long edges).
    const double to_mesh = glm::length(origin), to_sphere = glm::length(origin - scene.spheres[0].center);
    if (std::abs(to_mesh - 1.0) < 5e-3 || std::abs(to_sphere - 1.0) < 1e-3) continue;
    rays.push_back({origin.x, origin.y, origin.z, direction.x, direction.y, direction.z});
    inside.push_back(to_mesh < 1.0 || to_sphere < 1.0);
  }
  std::vector<uint32_t> expected(rays.size());
  size_t odd = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    expected[k] = count_reference_crossings(reference, rays[k], 0.0, no_hit);
    const uint32_t plane = rays[k][5] < 0.0;  // every origin lies above the plane
    ASSERT_EQ(int((expected[k] - plane) % 2), inside[k]) << "reference, ray " << k;
    odd += (expected[k] - plane) % 2;
  }
  EXPECT_GT(odd, 200u) << "some origins must lie inside";
  for (const RendererOptions& options : counting_variants()) {
    SCOPED_TRACE(variant_name(options));
    Renderer renderer(device(), scene, options);
    const std::vector<uint32_t> counts = renderer.count_intersections(rays);
    size_t wrong = 0, first_wrong = rays.size();
    for (size_t k = 0; k < rays.size(); ++k) {
      if (counts[k] != expected[k] && wrong++ == 0) first_wrong = k;
    }
    EXPECT_EQ(wrong, 0u) << "of " << rays.size() << " rays, the first " << first_wrong;
  }
}

// Ranges count what lies within them; masks leave out what they hide; the default scene's spheres,
// planes and meshes together (counts as the reference's for the camera's pixel rays).
TEST(Crossings, RangesMasksAndTheDefaultScene) {
  Scene scene;
  scene.spheres.push_back({{0.0, 0.0, 0.0}, 1.0, Mask(1)});
  scene.planes.push_back({{0.0, 0.0, -3.0}, {0.0, 0.0, 1.0}, Mask(2)});
  const std::vector<GivenRay> rays{{0, 0, 5, 0, 0, -1}, {0, 0, 5, 0, 0, -1}, {0, 0, 5, 0, 0, -2}, {0, 0, 0, 0, 0, -1}};
  const std::vector<double> t_min{0.0, 4.5, 0.0, 0.5}, t_max{no_hit, 6.5, 2.75, no_hit};
  // Ray 0 enters the sphere at 4, leaves at 6 and crosses the plane at 8; ray 1 sees the exit alone;
  // ray 2's range ends at 2.75 along its unit direction (not its own, twice as long), before the
  // sphere; ray 3 starts inside it, its range past its origin, and leaves it and crosses the plane.
  const RayRanges ranges{t_min, t_max};
  const std::vector<uint32_t> every_bit{3, 1, 0, 2}, sphere_alone{2, 1, 0, 1};
  for (const RendererOptions& options : counting_variants()) {
    SCOPED_TRACE(variant_name(options));
    Renderer renderer(device(), scene, options);
    EXPECT_EQ(renderer.count_intersections(rays, ranges), every_bit);
    renderer.set_ray_mask(1);
    EXPECT_EQ(renderer.count_intersections(rays, ranges), sphere_alone);
  }

  const Scene model = sized(default_scene(), 48, 32);
  const std::vector<GivenRay> pixels = pixel_rays(model);
  const ReferenceScene model_reference(model);
  for (const PrimitiveSearch search : runnable(every_search)) {
    RendererOptions options;
    options.scene.search = search;
    SCOPED_TRACE(traversal_name(search));
    Renderer renderer(device(), model, options);
    const std::vector<uint32_t> counts = renderer.count_intersections(pixels);
    size_t wrong = 0, crossed = 0;
    for (size_t k = 0; k < pixels.size(); ++k) {
      wrong += counts[k] != count_reference_crossings(model_reference, pixels[k], 0.0, no_hit);
      crossed += counts[k] > 1;
    }
    EXPECT_EQ(wrong, 0u) << "of " << pixels.size() << " pixel rays";
    EXPECT_GT(crossed, pixels.size() / 10) << "rays must cross more than the nearest surface";
  }
}

}  // namespace
}  // namespace vkray
