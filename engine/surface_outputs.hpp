// The surface outputs of a camera's frame (docs/outputs.md, "Output contract"): what the primitive each
// pixel's ray hit gives at the hit, evaluated on the host in double from the frame's ids and the
// pixel's ray, so that the device keeps no per-corner attributes and computes nothing more.
#pragma once

#include "engine/frame.hpp"
#include "engine/scene/scene.hpp"

namespace vkray {

// Fills the barycentric, shading-normal, texcoord and front-facing outputs `frame.aovs` asks for; `scene` is the
// one rendered (its meshes give the triangles, normals and texture coordinates the ids name).
// - barycentric: the weights (b1, b2) of the triangle's second and third vertices where the
//   pixel's ray in double (CameraBasis) meets the triangle's plane, clamped onto the triangle (the
//   device may take a triangle the double ray passes a rounding outside); the hit point from the
//   depth where the ray lies in the plane. 0 for spheres, planes and misses.
// - shading-normal: the triangle's vn interpolated with those weights and normalized, negated
//   where the ray meets the triangle's back (the side from which its vertices run clockwise), so
//   that it lies on the ray's side as the geometric normal output does; a triangle without vn
//   (or whose interpolated vn vanishes), a sphere or a plane gives its geometric normal facing the
//   ray. 0 on a miss.
// - texcoord: the triangle's vt (u, v) interpolated with those weights; 0 without vt.
// - front-facing: 1 where the pixel's ray meets a triangle whose vertices run counter-clockwise as
//   it sees them (its face normal, (b - a) x (c - a), points against the ray), a sphere from
//   outside (the ray's origin at least a radius from its centre) or a plane from the side its
//   normal points to; 0 elsewhere and on a miss.
void add_surface_outputs(Frame& frame, const Scene& scene);

// What `hit` gives where the ray (origin, unit direction dir) meets it at distance t, as the
// outputs above describe each: a camera's pixels and given rays (the C API's cast_rays) alike.
struct SurfaceAt {
  glm::dvec2 barycentric{0.0};
  glm::dvec3 shading_normal{0.0};
  glm::dvec2 texcoord{0.0};
  bool front = false;
};
// A triangle an instance places (`instance`, else no_object) is evaluated in its mesh's coordinates,
// the ray taken there as the reference takes it; its shading normal comes back through the inverse
// transpose (which keeps the side of the ray it lies on), and a mirroring instance turns its winding
// over: front where the placed vertices run counter-clockwise, as the scene flattened would have it.
SurfaceAt surface_at(const Scene& scene, ObjectPrimitive hit, const glm::dvec3& origin, const glm::dvec3& dir, double t,
                     uint32_t instance = no_object);

// What the primitive `found` (an instance's triangle where `instance` names one) gives at `nearest`, a
// point of it (a point query's answer): its outward unit normal (a triangle's by its winding, the
// face normal (b - a) x (c - a) normalized; through an instance's inverse transpose, turned where
// it mirrors, so that it points out of the placed solid; a sphere's away from its centre; a plane's
// own) and a triangle's weights (b1, b2) there (0 elsewhere).
struct PointSurface {
  glm::dvec3 normal{0.0};
  glm::dvec2 barycentric{0.0};
};
PointSurface point_surface(const Scene& scene, ObjectPrimitive found, uint32_t instance, const glm::dvec3& nearest);

}  // namespace vkray
