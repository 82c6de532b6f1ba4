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
    if (options.loop_budget > 0) {
      EXPECT_GT(renderer.timings().unfinished_rays, 0u) << "the loop budget must leave rays to the host";
    }
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
  const std::vector<GivenRay> rays{{0, 0, 5, 0, 0, -1}, {0, 0, 5, 0, 0, -1}, {0, 0, 5, 0, 0, -2}, {0, 0, 0, 0, 0, -1},
                                  {0, 1, 5, 0, 0, -1}};
  const std::vector<double> t_min{0.0, 4.5, 0.0, 0.5, 0.0}, t_max{no_hit, 6.5, 2.75, no_hit, no_hit};
  // Ray 0 enters the sphere at 4, leaves at 6 and crosses the plane at 8; ray 1 sees the exit alone;
  // ray 2's range ends at 2.75 along its unit direction (not its own, twice as long), before the
  // sphere; ray 3 starts inside it, its range past its origin, and leaves it and crosses the plane;
  // ray 4 touches the sphere (its discriminant exactly 0): the double root counts twice, so parity
  // says outside.
  const RayRanges ranges{t_min, t_max};
  const std::vector<uint32_t> every_bit{3, 1, 0, 2, 3}, sphere_alone{2, 1, 0, 1, 2};
  const ReferenceScene reference(scene), sphere_reference(scene, 1);
  for (size_t k = 0; k < rays.size(); ++k) {
    EXPECT_EQ(count_reference_crossings(reference, rays[k], t_min[k], t_max[k]), every_bit[k]) << "reference, ray " << k;
    EXPECT_EQ(count_reference_crossings(sphere_reference, rays[k], t_min[k], t_max[k]), sphere_alone[k]) << "reference, ray " << k;
  }
  for (const RendererOptions& options : counting_variants()) {
    SCOPED_TRACE(variant_name(options));
    Renderer renderer(device(), scene, options);
    EXPECT_EQ(renderer.count_intersections(rays, ranges), every_bit);
    // The touching ray's first hits: the sphere's double root twice at 5, then the plane at 8.
    const RayHits touching = renderer.cast_rays(std::span(rays).subspan(4, 1), {}, 3);
    EXPECT_EQ(std::vector<float>(touching.t.begin(), touching.t.end()), (std::vector<float>{5.0f, 5.0f, 8.0f}));
    EXPECT_EQ(std::vector<uint32_t>(touching.object.begin(), touching.object.end()), (std::vector<uint32_t>{0, 0, 1}));
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


// Three closed cubes along the x axis (2 wide, centred at x = 0, 4 and 8), a sphere of radius 0.8 in
// the first and one of radius 0.6 apart at x = 12, and the plane x = 15 facing -x: a ray along +x near
// the axis crosses 6 cube faces, 4 sphere roots and the plane, 11 crossings, each met nearly head
// on (the rays stay within 0.1 rad of the axis and 0.5 of it at the cubes, away from every cube edge
// and from the faces' diagonals, where a triangle's neighbour may take the hit).
Scene row_of_shapes() {
  Scene scene = cube_scene();
  for (const double x : {4.0, 8.0}) {
    Mesh cube = scene.meshes[0];
    for (glm::dvec3& p : cube.positions) p.x += x;
    scene.meshes.push_back(std::move(cube));
  }
  scene.spheres.push_back({{0.0, 0.0, 0.0}, 0.8});
  scene.spheres.push_back({{12.0, 0.0, 0.0}, 0.6});
  scene.planes.push_back({{15.0, 0.0, 0.0}, {-1.0, 0.0, 0.0}});
  return scene;
}

std::vector<GivenRay> rays_along_the_row(size_t count) {
  PortableRandom random(11);
  std::vector<GivenRay> rays;
  while (rays.size() < count) {
    const double y = random.uniform(-0.3, 0.3), z = random.uniform(-0.3, 0.3);
    const double dy = random.uniform(-0.01, 0.01), dz = random.uniform(-0.01, 0.01);
    // Within 0.01 of a face's diagonal anywhere along the cubes (x up to 9): too near an edge.
    bool near_diagonal = false;
    for (const double x : {-1.0, 1.0, 3.0, 5.0, 7.0, 9.0}) {
      const double at_y = y + (x + 2.0) * dy, at_z = z + (x + 2.0) * dz;
      near_diagonal = near_diagonal || std::abs(std::abs(at_y) - std::abs(at_z)) < 0.01;
    }
    if (!near_diagonal) rays.push_back({-2.0, y, z, 1.0, dy, dz});
  }
  return rays;
}

// The row and its rays scaled by `scale` about the origin, then moved by `offset` (stiff cases: a
// row far from the world's origin, a tiny one far away).
struct Placement {
  double scale;
  glm::dvec3 offset;
};

Scene placed_scene(Scene scene, const Placement& at) {
  for (Mesh& mesh : scene.meshes) {
    for (glm::dvec3& p : mesh.positions) p = at.offset + at.scale * p;
  }
  for (Sphere& sphere : scene.spheres) sphere.center = at.offset + at.scale * sphere.center, sphere.radius *= at.scale;
  for (Plane& plane : scene.planes) plane.point = at.offset + at.scale * plane.point;
  return scene;
}

std::vector<GivenRay> placed_rays(std::vector<GivenRay> rays, const Placement& at) {
  for (GivenRay& ray : rays) {
    for (int c = 0; c < 3; ++c) ray[c] = at.offset[c] + at.scale * ray[c];
  }
  return rays;
}

// The first hits along the rays, 4 (fewer than the crossings) and 16 (VKRAY_HITS_MAX, more: misses
// past the 11th), are the reference's in every search and variant: the same objects and primitives
// in the same order, each distance within float32's error and each normal within its angle; 4 also
// with the row 1e5 from the world's origin, and scaled by 1e-4 3e4 away. The error of a distance:
// every position relative to the origin and the direction are good to 2 eps (eps = 2^-24) of their
// size, and the tests' arithmetic adds a few eps, which a head-on hit (cos > 0.99) passes to t as
// 8 eps (t + 16 s) (16 s: the row's extent, the largest position from the anchor, at scale s); a
// normal: a triangle's is stored rounded (2 eps), a sphere's comes from an offset good to 10 eps of
// its radius (intersect.glsl): 32 eps.
TEST(FirstHits, InOrderAsTheReference) {
  constexpr double eps = 0x1p-24;
  const std::vector<GivenRay> row_rays = rays_along_the_row(512);
  for (const Placement& at : {Placement{1.0, glm::dvec3(0.0)}, Placement{1.0, glm::dvec3(1e5, -2e5, 5e4)},
                              Placement{1e-4, glm::dvec3(3e4, 1e4, -2e4)}}) {
    const Scene scene = placed_scene(row_of_shapes(), at);
    const std::vector<GivenRay> rays = placed_rays(row_rays, at);
    const ReferenceScene reference(scene);
    const bool as_given = at.scale == 1.0 && at.offset == glm::dvec3(0.0);
    for (const uint32_t count : {4u, uint32_t{VKRAY_HITS_MAX}}) {
      if (!as_given && count == VKRAY_HITS_MAX) continue;
      std::vector<std::vector<ReferenceHit>> expected(rays.size());
      for (size_t k = 0; k < rays.size(); ++k) {
        expected[k] = first_reference_hits(reference, rays[k], 0.0, no_hit, count);
        ASSERT_EQ(std::count_if(expected[k].begin(), expected[k].end(), [](const ReferenceHit& h) { return h.kind != PrimitiveKind::none; }),
                  std::min(count, 11u));
      }
      for (const RendererOptions& options : counting_variants()) {
        // The longest list (a pipeline of its own, slower to compile) in the per-ray walk and float64 alone.
        if (count == VKRAY_HITS_MAX && (options.scene.search != PrimitiveSearch::bvh_per_ray || options.shader.generic ||
                                        options.shader.storage_geometry || options.loop_budget > 0)) {
          continue;
        }
        SCOPED_TRACE(variant_name(options) + ", " + std::to_string(count) + " hits, scale " + std::to_string(at.scale) +
                     ", offset " + std::to_string(glm::length(at.offset)));
        Renderer renderer(device(), scene, options);
        const RayHits hits = renderer.cast_rays(rays, {}, count);
        if (options.loop_budget > 0) {
          EXPECT_GT(renderer.timings().unfinished_rays, 0u) << "the loop budget must leave rays to the host";
        }
        ASSERT_EQ(hits.count, rays.size() * count);
        ASSERT_EQ(hits.hits_per_ray, count);
        size_t wrong_ids = 0, wrong_t = 0, wrong_normals = 0;
        std::string first;
        for (size_t k = 0; k < rays.size(); ++k) {
          for (uint32_t layer = 0; layer < count; ++layer) {
            const size_t at_hit = k * count + layer;
            const ReferenceHit& want = expected[k][layer];
            const ObjectPrimitive source = reference.source(want);
            const bool ids_differ = hits.object[at_hit] != source.object || hits.primitive[at_hit] != source.primitive;
            const double t = hits.t64.empty() ? double{hits.t[at_hit]} : hits.t64[at_hit];
            const bool t_differs = want.kind == PrimitiveKind::none ? !std::isinf(t)
                                                                    : !(std::abs(t - want.t) <= 8 * eps * (want.t + 16.0 * at.scale));
            const glm::dvec3 normal(hits.normal[at_hit], hits.normal[hits.count + at_hit], hits.normal[2 * hits.count + at_hit]);
            const bool normal_differs =
                want.kind == PrimitiveKind::none ? normal != glm::dvec3(0.0) : !(angle_between(normal, want.normal) <= 32 * eps);
            wrong_ids += ids_differ, wrong_t += t_differs, wrong_normals += normal_differs;
            if ((ids_differ || t_differs || normal_differs) && first.empty()) {
              first = "ray " + std::to_string(k) + " hit " + std::to_string(layer) + ": t " + std::to_string(t) + " (reference " +
                      std::to_string(want.t) + "), object " + std::to_string(hits.object[at_hit]) + " (" +
                      std::to_string(source.object) + ")";
            }
          }
        }
        EXPECT_EQ(wrong_ids + wrong_t + wrong_normals, 0u)
            << wrong_ids << " ids, " << wrong_t << " distances, " << wrong_normals << " normals; first: " << first;
      }
    }
  }
}

// The nearest of the first hits is the nearest hit, bit for bit (the same tests on the same
// values; no two surfaces here lie at one distance, where the nearest hit's tie rules would
// apply); ranges and masks apply to the list as to the nearest hit; counts outside 1 to 16 are refused.
TEST(FirstHits, TheFirstIsTheNearestAndRangesAndMasksApply) {
  Scene scene = row_of_shapes();
  scene.meshes[1].mask = 2;
  const std::vector<GivenRay> rays = rays_along_the_row(256);
  Renderer renderer(device(), scene);
  const RayHits nearest = renderer.cast_rays(rays);
  const RayHits first = renderer.cast_rays(rays, {}, 4);
  size_t differ = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    differ += nearest.t[k] != first.t[4 * k] || nearest.object[k] != first.object[4 * k] ||
              nearest.primitive[k] != first.primitive[4 * k] || nearest.normal[k] != first.normal[4 * k];
  }
  EXPECT_EQ(differ, 0u);

  // From x = 2 to 9.5: the second cube (3 and 5) and the third's near face (7) alone; with mask 1 the
  // third's alone (7, 9), the second hidden.
  const std::vector<double> t_min(rays.size(), 4.0), t_max(rays.size(), 11.5);
  const ReferenceScene every_bit(scene), without_second(scene, 1);
  for (const Mask mask : {Mask(0xff), Mask(1)}) {
    renderer.set_ray_mask(mask);
    const RayHits ranged = renderer.cast_rays(rays, {t_min, t_max}, 4);
    size_t wrong = 0;
    for (size_t k = 0; k < rays.size(); ++k) {
      const std::vector<ReferenceHit> want = first_reference_hits(mask == 1 ? without_second : every_bit, rays[k], 4.0, 11.5, 4);
      for (uint32_t layer = 0; layer < 4; ++layer) {
        const ReferenceScene& reference = mask == 1 ? without_second : every_bit;
        wrong += ranged.object[4 * k + layer] != reference.source(want[layer]).object;
      }
    }
    EXPECT_EQ(wrong, 0u) << "ray mask " << int(mask);
  }
  EXPECT_THROW(renderer.cast_rays(rays, {}, 0), InputError);
  EXPECT_THROW(renderer.cast_rays(rays, {}, VKRAY_HITS_MAX + 1), InputError);
}

}  // namespace
}  // namespace vkray
