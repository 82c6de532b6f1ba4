// The geometry of point queries, written once for the host (the fp64 reference, in double) and the
// shaders (float32): the nearest point of a triangle, of a sphere and of a plane to a query point, and
// a triangle's solid angle seen from it (the winding number's term). Every position is given
// relative to the query point, so that what is near it keeps its digits however far both lie from
// the world's origin (as rays take vertices relative to their origin).
#ifndef VKRAY_POINT_GEOMETRY_H
#define VKRAY_POINT_GEOMETRY_H

#ifdef __cplusplus
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
namespace vkray::point_geometry {
using real = double;
using real2 = glm::dvec2;
using real3 = glm::dvec3;
using glm::cross;
using glm::dot;
using glm::length;
using std::sqrt;
inline double atan(double y, double x) { return std::atan2(y, x); }
#define VKRAY_POINT_FUNCTION inline
#define VKRAY_POINT_PRECISE
#else
#define VKRAY_POINT_FUNCTION
#define VKRAY_POINT_PRECISE precise
#endif

// The nearest point of triangle (a, b, c) to the query point, the vertices relative to it: the
// weights (v, w) of b and c, the point a + v (b - a) + w (c - a). Ericson, "Real-Time Collision
// Detection" (2005), 5.1.5: the regions of the three vertices, then of the three edges, are told by
// signs of dot products of the edges with the vertices; what is left is the face, whose weights are
// its two subtriangles' areas over the whole's, in the plane of the triangle (va, vb, vc: the
// areas, from the same dot products). Each weight is clamped to its region, so that the point lies
// on the triangle whatever the rounding; a triangle of zero area (never stored) would give an edge.
VKRAY_POINT_FUNCTION real2 nearest_on_triangle(real3 a, real3 b, real3 c) {
  real3 ab = b - a, ac = c - a;
  // (The query point is the origin: p - a = -a.)
  VKRAY_POINT_PRECISE real d1 = -dot(ab, a), d2 = -dot(ac, a);
  if (d1 <= 0.0 && d2 <= 0.0) return real2(0.0, 0.0);  // vertex a
  VKRAY_POINT_PRECISE real d3 = -dot(ab, b), d4 = -dot(ac, b);
  if (d3 >= 0.0 && d4 <= d3) return real2(1.0, 0.0);  // vertex b
  VKRAY_POINT_PRECISE real vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return real2(d1 / (d1 - d3), 0.0);  // edge ab
  VKRAY_POINT_PRECISE real d5 = -dot(ab, c), d6 = -dot(ac, c);
  if (d6 >= 0.0 && d5 <= d6) return real2(0.0, 1.0);  // vertex c
  VKRAY_POINT_PRECISE real vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return real2(0.0, d2 / (d2 - d6));  // edge ac
  VKRAY_POINT_PRECISE real va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {  // edge bc
    real w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return real2(1.0 - w, w);
  }
  real denominator = va + vb + vc;
  real v = vb / denominator, w = vc / denominator;
  return real2(v, w);
}

#if !defined(__cplusplus) && defined(VKRAY_FLOAT64)
// atan2 in double, which GLSL lacks (its atan takes floats: 6e-8 of an angle, where the float64
// shaders' winding numbers are to keep double's digits). The quotient of the smaller over the larger
// magnitude, t in [0, 1], taken below tan(pi / 12) by atan(t) = pi / 6 + atan((t sqrt3 - 1) / (t + sqrt3))
// (GLSL's literals are floats without LF.) (Cody and Waite, "Software Manual for the Elementary Functions", 1980, 11.2); there the series
// t - t^3 / 3 + t^5 / 5 - ..., whose 15th term, 0.268^29 / 29, is below 2^-57; then the octant's
// reflections.
double atan_of_doubles(double y, double x) {
  double ax = abs(x), ay = abs(y);
  if (ax == 0.0 && ay == 0.0) return 0.0;  // as atan2(0, +0)
  bool swapped = ay > ax;
  double t = swapped ? ax / ay : ay / ax;
  const double sqrt3 = 1.7320508075688772935LF, tan_pi_12 = 0.26794919243112270LF;
  double shift = 0.0;
  if (t > tan_pi_12) {
    t = (t * sqrt3 - 1.0) / (t + sqrt3);
    shift = 0.52359877559829887308LF;  // pi / 6
  }
  double t2 = t * t, sum = 0.0;
  for (int k = 14; k >= 0; --k) sum = 1.0 / double(2 * k + 1) - t2 * sum;
  double angle = shift + t * sum;
  if (swapped) angle = 1.57079632679489661923LF - angle;
  if (x < 0.0) angle = 3.14159265358979323846LF - angle;
  return y < 0.0 ? -angle : angle;
}
#endif

// The solid angle triangle (a, b, c) subtends at the query point, the vertices relative to it,
// signed by its winding (positive where a, b, c run counter-clockwise seen from the point): van
// Oosterom and Strackee, "The Solid Angle of a Plane Triangle", IEEE Trans. Biomed. Eng. 30(2),
// 1983: tan(omega / 2) = a . (b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|), taken with
// atan2 so that the angle is right in (-2 pi, 2 pi) on both sides of the triangle's plane. Over
// 4 pi, the triangle's share of the winding number (Jacobson, Kavan and Sorkine-Hornung, "Robust
// Inside-Outside Segmentation using Generalized Winding Numbers", SIGGRAPH 2013).
VKRAY_POINT_FUNCTION real solid_angle(real3 a, real3 b, real3 c) {
  real la = length(a), lb = length(b), lc = length(c);
  VKRAY_POINT_PRECISE real numerator = dot(a, cross(b, c));
  VKRAY_POINT_PRECISE real denominator = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
#if !defined(__cplusplus) && defined(VKRAY_FLOAT64)
  return 2.0 * atan_of_doubles(numerator, denominator);
#else
  return 2.0 * atan(numerator, denominator);
#endif
}

#ifdef __cplusplus
}  // namespace vkray::point_geometry
#endif
#undef VKRAY_POINT_FUNCTION
#undef VKRAY_POINT_PRECISE
#endif  // VKRAY_POINT_GEOMETRY_H
