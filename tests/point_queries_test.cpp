// Point queries on the device against the fp64 reference, point by point: the nearest point's
// distance within the bound the shaders' arithmetic gives, the primitive it lies on, and the
// winding number within its bound; in every search and precision, far from the origin, near the
// surface, at extreme scales, with instances, masks, largest distances and a loop budget.
#include "engine/reference/reference.hpp"
#include "tests/gpu_test_support.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace {

using namespace vkray;
using namespace vkray::test;

// The unit roundoff of a renderer's shaders.
double roundoff(const RendererOptions& options) { return options.shader.precision == Precision::float64 ? 0x1p-53 : 0x1p-24; }

// What the distances' error bound is measured against: the diagonal of the box of the scene's finite
// primitives and the query points, and the largest size of a primitive whose offsets the shader
// takes (a triangle's longest edge, a sphere's diameter, a placed mesh's box's diagonal times its
// placement's condition number: its point is taken into the mesh's coordinates by the inverse).
struct Sizes {
  double diagonal = 0.0, primitive = 0.0;
  glm::dvec3 centre{0.0};
};

Sizes sizes_of(const Scene& scene, const std::vector<glm::dvec3>& points) {
  Bounds box;
  Sizes sizes;
  for (const glm::dvec3& p : points) box.add(p);
  for (const Sphere& sphere : scene.spheres) {
    box.add(sphere.center - sphere.radius), box.add(sphere.center + sphere.radius);
    sizes.primitive = std::max(sizes.primitive, 2.0 * sphere.radius);
  }
  for (const Mesh& mesh : scene.meshes) {
    if (mesh.instanced) continue;
    for (const auto& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        box.add(mesh.positions[t[k]]);
        sizes.primitive = std::max(sizes.primitive, glm::length(mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]));
      }
    }
  }
  for (const Instance& instance : scene.instances) {
    Bounds placed_box;
    for (const glm::dvec3& p : scene.meshes[instance.mesh].positions) placed_box.add(placed(instance, p));
    box.add(placed_box.lower), box.add(placed_box.upper);
    const double condition = smallest_scale(glm::inverse(instance.linear)) > 0.0
                                 ? 1.0 / (smallest_scale(instance.linear) * smallest_scale(glm::inverse(instance.linear)))
                                 : 1.0;
    sizes.primitive = std::max(sizes.primitive, glm::length(placed_box.upper - placed_box.lower) * condition);
  }
  sizes.diagonal = glm::length(box.upper - box.lower);
  sizes.centre = 0.5 * (box.lower + box.upper);
  return sizes;
}

// The bound of a distance's error. Positions are taken relative to the point from their hi and lo
// parts, each offset within 2^-24 of its length (float32; 2^-53 in float64 shaders); the nearest
// point of a triangle is then a dozen roundings of dot products of offsets no longer than the
// farthest vertex, d + s away (s the primitive's size: Sizes), and a sphere's alike: 16 units of
// roundoff of d + s. A plane's height is its stored height less the dot product of its normal with
// the point (relative to the scene's anchor, in the box): 16 units of d + the box's diagonal.
double distance_bound(const Sizes& sizes, const PointHit& exact, const RendererOptions& options) {
  const double size = exact.kind == PrimitiveKind::plane ? sizes.diagonal : sizes.primitive;
  return 16.0 * roundoff(options) * (exact.distance + size);
}

