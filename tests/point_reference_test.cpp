// Point queries in the fp64 reference: the tree walk against every primitive measured (the same
// arithmetic, so the same answer to the bit), the winding number's caps against every triangle's
// solid angle, and both against what the geometry says exactly (a cube's distance, a closed mesh's
// inside), with instances rotated, sheared, unevenly scaled and mirrored, and masks.
#include "engine/reference/reference.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/scene.hpp"
#include "tests/test_scenes.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using vkray::Instance;
using vkray::Mesh;
using vkray::PointHit;
using vkray::PrimitiveKind;
using vkray::ReferenceScene;
using vkray::Scene;

// The tree's nearest point is brute force's, to the bit, and so is its primitive (ties go the same
// way); within a largest distance too, and a miss past it.
TEST(PointReference, TheTreeFindsWhatBruteForceFinds) {
  const Scene scene = vkray::test::placed_shapes_scene();
  const ReferenceScene reference(scene);
  int found_instances = 0;
  for (const glm::dvec3& point : vkray::test::points_in(vkray::test::placed_shapes_box(), 1.0, 3000, 7)) {
    const PointHit tree = reference.closest_point(point), every = reference.closest_point_brute_force(point);
    ASSERT_EQ(tree.distance, every.distance) << point.x << " " << point.y << " " << point.z;
    EXPECT_EQ(tree.kind, every.kind);
    EXPECT_EQ(tree.index, every.index);
    EXPECT_EQ(tree.instance, every.instance);
    EXPECT_EQ(tree.point, every.point);
    EXPECT_NEAR(glm::length(tree.point - point), tree.distance, 1e-12 * (1.0 + tree.distance));
    found_instances += tree.instance != vkray::no_object;
    const double bound = 0.5 * tree.distance;
    EXPECT_EQ(reference.closest_point(point, bound).kind, PrimitiveKind::none);
    EXPECT_EQ(reference.closest_point(point, bound).distance, vkray::no_hit);
    EXPECT_EQ(reference.closest_point(point, 2.0 * tree.distance).distance, tree.distance);
  }
  EXPECT_GT(found_instances, 100);  // the instances are nearest often enough to be tested
}

// Distances the geometry gives exactly: the cube [-1, 1]^3's (outside: the length of the excess
// over the box; inside: the depth below the nearest face), a sphere's |p - c| - r, a plane's height.
TEST(PointReference, DistancesAsTheGeometryGivesThem) {
  const Scene cube = vkray::test::cube_scene();
  const ReferenceScene reference(cube);
  for (const glm::dvec3& point : vkray::test::points_in({glm::dvec3(-1.0), glm::dvec3(1.0)}, 1.5, 2000, 11)) {
    const glm::dvec3 excess = glm::max(glm::abs(point) - 1.0, glm::dvec3(0.0));
    const double outside = glm::length(excess);
    const double inside = 1.0 - std::max({std::abs(point.x), std::abs(point.y), std::abs(point.z)});
    const double exact = outside > 0.0 ? outside : inside;
    EXPECT_NEAR(reference.closest_point(point).distance, exact, 1e-15 * 8.0) << point.x << " " << point.y << " " << point.z;
  }
  Scene primitives;
  primitives.spheres.push_back({glm::dvec3(1.0, 2.0, 3.0), 0.5});
  primitives.planes.push_back({glm::dvec3(0.0, -4.0, 0.0), glm::normalize(glm::dvec3(0.0, 1.0, 1.0))});
  vkray::check_scene(primitives);
  const ReferenceScene simple(primitives);
  for (const glm::dvec3& point : vkray::test::points_in({glm::dvec3(-3.0), glm::dvec3(3.0)}, 0.0, 500, 12)) {
    const double sphere = std::abs(glm::length(point - glm::dvec3(1.0, 2.0, 3.0)) - 0.5);
    const double plane = std::abs(glm::dot(point - glm::dvec3(0.0, -4.0, 0.0), glm::normalize(glm::dvec3(0.0, 1.0, 1.0))));
    const PointHit hit = simple.closest_point(point);
    EXPECT_NEAR(hit.distance, std::min(sphere, plane), 1e-14);
    EXPECT_EQ(hit.kind, sphere < plane ? PrimitiveKind::sphere : PrimitiveKind::plane);
  }
  // At a sphere's centre every point of it is nearest: the one along +x.
  const PointHit centre = simple.closest_point(glm::dvec3(1.0, 2.0, 3.0));
  EXPECT_EQ(centre.point, glm::dvec3(1.5, 2.0, 3.0));
}

