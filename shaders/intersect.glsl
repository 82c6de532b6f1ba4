// Ray/primitive intersection. Each routine returns the ray parameter t of the nearest hit with
// 0 < t < t_max, or t_max when there is none. Rays are normalized, so t is a distance.
// float32 shaders evaluate the formulas below with the compensations each explains; float64 shaders
// (VKRAY_FLOAT64, `--precision double`) evaluate the reference's formulas (engine/reference/reference.cpp) in
// double: the exact, slow end of the error-against-time curve.
#ifndef VKRAY_INTERSECT_GLSL
#define VKRAY_INTERSECT_GLSL

#include "gpu_layout.h"

#ifdef VKRAY_FLOAT64
#define real double
#define real2 dvec2
#define real3 dvec3
#define real4 dvec4
#else
#define real float
#define real2 vec2
#define real3 vec3
#define real4 vec4
#endif

layout(constant_id = VKRAY_SPEC_SPHERE_FORMULA) const uint SPHERE_FORMULA = VKRAY_SPHERE_STABLE;
layout(constant_id = VKRAY_SPEC_TRIANGLE_TEST) const uint TRIANGLE_TEST = VKRAY_TRIANGLE_WATERTIGHT;
layout(constant_id = VKRAY_SPEC_COORDINATES) const uint COORDINATES = VKRAY_COORDINATES_CAMERA_RELATIVE;

layout(constant_id = VKRAY_SPEC_LO_PARTS) const bool LO_PARTS = true;
// Whether the lo parts of positions are added: camera-relative coordinates, the camera near the scene.
const bool use_lo_parts = COORDINATES == VKRAY_COORDINATES_CAMERA_RELATIVE && LO_PARTS;

// The ray's origin: the camera, split into hi and lo parts relative to the anchor in float32
// shaders (see GpuPoint in gpu_layout.h), in world coordinates in float64 shaders.
struct Origin {
#ifdef VKRAY_FLOAT64
  dvec3 position;
#else
  vec3 hi;
  vec3 lo;
#endif
};

#ifndef VKRAY_FLOAT64
// Error-free transformations. Vulkan lets a compiler fuse a * b + c into an fma or not (lavapipe
// does not), so they are written with plain operations marked `precise`, which forbids both fusing
// and reassociation. One body for float and vec3 (component-wise).
// s + e == a + b exactly (Knuth's TwoSum).
#define VKRAY_DEFINE_TWO_SUM(T)                      \
  void two_sum(T a, T b, out T s, out T e) {         \
    precise T sum = a + b;                           \
    precise T b_virtual = sum - a;                   \
    precise T a_virtual = sum - b_virtual;           \
    precise T error = (a - a_virtual) + (b - b_virtual); \
    s = sum;                                         \
    e = error;                                       \
  }