// Each point's nearest point from the device against the reference's: the distance within its
// bound; the primitive the same, and the offset within the bound, unless another primitive lies
// within the bound of as near (a tie the rounding may break either way), where the device's point
// must lie on the scene's surface, at its distance.
void expect_nearest_match(const Scene& scene, const std::vector<glm::dvec3>& points, const RendererOptions& options,
                          const std::vector<double>& max_distances = {}, Mask ray_mask = every_mask_bit) {
  SCOPED_TRACE(variant_name(options));
  Renderer renderer(device(), scene, options);
  renderer.set_ray_mask(ray_mask);
  const PointHits hits = renderer.closest_points(points, max_distances);
  const ReferenceScene reference(scene, ray_mask);
  const Sizes sizes = sizes_of(scene, points);
  size_t failures = 0, ties = 0;
  double worst = 0.0;
  for (size_t k = 0; k < points.size() && failures < 10; ++k) {
    const double most = max_distances.empty() ? no_hit : max_distances[max_distances.size() == 1 ? 0 : k];
    const PointHit exact = reference.closest_point(points[k], most);
    const glm::dvec3 offset = hits.offset_at(k);
    const auto where = [&] {
      return testing::Message() << "point " << k << " (" << points[k].x << ", " << points[k].y << ", " << points[k].z << "): device "
                                << hits.distance_at(k) << " object " << hits.object[k] << " primitive " << hits.primitive[k]
                                << ", reference " << exact.distance << " object " << reference.source(exact).object << " primitive "
                                << reference.source(exact).primitive;
    };
    if (exact.kind == PrimitiveKind::none) {
      if (!std::isinf(hits.distance_at(k)) || hits.object[k] != no_object) ++failures, ADD_FAILURE() << where() << ": found past the bound";
      continue;
    }
    const double bound = distance_bound(sizes, exact, options);
    const double error = std::abs(hits.distance_at(k) - exact.distance);
    worst = std::max(worst, error / bound);
    if (!(error <= bound)) {
      ++failures, ADD_FAILURE() << where() << ": distance off by " << error << ", bound " << bound;
      continue;
    }
    const ObjectPrimitive source = reference.source(exact);
    const bool same = hits.object[k] == source.object && hits.primitive[k] == source.primitive && hits.instance[k] == exact.instance;
    if (same) {
      if (!(glm::length(offset - (exact.point - points[k])) <= 2.0 * bound)) {
        ++failures, ADD_FAILURE() << where() << ": offset off by " << glm::length(offset - (exact.point - points[k]));
      }
      continue;
    }
    ++ties;
    const double off_surface = reference.closest_point(points[k] + offset).distance;
    if (!(off_surface <= 2.0 * bound && std::abs(glm::length(offset) - hits.distance_at(k)) <= bound)) {
      ++failures, ADD_FAILURE() << where() << ": another primitive, its point " << off_surface << " off the surface";
    }
  }
  std::printf("    %zu points: worst distance error %.3f of its bound, %zu ties broken otherwise\n", points.size(), worst, ties);
  // Ties are common, not rare: outside a mesh, a shared vertex or edge is the nearest feature of
  // much of space, and each triangle sharing it is as near. Every tie's point was checked above to
  // lie on the surface at the nearest distance.
}

// The bound of a winding number's error at `point`. Each term 2 atan2(num, den) (point_geometry.h),
// num and den each within 8 units of roundoff of 4 |a||b||c| (a dot of a cross, four products
// summed; the offsets' own relative error included), is within 2^6 u 4 |a||b||c| / |(den, num)| of
// its angle, plus atan's own 2u pi; an instance's point is taken into its mesh's coordinates with an
// absolute error of u |p| there, a relative one of u |p| / min(|a|, |b|, |c|). The walk meets at
// most every triangle and, in caps, as many edges again (the capped subtrees are disjoint and a cap
// is kept only where its boundary is no longer than its subtree), each cap's term well
// conditioned (|(den, num)| >= |a||b||c|, point_walk.glsl): the sum over every triangle, and as many
// again of the cap's bound.
double winding_bound(const Scene& scene, const glm::dvec3& point, double u) {
  double total = 0.0;
  size_t triangles = 0;
  const auto add = [&](const Mesh& mesh, const glm::dvec3& p, double p_size) {
    for (const auto& t : mesh.triangles) {
      const glm::dvec3 a = mesh.positions[t[0]] - p, b = mesh.positions[t[1]] - p, c = mesh.positions[t[2]] - p;
      const double product = glm::length(a) * glm::length(b) * glm::length(c);
      const double num = glm::dot(a, glm::cross(b, c));
      const double den = product + glm::dot(a, b) * glm::length(c) + glm::dot(a, c) * glm::length(b) + glm::dot(b, c) * glm::length(a);
      const double shortest = std::min({glm::length(a), glm::length(b), glm::length(c)});
      const double relative = 1.0 + p_size / std::max(shortest, 1e-300);
      total += 256.0 * u * product * relative / std::max(std::hypot(num, den), 1e-300) + 2.0 * u * M_PI;
      // At the cut of atan2 (den < 0 and num about 0: the point within num's rounding of the
      // triangle's inside) a rounding that turns num's sign turns the term by 4 pi: the winding
      // number by 1, as it truly turns where a point crosses the surface there.
      if (den < 0.0 && std::abs(num) <= 32.0 * u * product * relative) total += 4.0 * M_PI;
      ++triangles;
    }
  };
  for (const Mesh& mesh : scene.meshes) {
    if (!mesh.instanced) add(mesh, point, 0.0);
  }
  for (const Instance& instance : scene.instances) {
    const glm::dvec3 in_mesh = glm::inverse(instance.linear) * (point - instance.translation);
    add(scene.meshes[instance.mesh], in_mesh, glm::length(in_mesh));
  }
  total += double(triangles) * (256.0 * u + 2.0 * u * M_PI);
  return total / (4.0 * M_PI);
}