// The caps answer what every triangle's solid angle sums to (each cap's fan closes its subtree's
// boundary: the sum is the same up to rounding, a few 1e-15 per term of thousands).
TEST(PointReference, CapsGiveTheWindingNumberOfEveryTriangle) {
  const Scene scene = vkray::test::placed_shapes_scene();
  const ReferenceScene reference(scene);
  for (const glm::dvec3& point : vkray::test::points_in(vkray::test::placed_shapes_box(), 1.0, 1500, 5)) {
    EXPECT_NEAR(reference.winding_number(point), reference.winding_number_brute_force(point), 1e-10)
        << point.x << " " << point.y << " " << point.z;
  }
}

// A closed mesh's winding number is 1 inside and 0 outside, whatever its placement (a mirrored one's
// too: its mesh's inside is placed, winding and all); a sphere's 1 inside; a plane's 1 behind it;
// an open grid's in between.
TEST(PointReference, WindingNumbersInsideAndOutside) {
  Scene scene;
  Mesh closed = vkray::make_sphere_mesh(800);
  closed.instanced = true;
  scene.meshes.push_back(closed);
  const glm::dmat3 mirrored(glm::dvec3(-2.0, 0.0, 0.0), glm::dvec3(0.0, 0.5, 0.0), glm::dvec3(0.0, 0.0, 1.0));
  scene.instances = {Instance{0, glm::dmat3(1.0), {0.0, 0.0, 0.0}}, Instance{0, mirrored, {5.0, 0.0, 0.0}}};
  scene.spheres.push_back({glm::dvec3(0.0, 5.0, 0.0), 1.0});
  scene.planes.push_back({glm::dvec3(0.0, -3.0, 0.0), glm::dvec3(0.0, 1.0, 0.0)});
  vkray::check_scene(scene);
  const ReferenceScene reference(scene);
  // The icosphere's faces lie within 1 - cos(its edge's angle) of the unit sphere: points kept 5%
  // away from it are inside or outside both.
  const auto inside_ellipsoid = [](const glm::dvec3& p) { return glm::length(p) < 0.95; };
  const auto outside_ellipsoid = [](const glm::dvec3& p) { return glm::length(p) > 1.05; };
  int inside = 0;
  for (const glm::dvec3& point : vkray::test::points_in({glm::dvec3(-3.0, -4.0, -2.0), glm::dvec3(8.0, 7.0, 2.0)}, 0.0, 4000, 3)) {
    const glm::dvec3 in_first = point, in_mirrored = glm::inverse(mirrored) * (point - glm::dvec3(5.0, 0.0, 0.0));
    const glm::dvec3 in_sphere = point - glm::dvec3(0.0, 5.0, 0.0);
    if (!(inside_ellipsoid(in_first) || outside_ellipsoid(in_first)) || !(inside_ellipsoid(in_mirrored) || outside_ellipsoid(in_mirrored))) {
      continue;
    }
    const double expected = double(inside_ellipsoid(in_first)) + double(inside_ellipsoid(in_mirrored)) +
                            double(glm::length(in_sphere) < 1.0) + double(point.y < -3.0);
    inside += expected > 0.0;
    EXPECT_NEAR(reference.winding_number(point), expected, 1e-9) << point.x << " " << point.y << " " << point.z;
  }
  EXPECT_GT(inside, 300);  // of about 470: the inside parts are 12% of the box
  // Half a closed mesh: 1/2 at its centre (the open half sees a hemisphere's solid angle: 2 pi).
  Scene half;
  half.meshes.push_back(vkray::test::quad_grid({-1, -1, 0}, {2, 0, 0}, {0, 2, 0}, 8));
  vkray::check_scene(half);
  const double at_centre_above = ReferenceScene(half).winding_number(glm::dvec3(0.0, 0.0, 1e-9));
  EXPECT_NEAR(std::abs(at_centre_above), 0.5, 1e-6);
}

// Masks leave out of point queries what they leave out of rays.
TEST(PointReference, MasksLeaveOutWhatRaysCannotMeet) {
  Scene scene;
  scene.spheres.push_back({glm::dvec3(0.0), 1.0, 0x01});
  scene.spheres.push_back({glm::dvec3(3.0, 0.0, 0.0), 1.0, 0x02});
  vkray::check_scene(scene);
  const ReferenceScene only_second(scene, 0x02);
  const PointHit hit = only_second.closest_point(glm::dvec3(0.0, 0.0, 0.5));
  EXPECT_EQ(hit.index, 1u);
  EXPECT_NEAR(hit.distance, glm::length(glm::dvec3(3.0, 0.0, -0.5)) - 1.0, 1e-14);
  EXPECT_EQ(only_second.winding_number(glm::dvec3(0.0)), 0.0);
  EXPECT_EQ(ReferenceScene(scene).winding_number(glm::dvec3(0.0)), 1.0);
}

}  // namespace
