// The reference intersectors against closed-form answers, including the cases where the textbook
// formulas fail.
#include "engine/reference/reference.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>

namespace vkray {
namespace {

const glm::dvec3 minus_z(0, 0, -1);

TEST(IntersectSphere, FrontHitInsideAndBehind) {
  EXPECT_DOUBLE_EQ(intersect_sphere({0, 0, 5}, 1, minus_z, no_hit), 4.0);
  EXPECT_DOUBLE_EQ(intersect_sphere({0, 0, 0}, 2, minus_z, no_hit), 2.0);    // origin at the centre
  EXPECT_DOUBLE_EQ(intersect_sphere({0, 0.6, 0}, 1, minus_z, no_hit), 0.8);  // inside: the far root
  EXPECT_EQ(intersect_sphere({0, 0, -5}, 1, minus_z, no_hit), no_hit);       // sphere behind
  EXPECT_EQ(intersect_sphere({0, 0, 5}, 1, minus_z, 3.9), 3.9);              // farther than t_max
}

TEST(IntersectSphere, OffAxisAndTangent) {
  // Ray at lateral offset 0.6 from the centre of a unit sphere 5 away: t = 5 - sqrt(1 - 0.36).
  EXPECT_NEAR(intersect_sphere({0.6, 0, 5}, 1, minus_z, no_hit), 4.2, 1e-15);
  EXPECT_DOUBLE_EQ(intersect_sphere({1, 0, 5}, 1, minus_z, no_hit), 5.0);  // exactly tangent
  EXPECT_EQ(intersect_sphere({1.0000001, 0, 5}, 1, minus_z, no_hit), no_hit);
}

// r = 1e-6 at distance 1e6: b^2 - c cancels completely in double (r^2 / |f|^2 = 1e-24), so the
// textbook discriminant misses a sphere the ray passes through. The perpendicular form does not.
TEST(IntersectSphere, TinySphereFarAway) {
  const double r = 1e-6, offset = 0.6e-6;
  const double t = intersect_sphere({offset, 0, 1e6}, r, minus_z, no_hit);
  EXPECT_NEAR(t, 1e6 - std::sqrt(r * r - offset * offset), 1e-9);
  const double b = -1e6, c = 1e12 + offset * offset - r * r;
  EXPECT_LE(b * b - c, 0.0) << "the textbook discriminant would have found this hit";
}

// r = 1e6 with the ray origin 1 above the surface: exact roots 1 and 2e6 + 1.
TEST(IntersectSphere, HugeSphereClose) {
  EXPECT_DOUBLE_EQ(intersect_sphere({0, 0, 1e6 + 1}, 1e6, minus_z, no_hit), 1.0);
}

TEST(IntersectPlane, HitsParallelAndBehind) {
  EXPECT_DOUBLE_EQ(intersect_plane({0, 1, 0}, {0, 0, 0}, {0, 2, 0}, glm::normalize(glm::dvec3(1, -1, 0)), no_hit),
                   2.0 * std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(intersect_plane({0, -1, 0}, {0, 0, 0}, {0, 2, 0}, {0, -1, 0}, no_hit), 2.0);  // back side
  EXPECT_EQ(intersect_plane({0, 1, 0}, {0, 0, 0}, {0, 2, 0}, {1, 0, 0}, no_hit), no_hit);        // parallel
  EXPECT_EQ(intersect_plane({0, 1, 0}, {0, 0, 0}, {0, 2, 0}, {0, 1, 0}, no_hit), no_hit);        // behind
  EXPECT_EQ(intersect_plane({0, 1, 0}, {0, 0, 0}, {0, 0, 0}, {0, -1, 0}, no_hit), no_hit);       // origin on it
}

// Large world coordinates: the plane's point is subtracted before the dot product.
TEST(IntersectPlane, FarFromTheOrigin) {
  EXPECT_DOUBLE_EQ(intersect_plane({0, 1, 0}, {3e9, 1e9 + 0.25, 0}, {3e9 + 7, 1e9 + 1.25, 5}, {0, -1, 0}, no_hit), 1.0);
}

TEST(IntersectTriangle, InsideOutsideAndBackFacing) {
  const glm::dvec3 a(-1, -1, 0), b(1, -1, 0), c(0, 1, 0);
  EXPECT_DOUBLE_EQ(intersect_triangle(a, b, c, {0, 0, 3}, minus_z, no_hit), 3.0);
  EXPECT_DOUBLE_EQ(intersect_triangle(a, c, b, {0, 0, 3}, minus_z, no_hit), 3.0);  // other winding
  EXPECT_DOUBLE_EQ(intersect_triangle(a, b, c, {0, 0, -3}, {0, 0, 1}, no_hit), 3.0);
  EXPECT_EQ(intersect_triangle(a, b, c, {0.9, 0.9, 3}, minus_z, no_hit), no_hit);
  EXPECT_EQ(intersect_triangle(a, b, c, {0, 0, -3}, minus_z, no_hit), no_hit);  // behind the origin
  // Oblique ray: from (0, 0, 3) towards (0.25, -0.5, 0).
  const glm::dvec3 dir = glm::normalize(glm::dvec3(0.25, -0.5, -3));
  EXPECT_NEAR(intersect_triangle(a, b, c, {0, 0, 3}, dir, no_hit), glm::length(glm::dvec3(0.25, -0.5, -3)), 1e-15);
}

TEST(IntersectTriangle, DegenerateAndEdgeOnMiss) {
  EXPECT_EQ(intersect_triangle({-1, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, 0, 3}, minus_z, no_hit), no_hit);  // collinear
  EXPECT_EQ(intersect_triangle({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0, 0.5, 3}, minus_z, no_hit), no_hit);  // repeated
  // Ray lying in the triangle's plane.
  EXPECT_EQ(intersect_triangle({-1, 0, -1}, {1, 0, -1}, {0, 0, 1}, {0, 0, 3}, minus_z, no_hit), no_hit);
}

TEST(IntersectTriangle, NeedleTriangle) {
  // 2 long, 1e-9 high at its tip: a ray through its middle hits at the exact distance.
  const double t = intersect_triangle({-1, 0, 0}, {1, 0, 0}, {0, 1e-9, 0}, {0, 0.25e-9, 2}, minus_z, no_hit);
  EXPECT_DOUBLE_EQ(t, 2.0);
}

// Two triangles sharing the diagonal of a quad; rays through points of the diagonal must hit at
// least one of them. (The diagonal's end points are corners of the quad's outline, where a rounded
// ray may legitimately pass outside both.)
TEST(IntersectTriangle, SharedEdgeIsWatertight) {
  const glm::dvec3 p00(-1.3, -0.7, 0.2), p10(1.1, -0.9, -0.3), p01(-0.8, 1.2, 0.4), p11(0.9, 1.05, -0.1);
  const glm::dvec3 origin(0.17, 0.05, 4.0);
  int misses = 0;
  for (int k = 1; k < 1000; ++k) {
    const double s = k / 1000.0;
    const glm::dvec3 on_edge = p10 + s * (p01 - p10);
    const glm::dvec3 dir = glm::normalize(on_edge - origin);
    const double t1 = intersect_triangle(p00, p10, p01, origin, dir, no_hit);
    const double t2 = intersect_triangle(p10, p11, p01, origin, dir, no_hit);
    misses += (t1 == no_hit && t2 == no_hit);
  }
  EXPECT_EQ(misses, 0);
}

TEST(ReferenceScene, NearestHitWinsAndNormalFacesTheRay) {
  Scene scene;
  scene.spheres.push_back({{0, 0, -10}, 1});
  scene.planes.push_back({{0, 0, -5}, {0, 0, -1}});  // normal pointing away from the camera
  Mesh mesh;
  mesh.positions = {{-1, -1, -20}, {1, -1, -20}, {0, 1, -20}};
  mesh.triangles = {{0, 1, 2}};
  scene.meshes.push_back(mesh);
  const ReferenceScene reference(scene);
  const ReferenceHit plane_hit = reference.trace({0, 0, 0}, minus_z);
  EXPECT_EQ(plane_hit.kind, PrimitiveKind::plane);
  EXPECT_DOUBLE_EQ(plane_hit.t, 5.0);
  EXPECT_EQ(plane_hit.normal, glm::dvec3(0, 0, 1));  // turned to face the ray
  const ReferenceHit sphere_hit = reference.trace({0, 0, -6}, minus_z);
  EXPECT_EQ(sphere_hit.kind, PrimitiveKind::sphere);
  EXPECT_DOUBLE_EQ(sphere_hit.t, 3.0);
  EXPECT_EQ(sphere_hit.normal, glm::dvec3(0, 0, 1));
  const ReferenceHit triangle_hit = reference.trace({0, 0, -12}, minus_z);
  EXPECT_EQ(triangle_hit.kind, PrimitiveKind::triangle);
  EXPECT_DOUBLE_EQ(triangle_hit.t, 8.0);
  EXPECT_EQ(triangle_hit.normal, glm::dvec3(0, 0, 1));
  EXPECT_EQ(reference.trace({0, 0, -12}, {0, 0, 1}).kind, PrimitiveKind::sphere);
  EXPECT_EQ(reference.trace({5, 5, 0}, {0, 1, 0}).kind, PrimitiveKind::none);
}

}  // namespace
}  // namespace vkray