// Whether `point` lies within `margin` of a sphere's surface or a plane (inside or outside told by a
// comparison the rounding may flip): left out of the winding numbers' checks.
bool at_a_sphere_or_plane(const Scene& scene, const glm::dvec3& point, double margin) {
  for (const Sphere& sphere : scene.spheres) {
    if (std::abs(glm::length(point - sphere.center) - sphere.radius) <= margin) return true;
  }
  for (const Plane& plane : scene.planes) {
    if (std::abs(glm::dot(plane.normal, point - plane.point)) <= margin) return true;
  }
  return false;
}

void expect_winding_match(const Scene& scene, const std::vector<glm::dvec3>& points, const RendererOptions& options,
                          Mask ray_mask = every_mask_bit) {
  SCOPED_TRACE(variant_name(options));
  Renderer renderer(device(), scene, options);
  renderer.set_ray_mask(ray_mask);
  const PointHits hits = renderer.winding_numbers(points);
  const ReferenceScene reference(scene, ray_mask);
  const double margin = 16.0 * roundoff(options) * sizes_of(scene, points).diagonal;
  size_t failures = 0, checked = 0;
  double worst = 0.0;
  for (size_t k = 0; k < points.size() && failures < 10; ++k) {
    if (at_a_sphere_or_plane(scene, points[k], margin)) continue;
    ++checked;
    const double exact = reference.winding_number(points[k]);
    const double bound = winding_bound(scene, points[k], roundoff(options));
    const double error = std::abs(hits.distance_at(k) - exact);
    worst = std::max(worst, error / bound);
    if (!(error <= bound)) {
      ++failures;
      ADD_FAILURE() << "point " << k << " (" << points[k].x << ", " << points[k].y << ", " << points[k].z << "): winding number "
                    << hits.distance_at(k) << ", reference " << exact << ", bound " << bound;
    }
  }
  std::printf("    %zu points: worst winding number error %.3g of its bound\n", checked, worst);
  EXPECT_GT(checked, points.size() * 9 / 10);
}

// The searches that walk vkray's own tree (ray queries have none) and brute force, in each precision
// they take.
std::vector<RendererOptions> point_searches(const ShaderVariant& shader = {}) {
  std::vector<RendererOptions> all;
  RendererOptions base;
  base.shader = shader;
  for (RendererOptions options : searches_with(base)) {
    if (options.scene.search == PrimitiveSearch::ray_query) continue;
    all.push_back(options);
    if (options.scene.search == PrimitiveSearch::bvh_packet) continue;  // float32 alone
    options.shader.precision = Precision::float64;
    all.push_back(options);
  }
  return all;
}

TEST(PointQueries, NearestInEverySearchAndPrecision) {
  const Scene scene = placed_shapes_scene();
  const std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 1.0, 1500, 21);
  for (const RendererOptions& options : point_searches()) expect_nearest_match(scene, points, options);
}

TEST(PointQueries, WindingNumbersInEverySearchAndPrecision) {
  const Scene scene = placed_shapes_scene();
  const std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 1.0, 600, 22);
  for (const RendererOptions& options : point_searches()) expect_winding_match(scene, points, options);
}

// The geometry read as storage buffers, and the generic shader (counts read at run time).
TEST(PointQueries, StorageGeometryAndGenericVariants) {
  const Scene scene = placed_shapes_scene();
  const std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 1.0, 500, 23);
  for (const ShaderVariant shader : {ShaderVariant{.storage_geometry = true}, ShaderVariant{.generic = true}}) {
    RendererOptions options;
    options.shader = shader;
    expect_nearest_match(scene, points, options);
    expect_winding_match(scene, points, options);
  }
}

// Points a millionth of the mesh's size off its surface, on both sides, and on it: their distances
// keep float32's digits of their own size (the offsets taken relative to the point), and the winding
// number tells inside from outside.
TEST(PointQueries, NearTheSurfaceAndOnIt) {
  Scene scene;
  scene.meshes.push_back(make_sphere_mesh(2000, glm::dvec3(0.3, -0.2, 0.1), 1.0));
  check_scene(scene);
  const Mesh& mesh = scene.meshes[0];
  std::vector<glm::dvec3> points;
  for (size_t t = 0; t < mesh.triangles.size(); t += 7) {
    const glm::dvec3 a = mesh.positions[mesh.triangles[t][0]], b = mesh.positions[mesh.triangles[t][1]],
                     c = mesh.positions[mesh.triangles[t][2]];
    const glm::dvec3 centroid = (a + b + c) / 3.0, normal = glm::normalize(glm::cross(b - a, c - a));
    for (const double height : {1e-6, -1e-6, 0.0}) points.push_back(centroid + height * normal);
  }
  for (const RendererOptions& options : point_searches()) {
    expect_nearest_match(scene, points, options);
    expect_winding_match(scene, points, options);
  }
}

