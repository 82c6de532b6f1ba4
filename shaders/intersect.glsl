// Ray/primitive intersection in float32. Each routine returns the ray parameter t of the nearest
// hit with 0 < t < t_max, or t_max when there is none. Rays are normalized, so t is a distance.
// The double-precision reference (engine/reference.cpp) evaluates the same formulas in double.
#ifndef VKRAY_INTERSECT_GLSL
#define VKRAY_INTERSECT_GLSL

#include "gpu_layout.h"

layout(constant_id = VKRAY_SPEC_SPHERE_FORMULA) const uint SPHERE_FORMULA = VKRAY_SPHERE_STABLE;
layout(constant_id = VKRAY_SPEC_TRIANGLE_TEST) const uint TRIANGLE_TEST = VKRAY_TRIANGLE_WATERTIGHT;

// s + e == a + b exactly (Knuth's TwoSum).
void two_sum(float a, float b, out float s, out float e) {
  precise float sum = a + b;
  precise float b_virtual = sum - a;
  precise float a_virtual = sum - b_virtual;
  precise float error = (a - a_virtual) + (b - b_virtual);
  s = sum;
  e = error;
}

// p + e == a * b exactly (Dekker's TwoProduct with Veltkamp's split). It is written with plain
// products and sums rather than fma, because Vulkan lets fma be evaluated unfused (lavapipe does).
void two_product(float a, float b, out float p, out float e) {
  const float splitter = 4097.0;  // 2^12 + 1 splits a float's 24-bit significand into 12 + 12 bits
  precise float a_big = splitter * a;
  precise float a_hi = a_big - (a_big - a);
  precise float a_lo = a - a_hi;
  precise float b_big = splitter * b;
  precise float b_hi = b_big - (b_big - b);
  precise float b_lo = b - b_hi;
  precise float product = a * b;
  precise float error = ((a_hi * b_hi - product) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo;
  p = product;
  e = error;
}

// |f|^2 - r^2 as if computed in twice the float precision, then rounded: products and sums are
// split into exact value and error terms (Ogita, Rump and Oishi, "Accurate Sum and Dot
// Product", SIAM J. Sci. Comput. 26(6), 2005, algorithm Dot2). Plain float loses all digits when
// the camera is near the surface of a sphere much larger than that distance (a planet as ground).
// Only rays that pass the discriminant test get here, so the cost is one call per hit candidate.
// Adds a * b to the running sum and its error term (one step of Dot2).
void dot2_step(float a, float b, inout float sum, inout float error) {
  float product, product_error, sum_error;
  two_product(a, b, product, product_error);
  two_sum(sum, product, sum, sum_error);
  precise float total_error = error + (sum_error + product_error);
  error = total_error;
}

float sphere_c(vec3 f, float radius) {
  float sum, error;
  two_product(f.x, f.x, sum, error);
  dot2_step(f.y, f.y, sum, error);
  dot2_step(f.z, f.z, sum, error);
  dot2_step(radius, -radius, sum, error);
  precise float c = sum + error;
  return c;
}

// Ray/sphere after Haines, Guenther and Akenine-Moeller, "Precision Improvements for Ray/Sphere
// Intersection", Ray Tracing Gems (2019), ch. 7:
// - the discriminant is r^2 - |f_perp|^2, with f_perp the part of (origin - center) orthogonal to
//   the ray, instead of b^2 - c, which cancels catastrophically for small spheres far away;
// - the two roots come from q = -(b + sign(b) sqrt(disc)) as c/q and q/a, so neither root is a
//   difference of nearly equal numbers; c itself comes from sphere_c.
// The textbook form, kept as a benchmark variant (VKRAY_SPHERE_NAIVE) to show what the stable one
// buys: b^2 - c cancels when the sphere is small against its distance, -b + sqrt(disc) when the
// camera is inside, and c = |f|^2 - r^2 loses everything near a large sphere's surface.
float intersect_sphere_naive(vec3 f, float radius, vec3 dir, float t_max) {
  float b = dot(f, dir);
  float disc = b * b - (dot(f, f) - radius * radius);
  if (disc < 0.0) return t_max;
  float root = sqrt(disc);
  float t = -b - root > 0.0 ? -b - root : -b + root;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

float intersect_sphere(vec3 f, float radius, vec3 dir, float t_max) {
  if (SPHERE_FORMULA == VKRAY_SPHERE_NAIVE) return intersect_sphere_naive(f, radius, dir, t_max);
  float a = dot(dir, dir);
  float b = dot(f, dir);
  vec3 f_perp = f - (b / a) * dir;
  float disc = radius * radius - dot(f_perp, f_perp);
  if (disc < 0.0) return t_max;
  float c = sphere_c(f, radius);
  float q = -(b + (b >= 0.0 ? 1.0 : -1.0) * sqrt(a * disc));
  if (q == 0.0) return t_max;  // origin on the surface and tangent ray: no hit in front
  float t0 = c / q;
  float t1 = q / a;
  float t_near = min(t0, t1);
  float t_far = max(t0, t1);
  float t = t_near > 0.0 ? t_near : t_far;  // camera inside the sphere: the far root
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Ray/plane: t = (offset - n.o) / (n.d). A ray parallel to the plane (n.d == 0) never hits it,
// which the explicit test states instead of relying on inf/NaN comparisons.
float intersect_plane(vec4 normal_offset, vec3 origin, vec3 dir, float t_max) {
  float denom = dot(normal_offset.xyz, dir);
  if (denom == 0.0) return t_max;
  float t = (normal_offset.w - dot(normal_offset.xyz, origin)) / denom;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Watertight ray/triangle test of Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection",
// JCGT 2(1), 2013. The vertices are moved into a ray-aligned frame in which the ray is the +z axis;
// the 2D edge functions U, V, W then decide inside/outside. Two triangles sharing an edge evaluate
// the same edge function with opposite sign from bit-identical inputs, so a ray through a shared
// edge hits at least one of them: no cracks between the triangles of a mesh (Moeller-Trumbore
// computes barycentrics per triangle and can miss both). `precise` forbids the compiler from
// fusing these products into FMAs differently per triangle, which would break that symmetry.
struct RayFrame {
  int kz;       // dominant axis of the direction: the ray frame's z
  bool swap_xy; // keeps the winding of the projected triangle when dir[kz] < 0
  vec3 shear;   // Sx, Sy, Sz
};

// (p[kx], p[ky], p[kz]) with kx = (kz + 1) % 3, ky = (kx + 1) % 3, swapped when the frame says so.
// Written with selects, not dynamic component indexing, which compilers turn into memory accesses.
vec3 permute(RayFrame frame, vec3 p) {
  vec3 q = frame.kz == 0 ? p.yzx : (frame.kz == 1 ? p.zxy : p);
  return frame.swap_xy ? q.yxz : q;
}

RayFrame make_ray_frame(vec3 dir) {
  vec3 ad = abs(dir);
  RayFrame frame;
  frame.kz = (ad.x > ad.y) ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
  frame.swap_xy = false;
  frame.swap_xy = permute(frame, dir).z < 0.0;
  vec3 d = permute(frame, dir);
  frame.shear = vec3(d.x / d.z, d.y / d.z, 1.0 / d.z);
  return frame;
}

// Vertex relative to the ray origin, in the ray frame (z not yet scaled by Sz).
vec3 to_ray_frame(RayFrame frame, vec3 vertex, vec3 origin) {
  precise vec3 p = permute(frame, vertex - origin);
  precise float px = p.x - frame.shear.x * p.z;
  precise float py = p.y - frame.shear.y * p.z;
  return vec3(px, py, p.z);
}

// Moeller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection", JGT 2(1), 1997: a
// benchmark variant (VKRAY_TRIANGLE_MOLLER_TRUMBORE). Barycentrics are computed per triangle, so a
// ray through an edge shared by two triangles can miss both.
float intersect_triangle_moller_trumbore(vec3 origin, vec3 dir, vec3 v0, vec3 v1, vec3 v2, float t_max) {
  vec3 e1 = v1 - v0;
  vec3 e2 = v2 - v0;
  vec3 p = cross(dir, e2);
  float det = dot(e1, p);
  if (det == 0.0) return t_max;
  float inv_det = 1.0 / det;
  vec3 s = origin - v0;
  float u = dot(s, p) * inv_det;
  if (u < 0.0 || u > 1.0) return t_max;
  vec3 q = cross(s, e1);
  float v = dot(dir, q) * inv_det;
  if (v < 0.0 || u + v > 1.0) return t_max;
  float t = dot(e2, q) * inv_det;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

float intersect_triangle(RayFrame frame, vec3 origin, vec3 dir, vec3 v0, vec3 v1, vec3 v2, float t_max) {
  if (TRIANGLE_TEST == VKRAY_TRIANGLE_MOLLER_TRUMBORE) return intersect_triangle_moller_trumbore(origin, dir, v0, v1, v2, t_max);
  vec3 a = to_ray_frame(frame, v0, origin);
  vec3 b = to_ray_frame(frame, v1, origin);
  vec3 c = to_ray_frame(frame, v2, origin);
  precise float u = c.x * b.y - c.y * b.x;
  precise float v = a.x * c.y - a.y * c.x;
  precise float w = b.x * a.y - b.y * a.x;
  if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return t_max;
  float det = u + v + w;
  if (det == 0.0) return t_max;  // ray in the triangle's plane, or a degenerate projection
  float t = frame.shear.z * (u * a.z + v * b.z + w * c.z) / det;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// 1 / dir, with components below 1e-37 in magnitude (in practice: exactly 0, a ray parallel to a
// slab) replaced by the largest float of the same sign: never the NaN of 0 * inf (GLSL's min and
// max are undefined on NaN), and the slab interval is still right. Box faces lie at least
// VKRAY_BOX_MARGIN from anything inside (engine/gpu_scene.cpp), so when the origin is inside the
// slab both ends are at least 1e-20 * 3.4e38 away, beyond any hit (coordinates stay within 1e15);
// when it lies outside, the interval is empty or starts beyond any hit; and a ray exactly in the
// plane of a face can meet nothing in the box.
vec3 safe_inverse(vec3 dir) {
  const float tiny = 1e-37;
  const float largest = 3.4028235e38;
  bvec3 parallel = lessThan(abs(dir), vec3(tiny));
  vec3 signed_largest = mix(vec3(largest), vec3(-largest), lessThan(dir, vec3(0.0)));
  return mix(1.0 / mix(dir, vec3(1.0), parallel), signed_largest, parallel);
}

// Slab tests of a ray against two boxes at once (a BVH node's children; see GpuBvhNode for the
// layout), conservative under rounding: the far distance is enlarged by 1 + 2 gamma(3),
// gamma(n) = n u / (1 - n u), u = 2^-24, which covers the error of the three operations behind
// each slab distance (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013). A ray that meets a box is
// never rejected, so culling by box can not open holes in a mesh. Likewise the near distance is
// shrunk by 1 - 2 gamma(3) before it is compared with t_max, so a box entered at the nearest hit so
// far up to rounding is still visited. `enter` is where the ray enters each box (0 when it starts
// inside). See safe_inverse for rays parallel to a slab.
bvec2 ray_hits_boxes(vec4 bounds_x, vec4 bounds_y, vec4 bounds_z, vec3 origin, vec3 inv_dir, float t_max,
                     out vec2 enter) {
  vec4 tx = (bounds_x - origin.x) * inv_dir.x;
  vec4 ty = (bounds_y - origin.y) * inv_dir.y;
  vec4 tz = (bounds_z - origin.z) * inv_dir.z;
  vec2 near = max(max(min(tx.xy, tx.zw), min(ty.xy, ty.zw)), max(min(tz.xy, tz.zw), vec2(0.0)));
  const float gamma3 = 1.7881396e-7;  // 3 * 2^-24 / (1 - 3 * 2^-24), rounded up
  vec2 far = min(min(max(tx.xy, tx.zw), max(ty.xy, ty.zw)), max(tz.xy, tz.zw)) * (1.0 + 2.0 * gamma3);
  enter = near;
  vec2 near_low = near * (1.0 - 2.0 * gamma3);
  return bvec2(near.x <= far.x && near_low.x < t_max, near.y <= far.y && near_low.y < t_max);
}

#endif  // VKRAY_INTERSECT_GLSL