// p + e == a * b exactly (Dekker's TwoProduct with Veltkamp's split: 2^12 + 1 splits a float's
// 24-bit significand into 12 + 12 bits).
#define VKRAY_DEFINE_TWO_PRODUCT(T)                  \
  void two_product(T a, T b, out T p, out T e) {     \
    const float splitter = 4097.0;                   \
    precise T a_big = splitter * a;                  \
    precise T a_hi = a_big - (a_big - a);            \
    precise T a_lo = a - a_hi;                       \
    precise T b_big = splitter * b;                  \
    precise T b_hi = b_big - (b_big - b);            \
    precise T b_lo = b - b_hi;                       \
    precise T product = a * b;                       \
    precise T error = ((a_hi * b_hi - product) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo; \
    p = product;                                     \
    e = error;                                       \
  }
VKRAY_DEFINE_TWO_SUM(float)
VKRAY_DEFINE_TWO_SUM(vec3)
VKRAY_DEFINE_TWO_PRODUCT(float)
VKRAY_DEFINE_TWO_PRODUCT(vec3)

// dot(a, b) as an unevaluated sum: the sum of the rounded products plus everything their rounding
// and summation left out (Ogita, Rump and Oishi, "Accurate Sum and Dot Product", SIAM J. Sci.
// Comput. 26(6), 2005, algorithm Dot2): as accurate as if computed in twice the precision.
void dot2(vec3 a, vec3 b, out float sum, out float error) {
  vec3 products, product_errors;
  two_product(a, b, products, product_errors);
  float e1, e2;
  two_sum(products.x, products.y, sum, e1);
  two_sum(sum, products.z, sum, e2);
  precise float total = (e1 + e2) + (product_errors.x + product_errors.y + product_errors.z);
  error = total;
}

// A position relative to the camera, from its GpuPoint parts and the camera's (see gpu_layout.h):
// hi - hi and lo - lo first, so the result is accurate to float32 relative to its own size. With
// plain float coordinates, or the camera far from the scene, the lo parts are left out.
vec3 relative_to_camera(vec3 hi, vec3 lo, vec3 origin_hi, vec3 origin_lo) {
  precise vec3 difference = hi - origin_hi;
  if (!use_lo_parts) return difference;
  precise vec3 sum = difference + (lo - origin_lo);
  return sum;
}

// f = origin - center as an unevaluated sum f_hi + f_lo, |f_lo| <= ulp(f_hi) / 2 (f_lo = 0 with
// plain float coordinates).
void sphere_offset(vec3 center_hi, vec3 center_lo, vec3 origin_hi, vec3 origin_lo, out vec3 f_hi, out vec3 f_lo) {
  if (!use_lo_parts) {
    f_hi = origin_hi - center_hi;
    f_lo = vec3(0.0);
    return;
  }
  vec3 difference, error;
  two_sum(origin_hi, -center_hi, difference, error);
  precise vec3 lo = error + (origin_lo - center_lo);
  // Renormalized, so that |f_lo| <= ulp(f_hi) / 2 as sphere_c assumes: when the centre is near the
  // camera, difference is exact but short (its bits above the anchor's ulp), and lo as large.
  two_sum(difference, lo, f_hi, f_lo);
}

// c = |f|^2 - r^2 from f = f_hi + f_lo and r = r_hi + r_lo, as accurate as if computed in twice the
// precision (Dot2 above). Plain float loses all digits near the surface of a sphere much larger
// than the camera's height above it (a planet as ground): c = 2 r h there, a difference of two
// numbers near r^2. Only rays that pass the discriminant test compute it.
float sphere_c(vec3 f_hi, vec3 f_lo, float r_hi, float r_lo) {
  float sum, error;
  dot2(f_hi, f_hi, sum, error);
  float square, square_error;
  two_product(r_hi, -r_hi, square, square_error);
  float total_error;
  two_sum(sum, square, sum, total_error);
  precise float small_terms = 2.0 * (dot(f_hi, f_lo) - r_hi * r_lo);
  precise float c = sum + (((error + square_error) + total_error) + small_terms);
  return c;
}

// The part of f = f_hi + f_lo orthogonal to dir, given b = f.dir / dir.dir: f - b dir with the
// products and the subtraction error-free, then what is left along dir (from b's own rounding)
// projected out. Accurate to float32 relative to |f_perp|, which is at most the radius for a hit,
// even when |f| is 1e7 times larger: this is what keeps a small sphere far away round.
vec3 perpendicular_part(vec3 f_hi, vec3 f_lo, float b_over_a, vec3 dir) {
  vec3 products, product_errors;
  two_product(vec3(b_over_a), dir, products, product_errors);
  vec3 sums, sum_errors;
  two_sum(f_hi, -products, sums, sum_errors);
  precise vec3 f_perp = sums + ((sum_errors - product_errors) + f_lo);
  return f_perp - (dot(f_perp, dir) / dot(dir, dir)) * dir;
}

// Ray/sphere after Haines, Guenther and Akenine-Moeller, "Precision Improvements for Ray/Sphere
// Intersection", Ray Tracing Gems (2019), ch. 7:
// - the discriminant is r^2 - |f_perp|^2, with f_perp the part of f = origin - center orthogonal
//   to the ray, instead of b^2 - c, which cancels catastrophically for small spheres far away (and
//   b^2 / a - c where that is the form that does not cancel: see intersect_sphere);
// - the two roots come from q = -(b + sign(b) sqrt(disc)) as c/q and q/a, so neither root is a
//   difference of nearly equal numbers.
// `normal` receives the hit point minus the centre over the radius, facing the ray by which root was
// taken (outward for the near root, inward from inside), not by the sign of its dot product with
// the ray, which rounding decides at the silhouette, where it is 0. Where the near root is the one
// taken (the ray enters ahead), `far_root` receives the far one, where it leaves, else t_max:
// counting crossings adds it, a tangent ray's double root too (twice, so the count's parity is
// kept); `far_normal` is its normal facing the ray (inward), for a list of first hits.
// The textbook form, kept as a benchmark variant (VKRAY_SPHERE_NAIVE) to show what this buys:
// b^2 - c cancels when the sphere is small against its distance, -b + sqrt(disc) when the camera is
// inside, c = |f|^2 - r^2 near a large sphere's surface, and f + t dir for any small sphere far away.
float intersect_sphere_naive(vec3 f, float radius, vec3 dir, float t_max, out vec3 normal, out float far_root,
                             out vec3 far_normal) {
  float b = dot(f, dir);
  float disc = b * b - (dot(f, f) - radius * radius);
  normal = vec3(0.0);
  far_root = t_max;
  far_normal = vec3(0.0);
  if (disc < 0.0) return t_max;
  float root = sqrt(disc);
  bool near = -b - root > 0.0;
  far_root = near ? -b + root : t_max;
  far_normal = -(f + (-b + root) * dir) / radius;
  float t = near ? -b - root : -b + root;
  normal = (near ? 1.0 : -1.0) * (f + t * dir) / radius;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Every result that reaches an output is `precise` (here and in the other tests): the same pixel
// must get the same bits from every pipeline that computes it (workgroup shapes, the generic and
// storage-geometry variants; tests/shader_variant_test.cpp), and a compiler may otherwise fuse a
// product and a sum into an FMA in one pipeline and not in another.
float intersect_sphere_scaled(vec3 f_hi, vec3 f_lo, float r_hi, float r_lo, vec3 dir, float t_max, out vec3 normal,
                              out float far_root, out vec3 far_normal);

// The test below squares lengths: for a sphere 1e-20 across they fall below float32's range, for one
// near 1e19 above it. So f and r are first scaled by the power of two that brings r near 1, and the
// distances found are scaled back: exact both ways (a power of two changes no bit of a float's
// significand), so a sphere of any size gets the bits it would get at r = 1; normals are ratios
// of scaled lengths and need nothing.
float intersect_sphere(vec3 f_hi, vec3 f_lo, float r_hi, float r_lo, vec3 dir, float t_max, out vec3 normal,
                       out float far_root, out vec3 far_normal) {
  if (SPHERE_FORMULA == VKRAY_SPHERE_NAIVE) {
    return intersect_sphere_naive(f_hi + f_lo, r_hi, dir, t_max, normal, far_root, far_normal);
  }
  int exponent;
  frexp(r_hi, exponent);
  float down = ldexp(1.0, -exponent), up = ldexp(1.0, exponent);
  float t = intersect_sphere_scaled(f_hi * down, f_lo * down, r_hi * down, r_lo * down, dir, t_max * down, normal, far_root,
                                    far_normal);
  // (Compared with t_max again after scaling back: a t_max scaled past float32's largest is inf.)
  precise float hit = t * up, far = far_root * up;
  far_root = far < t_max ? far : t_max;
  return hit < t_max ? hit : t_max;
}

float intersect_sphere_scaled(vec3 f_hi, vec3 f_lo, float r_hi, float r_lo, vec3 dir, float t_max, out vec3 normal,
                              out float far_root, out vec3 far_normal) {
  normal = vec3(0.0);
  far_root = t_max;
  far_normal = vec3(0.0);
  precise float a = dot(dir, dir);
  vec3 f = f_hi + f_lo;
  precise float ff = dot(f, f);
  precise float rr = r_hi * r_hi;
  precise float b = dot(f, dir);
  precise vec3 f_perp = f - (b / a) * dir;
  precise float disc = rr - dot(f_perp, f_perp);
  // Misses first, cheaply: this f_perp is within ~11 eps |f| of the exact one, so its square within
  // ~21 eps |f|^2, and the roundings of disc add ~3 eps (|f|^2 + r^2). Below -32 eps (|f|^2 + r^2)
  // (eps = 2^-24) no ray can hit.
  if (disc < -1.9073486e-6 * (ff + rr)) return t_max;
  // Two kinds of sphere, told apart by f alone, the camera's offset (the same for every ray: the
  // branch never diverges):
  // - far away (|f| > 4 r): c = |f|^2 - r^2 cannot cancel (it is above 15/16 |f|^2), but f_perp
  //   can: the error-free form keeps small spheres far away round;
  // - near (the camera within 4 r of the centre: inside, on, or near a large sphere): f_perp is
  //   good to 4 eps r, but c needs the error-free sum, and where |b| < r (a planet's horizon: rays
  //   along the surface, |f_perp| within a few units of r = 1e6) so does the discriminant, then
  //   taken as b^2 / a - c with b error-free too.
  bool far = ff > 16.0 * rr;
  float c;
  if (far) {
    f_perp = perpendicular_part(f_hi, f_lo, b / a, dir);
    disc = rr - dot(f_perp, f_perp);
    c = ff - rr;
  } else {
    c = sphere_c(f_hi, f_lo, r_hi, r_lo);
    precise float b_squared = b * b, a_rr = a * rr;
    if (b_squared < a_rr) {
      float sum, error;
      dot2(f_hi, dir, sum, error);
      b = sum + (error + dot(f_lo, dir));
      disc = (b * b) / a - c;
    }
  }
  if (disc < 0.0) return t_max;
  precise float root = sqrt(a * disc);
  precise float q = -(b + (b >= 0.0 ? root : -root));
  if (q == 0.0) return t_max;  // origin on the surface and tangent ray: no hit in front
  float t0 = c / q;
  float t1 = q / a;
  float t_near = min(t0, t1);
  bool near = t_near > 0.0;
  float t = near ? t_near : max(t0, t1);  // camera inside the sphere: the far root
  far_root = near ? max(t0, t1) : t_max;
  // The hit relative to the centre: for a sphere far away f_perp -+ sqrt(disc / a) dir (minus for
  // the near root), not f + t dir, a difference of two vectors as long as the distance; near, f + t
  // dir is within ~10 eps r.
  precise vec3 offset = far ? f_perp + ((near ? -root : root) / a) * dir : f + t * dir;
  normal = (near ? offset : -offset) / r_hi;  // facing the ray (see above)
  precise vec3 far_offset = far ? f_perp + (root / a) * dir : f + max(t0, t1) * dir;
  far_normal = -far_offset / r_hi;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

#else  // VKRAY_FLOAT64: the reference's formulas, in double

double intersect_sphere(dvec3 f, double radius, dvec3 dir, double t_max, out dvec3 normal, out double far_root,
                        out dvec3 far_normal) {
  normal = dvec3(0.0);
  far_root = t_max;
  far_normal = dvec3(0.0);
  precise double a = dot(dir, dir);
  precise double b = dot(f, dir);
  precise dvec3 f_perp = f - (b / a) * dir;
  precise double disc = radius * radius - dot(f_perp, f_perp);
  if (disc < 0.0) return t_max;
  precise double c = dot(f, f) - radius * radius;
  precise double root = sqrt(a * disc);
  precise double q = -(b + (b >= 0.0 ? root : -root));
  if (q == 0.0) return t_max;
  double t0 = c / q;
  double t1 = q / a;
  bool near = min(t0, t1) > 0.0;
  double t = near ? min(t0, t1) : max(t0, t1);
  far_root = near ? max(t0, t1) : t_max;
  precise dvec3 offset = f + t * dir;
  normal = (near ? 1.0 : -1.0) * offset / radius;
  precise dvec3 far_offset = f + max(t0, t1) * dir;
  far_normal = -far_offset / radius;
  return (t > 0.0 && t < t_max) ? t : t_max;
}


#endif  // VKRAY_FLOAT64

// Ray/plane: t = height / (n.d), height = dot(n, point - origin) the plane's signed offset from the
// ray origin along n (the host computes it per render in double: GpuPlane). A ray parallel to the
// plane (n.d == 0) never hits it, which the explicit test states instead of relying on inf/NaN.
real intersect_plane(real3 normal, real height, real3 dir, real t_max) {
  precise real denom = dot(normal, dir);
  if (denom == 0.0) return t_max;
  real t = height / denom;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Watertight ray/triangle test of Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection",
// JCGT 2(1), 2013. The vertices, already relative to the ray's origin, are moved into a ray-aligned
// frame in which the ray is the +z axis; the 2D edge functions U, V, W then decide inside/outside.
// Two triangles sharing an edge evaluate the same edge function with opposite sign from
// bit-identical inputs (a shared vertex is stored once per triangle with the same bits, and made
// relative to the camera by the same operations), so a ray through a shared edge hits at least one
// of them: no cracks between the triangles of a mesh (Moeller-Trumbore computes barycentrics per
// triangle and can miss both). `precise` forbids the compiler from fusing these products into FMAs
// differently per triangle, which would break that symmetry.
struct RayFrame {
  int kz;       // dominant axis of the direction: the ray frame's z
  bool swap_xy; // keeps the winding of the projected triangle when dir[kz] < 0
  real3 shear;  // Sx, Sy, Sz
};

// (p[kx], p[ky], p[kz]) with kx = (kz + 1) % 3, ky = (kx + 1) % 3, swapped when the frame says so.
// Written with selects, not dynamic component indexing, which compilers turn into memory accesses.
real3 permute(RayFrame frame, real3 p) {
  real3 q = frame.kz == 0 ? p.yzx : (frame.kz == 1 ? p.zxy : p);
  return frame.swap_xy ? q.yxz : q;
}

RayFrame make_ray_frame(real3 dir) {
  real3 ad = abs(dir);
  RayFrame frame;
  frame.kz = (ad.x > ad.y) ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
  frame.swap_xy = false;
  frame.swap_xy = permute(frame, dir).z < 0.0;
  real3 d = permute(frame, dir);
  frame.shear = real3(d.x / d.z, d.y / d.z, 1.0 / d.z);
  return frame;
}

// A vertex relative to the ray origin, in the ray frame (z not yet scaled by Sz).
real3 to_ray_frame(RayFrame frame, real3 vertex) {
  precise real3 p = permute(frame, vertex);
  precise real px = p.x - frame.shear.x * p.z;
  precise real py = p.y - frame.shear.y * p.z;
  return real3(px, py, p.z);
}

// Moeller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection", JGT 2(1), 1997: a
// benchmark variant (VKRAY_TRIANGLE_MOLLER_TRUMBORE). Barycentrics are computed per triangle, so a
// ray through an edge shared by two triangles can miss both. Vertices relative to the ray origin.
real intersect_triangle_moller_trumbore(real3 dir, real3 v0, real3 v1, real3 v2, real t_max) {
  real3 e1 = v1 - v0;
  real3 e2 = v2 - v0;
  real3 p = cross(dir, e2);
  real det = dot(e1, p);
  if (det == 0.0) return t_max;
  real inv_det = 1.0 / det;
  real3 s = -v0;
  real u = dot(s, p) * inv_det;
  if (u < 0.0 || u > 1.0) return t_max;
  real3 q = cross(s, e1);
  real v = dot(dir, q) * inv_det;
  if (v < 0.0 || u + v > 1.0) return t_max;
  real t = dot(e2, q) * inv_det;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Whether a triangle whose edge functions `uvw` agree in sign (det = their sum, not 0) claims the
// edges the ray passes exactly through (u, v, w exactly 0): a ray through an edge shared by two
// triangles, or a vertex shared by a fan of them, then hits exactly one, which counting crossings
// needs (the watertight test alone takes both). The rule is rasterization's top-left rule in the
// ray frame: a triangle owns an edge where it lies to the left of the edge directed upward (+y,
// or +x along y = 0), as if the ray were moved by (-e, e^2) for an infinitesimal e: one such move
// for every triangle of a ray, so exactly one triangle of a flat fan contains it. An edge's
// direction is told from its endpoints by comparisons, exactly; the vertices share their bits in
// both triangles, and counter-clockwise (u, v, w < 0, det < 0) puts the triangle on the left of its
// edges b->c, c->a and a->b.
bool claims_edges(real3 a, real3 b, real3 c, bvec3 on_edge, real det) {
  real3 from_x = real3(b.x, c.x, a.x), from_y = real3(b.y, c.y, a.y);
  real3 to_x = real3(c.x, a.x, b.x), to_y = real3(c.y, a.y, b.y);
  bvec3 upward = bvec3(uvec3(greaterThan(to_y, from_y)) | (uvec3(equal(to_y, from_y)) & uvec3(greaterThan(to_x, from_x))));
  bvec3 owned = equal(upward, bvec3(det < 0.0));
  return !any(bvec3(uvec3(on_edge) & uvec3(not(owned))));
}

// Vertices relative to the ray origin. With claim_edges (counting crossings, first hits), an edge
// the ray passes exactly through counts for one of its triangles alone (claims_edges); the
// Moeller-Trumbore benchmark variant claims none, and may count such an edge twice or not at all.
real intersect_triangle(RayFrame frame, real3 dir, real3 v0, real3 v1, real3 v2, real t_max, bool claim_edges) {
  if (TRIANGLE_TEST == VKRAY_TRIANGLE_MOLLER_TRUMBORE) return intersect_triangle_moller_trumbore(dir, v0, v1, v2, t_max);
  real3 a = to_ray_frame(frame, v0);
  real3 b = to_ray_frame(frame, v1);
  real3 c = to_ray_frame(frame, v2);
  // Edge functions (u, v, w) = left - right, one per edge.
  real3 left_x = real3(c.x, a.x, b.x), left_y = real3(b.y, c.y, a.y);
  real3 right_x = real3(c.y, a.y, b.y), right_y = real3(b.x, c.x, a.x);
  precise real3 left = left_x * left_y;
  precise real3 right = right_x * right_y;
  precise real3 uvw = left - right;
#if defined(VKRAY_DOUBLE_EDGES)
  // Devices whose doubles are fast (VKRAY_DOUBLE_EDGES: CPUs; on an H200, 0.95-0.97 of the float
  // walk's time, docs/gpu-reports): each product of two floats is exact in
  // double (48 significant bits of 53) and their difference is rounded once, so every sign is
  // exact and two triangles of an edge get exact negatives: watertight, for 9 double operations
  // where the error-free fallback below costs ~100 float ones on every test (llvmpipe runs a branch
  // masked whether or not a lane takes it): the bunny's walk 141-144 against 149-154 ms.
  dvec3 exact_uvw = dvec3(left_x) * dvec3(left_y) - dvec3(right_x) * dvec3(right_y);
  if (any(lessThan(exact_uvw, dvec3(0.0))) && any(greaterThan(exact_uvw, dvec3(0.0)))) return t_max;
  bvec3 on_edge = equal(exact_uvw, dvec3(0.0));  // before rounding to float, which may flush to 0
  // The distance in double too: the edge functions are products of two coordinates and the
  // numerator of three, which for a triangle 1e-15 across seen from nearby (1e-45) leaves float32's
  // range (the distance came out 5% off; at 1e-16 as 0, no hit). In double they hold down to
  // coordinates of float32's own least (1e-38), for 5 more double operations.
  precise double exact_det = (exact_uvw.x + exact_uvw.y) + exact_uvw.z;
  if (exact_det == 0.0) return t_max;
  if (claim_edges && !claims_edges(a, b, c, on_edge, exact_det < 0.0 ? -1.0 : 1.0)) return t_max;
  precise double exact_t = double(frame.shear.z) * dot(exact_uvw, dvec3(a.z, b.z, c.z)) / exact_det;
  float t_double_edges = float(exact_t);
  return (t_double_edges > 0.0 && t_double_edges < t_max) ? t_double_edges : t_max;
#else
#ifndef VKRAY_FLOAT64
  // Coordinates below 2^-60 (a triangle 1e-20 across seen from nearby): every one scaled by 2^60,
  // exactly, so that the edge functions (products of two) stay within float32's normal range (below
  // 2^-126 they flush to 0 on many devices); the distance is scaled back at the end. Taken by no
  // lane of an ordinary scene; where one takes it, the others' arithmetic is unchanged.
  const float tiny = 8.6736174e-19;  // 2^-60
  real unscale = 1.0;
  if (all(lessThan(max(max(abs(a), abs(b)), abs(c)), vec3(tiny)))) {
    const float up = 1.1529215e18;  // 2^60
    a *= up, b *= up, c *= up;
    unscale = 8.6736174e-19;  // 2^-60
    left_x = real3(c.x, a.x, b.x), left_y = real3(b.y, c.y, a.y);
    right_x = real3(c.y, a.y, b.y), right_y = real3(b.x, c.x, a.x);
    left = left_x * left_y;
    right = right_x * right_y;
    uvw = left - right;
  }
#endif
#ifndef VKRAY_FLOAT64
  // A triangle much smaller than its distance from the ray (1e-4 across, 500 to the side) has edge
  // functions below their rounding error, 2 eps (|left| + |right|) with eps = 2^-24: their signs are
  // noise, and all three may agree, a hit far from the triangle. Where any is that small, all three
  // are evaluated again error-free (TwoProduct; the difference of the products is then exact by
  // Sterbenz's lemma). Whether an edge is that small depends on its two vertices alone: where it is,
  // both triangles of the edge take its exact value (exact negatives of each other); where it is
  // not, its sign is right either way. So the test stays watertight.
  if (any(lessThan(abs(uvw), 2.5e-7 * (abs(left) + abs(right))))) {
    vec3 left_error, right_error;
    two_product(left_x, left_y, left, left_error);
    two_product(right_x, right_y, right, right_error);
    uvw = (left - right) + (left_error - right_error);
  }
#else
  // Kahan's difference of products, as the reference takes it: within 2 ulp of the exact value
  // (Jeannerod, Louvet and Muller, Math. Comp. 82, 2013), so every sign is exact and 0 exactly
  // where the value is: the triangles around a vertex a ray passes near agree on which side it lies.
  precise dvec3 right_error = fma(-right_x, right_y, right);
  precise dvec3 difference = fma(left_x, left_y, -right);
  uvw = difference + right_error;
#endif
  if (any(lessThan(uvw, real3(0.0))) && any(greaterThan(uvw, real3(0.0)))) return t_max;
  bvec3 on_edge = equal(uvw, real3(0.0));  // exact zeros: float32's small ones error-free, float64's by Kahan
  real u = uvw.x, v = uvw.y, w = uvw.z;
  real det = u + v + w;
  if (det == 0.0) return t_max;  // ray in the triangle's plane, or a degenerate projection
  if (claim_edges && !claims_edges(a, b, c, on_edge, det)) return t_max;
#ifdef VKRAY_FLOAT64
  precise real t = frame.shear.z * (u * a.z + v * b.z + w * c.z) / det;
#else
  // The edge functions over their sum (the barycentric weights, in [0, 1]) before they meet the
  // vertices' z: u a.z is a product of three coordinates, past float32's range for a triangle 1e13
  // across (and below it at 1e-13), where the weights keep every product near the coordinates' size.
  precise real3 weights = uvw / det;
  precise real t = frame.shear.z * dot(weights, real3(a.z, b.z, c.z)) * unscale;
#endif
  return (t > 0.0 && t < t_max) ? t : t_max;
#endif
}

// 1 / dir, with components below 1e-37 in magnitude (in practice: exactly 0, a ray parallel to a
// slab) replaced by the largest float of the same sign: never the NaN of 0 * inf (GLSL's min and
// max are undefined on NaN), and the slab interval is still right. Box faces lie at least
// VKRAY_BOX_MARGIN from anything inside (engine/render/gpu_scene.cpp), so when the origin is inside the
// slab both ends are at least 1e-20 * 3.4e38 away, beyond any hit (coordinates stay within 1e15);
// when it lies outside, the interval is empty or starts beyond any hit; and a ray exactly in the
// plane of a face can meet nothing in the box.
real3 safe_inverse(real3 dir) {
  const real tiny = 1e-37;
  const real largest = 3.4028235e38;
  bvec3 parallel = lessThan(abs(dir), real3(tiny));
  real3 signed_largest = mix(real3(largest), real3(-largest), lessThan(dir, real3(0.0)));
  return mix(1.0 / mix(dir, real3(1.0), parallel), signed_largest, parallel);
}

// Slab tests of rays against two boxes at once (a BVH node's children; see GpuBvhNode for the
// layout), for every ray whose inverse direction lies, component by component, between inv_lo and
// inv_hi: one ray (inv_lo = inv_hi), or a packet's rays by interval arithmetic. For a slab plane at
// distance a from the origin, fl(a * inv) is monotonic in inv, so each ray's slab distances lie
// between those at the interval's ends, and `near` and `far` below bound every such ray's own from
// below and above, as computed for it alone: a box that one of the rays enters before t_max is
// never rejected. A packet with both signs in a component gets the whole range of floats there: no
// culling on that axis, never a wrong one.
// The test is conservative under rounding: the far distance is enlarged by 1 + 2 gamma(3),
// gamma(n) = n u / (1 - n u), u = 2^-24, which covers the error of the three operations behind
// each slab distance (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013; in double it is more than
// needed). A ray that meets a box is never rejected, so culling by box can not open holes in a
// mesh. Likewise the near distance is shrunk by 1 - 2 gamma(3) before it is compared with t_max, so
// a box entered at the nearest hit so far up to rounding is still visited. `enter` is where the rays
// enter each box at the earliest (0 when they start inside). `origin` is the camera's hi part in
// float32 shaders: every box is widened by `margin` = |lo| per axis, so it holds what it holds
// relative to the exact camera. See safe_inverse for rays parallel to a slab.
// min and max of values that are never NaN, as a compare and a select: GLSL leaves NaN undefined, and
// llvmpipe spends a third instruction on it in min and max; the bunny's packet walk at 1920x1080 took
// 34 instead of 39 ms with these in the slab tests.
real select_min(real a, real b) { return a < b ? a : b; }
real2 select_min(real2 a, real2 b) { return mix(b, a, lessThan(a, b)); }
real2 select_max(real2 a, real2 b) { return mix(b, a, greaterThan(a, b)); }
real4 select_min(real4 a, real4 b) { return mix(b, a, lessThan(a, b)); }
real4 select_max(real4 a, real4 b) { return mix(b, a, greaterThan(a, b)); }

bvec2 rays_hit_boxes(vec4 bounds_x, vec4 bounds_y, vec4 bounds_z, real3 origin, vec3 margin, real3 inv_lo,
                     real3 inv_hi, real t_max, out real2 enter) {
  // Without lo parts the margin is 0: leaving the additions out saves 12 of a node's ~60 operations.
  if (use_lo_parts) {
    bounds_x += vec4(-margin.x, -margin.x, margin.x, margin.x);
    bounds_y += vec4(-margin.y, -margin.y, margin.y, margin.y);
    bounds_z += vec4(-margin.z, -margin.z, margin.z, margin.z);
  }
  real4 ax = real4(bounds_x) - origin.x, ay = real4(bounds_y) - origin.y, az = real4(bounds_z) - origin.z;
  real4 tx_lo = ax * inv_lo.x, ty_lo = ay * inv_lo.y, tz_lo = az * inv_lo.z;
  real4 tx_hi = ax * inv_hi.x, ty_hi = ay * inv_hi.y, tz_hi = az * inv_hi.z;
  // Per bound, the smallest and largest of the rays' distances to its plane (one ray: both are its).
  real4 tx_min = select_min(tx_lo, tx_hi), ty_min = select_min(ty_lo, ty_hi), tz_min = select_min(tz_lo, tz_hi);
  real4 tx_max = select_max(tx_lo, tx_hi), ty_max = select_max(ty_lo, ty_hi), tz_max = select_max(tz_lo, tz_hi);
  real2 near = select_max(select_max(select_min(tx_min.xy, tx_min.zw), select_min(ty_min.xy, ty_min.zw)),
                          select_max(select_min(tz_min.xy, tz_min.zw), real2(0.0)));
  const real gamma3 = 1.7881396e-7;  // 3 * 2^-24 / (1 - 3 * 2^-24), rounded up
  real2 far = select_min(select_min(select_max(tx_max.xy, tx_max.zw), select_max(ty_max.xy, ty_max.zw)),
                         select_max(tz_max.xy, tz_max.zw)) *
              (1.0 + 2.0 * gamma3);
  enter = near;
  real2 near_low = near * (1.0 - 2.0 * gamma3);
  return bvec2(near.x <= far.x && near_low.x < t_max, near.y <= far.y && near_low.y < t_max);
}

bvec2 ray_hits_boxes(vec4 bounds_x, vec4 bounds_y, vec4 bounds_z, real3 origin, vec3 margin, real3 inv_dir,
                     real t_max, out real2 enter) {
  return rays_hit_boxes(bounds_x, bounds_y, bounds_z, origin, margin, inv_dir, inv_dir, t_max, enter);
}

#endif  // VKRAY_INTERSECT_GLSL