// A million units from the origin, the whole scene and its points moved: the hi and lo parts carry
// it, the bounds are those at home.
TEST(PointQueries, FarFromTheOrigin) {
  const Scene scene = translated(placed_shapes_scene(), {1e6, -2e6, 5e5});
  std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 1.0, 800, 24);
  for (glm::dvec3& point : points) point += glm::dvec3(1e6, -2e6, 5e5);
  RendererOptions options;
  expect_nearest_match(scene, points, options);
  expect_winding_match(scene, points, options);
}

// Instances at extreme scales: a mesh a millionth across and one a million across, each far from
// the origin, queried at points of their own size.
TEST(PointQueries, InstancesAtExtremeScales) {
  for (const double scale : {1e-6, 1e6}) {
    Scene scene;
    Mesh mesh = make_sphere_mesh(800);
    mesh.instanced = true;
    scene.meshes.push_back(mesh);
    const glm::dmat3 uneven(glm::dvec3(scale, 0.0, 0.0), glm::dvec3(0.0, 2.0 * scale, 0.0), glm::dvec3(0.0, 0.0, 0.5 * scale));
    const glm::dvec3 at(3e5, 1e5, -2e5);
    scene.instances = {Instance{0, uneven, at}, Instance{0, glm::dmat3(scale), at + glm::dvec3(3.0 * scale, 0.0, 0.0)}};
    check_scene(scene);
    std::vector<glm::dvec3> points = points_in({glm::dvec3(-2.0), glm::dvec3(5.0, 2.0, 2.0)}, 0.0, 400, 25);
    for (glm::dvec3& point : points) point = at + scale * point;
    SCOPED_TRACE(testing::Message() << "scale " << scale);
    expect_nearest_match(scene, points, {});
    expect_winding_match(scene, points, {});
  }
}

// A largest distance, one for all and one a point: what lies beyond is a miss (+inf, no object), the
// rest found as without it.
TEST(PointQueries, LargestDistances) {
  const Scene scene = placed_shapes_scene();
  const std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 2.0, 600, 26);
  expect_nearest_match(scene, points, {}, {0.3});
  std::vector<double> each;
  for (size_t k = 0; k < points.size(); ++k) each.push_back(k % 3 == 0 ? 0.0 : 0.05 * double(k % 17));
  expect_nearest_match(scene, points, {}, each);
  Renderer renderer(device(), scene);
  EXPECT_THROW(renderer.closest_points(points, std::vector<double>{-1.0}), InputError);
  EXPECT_THROW(renderer.closest_points(points, std::vector<double>{1.0, 2.0}), InputError);
  EXPECT_THROW(renderer.closest_points(std::vector<glm::dvec3>{glm::dvec3(NAN, 0.0, 0.0)}), InputError);
}

// Masks: what the ray mask leaves out, point queries leave out.
TEST(PointQueries, MasksLeaveOutWhatRaysCannotMeet) {
  Scene scene = placed_shapes_scene();
  scene.spheres[0].mask = 0x02;
  scene.instances[1].mask = 0x02;
  scene.meshes[2].mask = 0x04;
  const std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 1.0, 500, 27);
  for (const Mask ray_mask : {Mask{0x01}, Mask{0x02}}) {
    SCOPED_TRACE(testing::Message() << "ray mask " << int(ray_mask));
    expect_nearest_match(scene, points, {}, {}, ray_mask);
    expect_winding_match(scene, points, {}, ray_mask);
  }
}

// A loop budget of a few iterations: the points past it are answered by the reference, ids included.
TEST(PointQueries, PointsBeyondTheLoopBudgetAreFinished) {
  const Scene scene = placed_shapes_scene();
  const std::vector<glm::dvec3> points = points_in(placed_shapes_box(), 1.0, 300, 28);
  RendererOptions options;
  options.loop_budget = 20;
  expect_nearest_match(scene, points, options);
  expect_winding_match(scene, points, options);
}

// Ray queries walk no tree of vkray's: point queries are refused, saying what to make instead.
TEST(PointQueries, RayQueryRenderersRefuse) {
  if (runnable({PrimitiveSearch::ray_query}).empty()) GTEST_SKIP() << "no ray queries here";
  RendererOptions options;
  options.scene.search = PrimitiveSearch::ray_query;
  Renderer renderer(device(), placed_shapes_scene(), options);
  EXPECT_THROW(renderer.closest_points(std::vector<glm::dvec3>{glm::dvec3(0.0)}), InputError);
}

}  // namespace
