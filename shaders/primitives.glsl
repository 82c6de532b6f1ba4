// Nearest triangle or sphere along a ray: brute force over every primitive (a handful of them), or
// a walk of the BVH, per ray or per subgroup packet (VKRAY_SPEC_SEARCH_MODE). Primitives and nodes
// are laid out as shaders/gpu_layout.h describes; planes are not handled here.
#ifndef VKRAY_PRIMITIVES_GLSL
#define VKRAY_PRIMITIVES_GLSL

#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_EXT_control_flow_attributes : require

#include "gpu_layout.h"
#include "intersect.glsl"

layout(constant_id = VKRAY_SPEC_SPHERE_COUNT) const uint SPHERE_COUNT = 0;
layout(constant_id = VKRAY_SPEC_TRIANGLE_SLOTS) const uint TRIANGLE_SLOTS = 0;
layout(constant_id = VKRAY_SPEC_SEARCH_MODE) const uint SEARCH_MODE = VKRAY_SEARCH_BRUTE_FORCE;
layout(constant_id = VKRAY_SPEC_TREE_HAS_TRIANGLES) const bool TREE_HAS_TRIANGLES = false;
layout(constant_id = VKRAY_SPEC_TREE_HAS_SPHERES) const bool TREE_HAS_SPHERES = false;
layout(constant_id = VKRAY_SPEC_LOOP_BUDGET) const uint LOOP_BUDGET = 0;
layout(constant_id = VKRAY_SPEC_GENERIC) const bool GENERIC = false;
layout(constant_id = VKRAY_SPEC_STACK_REGISTERS) const uint STACK_REGISTERS = 0;
layout(constant_id = VKRAY_SPEC_HIT_QUERY) const uint HIT_QUERY = VKRAY_HIT_QUERY_NEAREST;
const bool ANY_HIT = HIT_QUERY == VKRAY_HIT_QUERY_ANY;
const bool COUNT_CROSSINGS = HIT_QUERY == VKRAY_HIT_QUERY_COUNT;
layout(constant_id = VKRAY_SPEC_MASKS) const bool MASKS = false;
layout(constant_id = VKRAY_SPEC_HITS) const uint HITS = 1u;
layout(constant_id = VKRAY_SPEC_INSTANCES) const bool INSTANCES = false;
const bool FIRST_HITS = HITS > 1u;
// Crossings counted or listed are each met once: an edge or vertex a ray passes exactly through,
// a tree's lone leaf.
const bool EVERY_CROSSING_ONCE = COUNT_CROSSINGS || FIRST_HITS;
// What the tree may hold: in the generic variant, both kinds.
const bool TREE_TRIANGLES = GENERIC || TREE_HAS_TRIANGLES;
const bool TREE_SPHERES = GENERIC || TREE_HAS_SPHERES;

// Geometry is read in 16-byte texels: through uniform texel buffers (texelFetch), or with
// VKRAY_STORAGE_GEOMETRY defined through storage buffers of vec4 or uvec4 (see gpu_layout.h for
// which each device reads faster). GEOMETRY_BUFFER declares one, FETCH reads texel `index` of it.
#ifdef VKRAY_STORAGE_GEOMETRY
#define GEOMETRY_BUFFER(binding_index, texel, sampler, name) \
  layout(std430, binding = binding_index) readonly buffer name##_texels { texel name[]; }
#define FETCH(name, index) name[index]
#else
#define GEOMETRY_BUFFER(binding_index, texel, sampler, name) layout(binding = binding_index) uniform sampler name
#define FETCH(name, index) texelFetch(name, index)
#endif
// Positions: floats in float32 shaders, pairs of 32-bit words of doubles in float64 shaders.
#ifdef VKRAY_FLOAT64
#define GeometryTexel uvec4
#define GeometrySampler usamplerBuffer
#else
#define GeometryTexel vec4
#define GeometrySampler samplerBuffer
#endif
GEOMETRY_BUFFER(VKRAY_BINDING_SPHERES, GeometryTexel, GeometrySampler, spheres);    // GpuSphere
GEOMETRY_BUFFER(VKRAY_BINDING_PRIMITIVES, uvec4, usamplerBuffer, primitives);      // GpuPrimitive
GEOMETRY_BUFFER(VKRAY_BINDING_VERTICES, GeometryTexel, GeometrySampler, vertices);  // GpuPoint
GEOMETRY_BUFFER(VKRAY_BINDING_NORMALS, GeometryTexel, GeometrySampler, normals);    // by primitive slot
GEOMETRY_BUFFER(VKRAY_BINDING_BVH_BOUNDS, vec4, samplerBuffer, bvh_bounds);        // GpuBvhNode: 4 texels
GEOMETRY_BUFFER(VKRAY_BINDING_BVH_LINKS, uvec4, usamplerBuffer, bvh_links);        // the same, as uints
GEOMETRY_BUFFER(VKRAY_BINDING_APART_MASKS, uvec4, usamplerBuffer, apart_masks);    // MASKS only
GEOMETRY_BUFFER(VKRAY_BINDING_INSTANCES, GeometryTexel, GeometrySampler, instances);  // INSTANCES only

// The call's ray mask (RayGenParams.counts.w), set by main before any search. A primitive counts
// only where its mask shares a bit with it: tested after the intersection, which leaves every
// walk's arithmetic as it is without masks.
uint ray_mask = 0xffu;
bool mask_hits(uint mask) { return !MASKS || (mask & ray_mask) != 0u; }
// The primitive in `slot` (its record's mask), and sphere `index` tested one by one or plane
// `index` after them (VKRAY_BINDING_APART_MASKS).
bool slot_visible(uint slot) { return !MASKS || mask_hits(FETCH(primitives, int(slot)).w >> VKRAY_PRIMITIVE_MASK_SHIFT); }
bool apart_visible(uint index) { return !MASKS || mask_hits(FETCH(apart_masks, int(index)).x); }

// COUNT_CROSSINGS: the surfaces the ray has crossed so far. Every test leaves the ray's range
// whole, so the walk visits everything along it.
uint crossings = 0u;

// FIRST_HITS: the first HITS crossings found so far, nearest first (ties by id, so that the order
// does not depend on the walk's; but a crossing tied with the last place is kept only where it was
// found first), VKRAY_HIT_NONE at the range's end where fewer were found. The
// walk's bound is the last one's distance: what lies beyond cannot enter the list. Indexed by
// constants alone once unrolled, so the list stays in registers.
real first_t[VKRAY_HITS_MAX];
uint first_id[VKRAY_HITS_MAX];
// INSTANCES: the instance placing each listed hit (VKRAY_NO_INSTANCE for the world's own), and the
// one whose mesh the walk is in now, which the walk sets as it enters and leaves an instance and
// each hit it lists takes. Ties at one t and slot are then ordered by instance.
uint first_instance[VKRAY_HITS_MAX];
uint listing_instance = VKRAY_NO_INSTANCE;

void clear_first_hits(real t_max) {
  [[unroll]] for (uint k = 0; k < VKRAY_HITS_MAX; ++k) {
    first_t[k] = t_max;
    first_id[k] = VKRAY_HIT_NONE;
    if (INSTANCES) first_instance[k] = VKRAY_NO_INSTANCE;
  }
}

// Inserts a crossing at t in order where it lies below the list's bound; returns the new bound.
real list_first_hit(real t, uint id) {
  bool placed = !(t < first_t[HITS - 1u]);
  [[unroll]] for (int k = VKRAY_HITS_MAX - 1; k >= 0; --k) {
    if (uint(k) >= HITS || placed) continue;
    int before = max(k - 1, 0);
    bool later_id = first_id[before] > id || (INSTANCES && first_id[before] == id && first_instance[before] > listing_instance);
    bool shift = k > 0 && (first_t[before] > t || (first_t[before] == t && later_id));
    first_t[k] = shift ? first_t[before] : t;
    first_id[k] = shift ? first_id[before] : id;
    if (INSTANCES) first_instance[k] = shift ? first_instance[before] : listing_instance;
    placed = !shift;
  }
  return first_t[HITS - 1u];
}

// A GpuPoint as stored: hi and lo parts in float32 shaders, the position and w in float64 shaders.
struct Point {
#ifdef VKRAY_FLOAT64
  dvec4 value;
#else
  vec4 hi;
  vec4 lo;
#endif
};

// Point `point` of a buffer of GpuPoints (its two texels); float32 shaders read the lo texel only
// where they use it.
#ifdef VKRAY_FLOAT64
Point point_from_texels(uvec4 first, uvec4 second) {
  return Point(dvec4(packDouble2x32(first.xy), packDouble2x32(first.zw), packDouble2x32(second.xy),
                     packDouble2x32(second.zw)));
}
#define fetch_point(name, point) \
  point_from_texels(FETCH(name, VKRAY_TEXELS_PER_POINT * (point)), FETCH(name, VKRAY_TEXELS_PER_POINT * (point) + 1))
#else
#define fetch_point(name, point)                                  \
  Point(FETCH(name, VKRAY_TEXELS_PER_POINT * (point)),             \
        use_lo_parts ? FETCH(name, VKRAY_TEXELS_PER_POINT * (point) + 1) : vec4(0.0))
// The hi part alone, for what needs no more (a plane's normal and height above the camera).
#define fetch_point_hi(name, point) Point(FETCH(name, VKRAY_TEXELS_PER_POINT * (point)), vec4(0.0))
#endif

// The point's position relative to the ray origin, and its w.
real3 point_from_origin(Point point, Origin origin) {
#ifdef VKRAY_FLOAT64
  return point.value.xyz - origin.position;
#else
  return relative_to_camera(point.hi.xyz, point.lo.xyz, origin.hi, origin.lo);
#endif
}

// A sphere given as (centre, radius): `normal` receives (hit - centre) / radius, `far_root` and
// `far_normal` the farther root and its normal (intersect_sphere).
real intersect_sphere_point(Point sphere, Origin origin, real3 dir, real t_max, out real3 normal, out real far_root,
                            out real3 far_normal) {
#ifdef VKRAY_FLOAT64
  return intersect_sphere(origin.position - sphere.value.xyz, sphere.value.w, dir, t_max, normal, far_root, far_normal);
#else
  vec3 f_hi, f_lo;
  sphere_offset(sphere.hi.xyz, sphere.lo.xyz, origin.hi, origin.lo, f_hi, f_lo);
  return intersect_sphere(f_hi, f_lo, sphere.hi.w, sphere.lo.w, dir, t_max, normal, far_root, far_normal);
#endif
}
real intersect_sphere_point(Point sphere, Origin origin, real3 dir, real t_max, out real3 normal, out real far_root) {
  real3 far_normal;
  return intersect_sphere_point(sphere, origin, dir, t_max, normal, far_root, far_normal);
}
real intersect_sphere_point(Point sphere, Origin origin, real3 dir, real t_max, out real3 normal) {
  real far_root;
  return intersect_sphere_point(sphere, origin, dir, t_max, normal, far_root);
}

// A sphere's crossings in (0, t_max), from the root intersect_sphere took (`t`: the near one where
// it lies ahead, else the far one) and its `far_root` (the far one after a near one taken, else
// t_max): a tangent ray's double root counts twice, which leaves the count's parity as it was.
uint sphere_crossings(real t, real far_root, real t_max) {
  return uint(t < t_max) + uint(far_root < t_max);
}

// A sphere's crossings (`t` and `far_root` as for sphere_crossings) into the list of first hits:
// the root taken as `id`, the far one after it as id | VKRAY_HIT_FAR_ROOT (after it at a tangent's
// double root too: ties go by id). Returns the new bound.
real list_sphere_hits(real t, real far_root, real t_max, uint id) {
  real bound = t_max;
  if (t < bound) bound = list_first_hit(t, id);
  if (far_root < bound) bound = list_first_hit(far_root, id | VKRAY_HIT_FAR_ROOT);
  return bound;
}

const uint no_primitive = VKRAY_HIT_NONE;

struct PrimitiveHit {
  real t;           // t_max when nothing nearer was found
  real3 normal;     // geometric normal facing the ray, not yet unit length
  bool unfinished;  // the walk ran out of LOOP_BUDGET: the host must finish this ray
  uint id;          // what was hit (VKRAY_BINDING_HITS): its slot, a tagged sphere, or VKRAY_HIT_NONE
  uint instance;    // the instance placing it (VKRAY_BINDING_INSTANCE_HITS), or VKRAY_NO_INSTANCE
};

// The nearest hit among primitive slots so far; the normal is computed once, for the winner.
struct SlotHit {
  real t;
  uint slot;
  uint instance;  // INSTANCES: the instance placing the slot's triangle, or VKRAY_NO_INSTANCE
};

// The vertices of a triangle relative to the ray origin.
void fetch_triangle(int slot, Origin origin, out real3 v0, out real3 v1, out real3 v2) {
  uvec4 record = FETCH(primitives, slot);
  v0 = point_from_origin(fetch_point(vertices, int(record.x)), origin);
  v1 = point_from_origin(fetch_point(vertices, int(record.y)), origin);
  v2 = point_from_origin(fetch_point(vertices, int(record.z)), origin);
}

// A triangle's unit normal (see VKRAY_TEXELS_PER_NORMAL_*).
real3 fetch_normal(int slot) {
#ifdef VKRAY_FLOAT64
  uvec4 first = FETCH(normals, VKRAY_TEXELS_PER_NORMAL_FLOAT64 * slot);
  uvec4 second = FETCH(normals, VKRAY_TEXELS_PER_NORMAL_FLOAT64 * slot + 1);
  return dvec3(packDouble2x32(first.xy), packDouble2x32(first.zw), packDouble2x32(second.xy));
#else
  return FETCH(normals, VKRAY_TEXELS_PER_NORMAL_FLOAT32 * slot).xyz;
#endif
}

// The point holding a tree sphere's centre and radius.
Point fetch_sphere(int slot) {
  return fetch_point(vertices, int(FETCH(primitives, slot).x));
}

void test_triangle(RayFrame frame, Origin origin, real3 dir, uint slot, inout SlotHit hit) {
  real3 v0, v1, v2;
  fetch_triangle(int(slot), origin, v0, v1, v2);
  real t = intersect_triangle(frame, dir, v0, v1, v2, hit.t, EVERY_CROSSING_ONCE);
  if (t < hit.t && slot_visible(slot)) {
    if (COUNT_CROSSINGS) {
      ++crossings;
      return;
    }
    if (FIRST_HITS) {
      hit.t = list_first_hit(t, slot);
      hit.slot = first_id[0];
      return;
    }
    hit.t = t;
    hit.slot = slot;
  }
}

// Whether the slot holds a sphere (read from its record in trees of both kinds only).
bool is_sphere(int slot) {
  if (!TREE_TRIANGLES) return true;
  if (!TREE_SPHERES) return false;
  return (FETCH(primitives, slot).w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_SPHERE;
}

// One primitive slot. Specialized on what the tree holds: a tree of triangles alone has no sphere
// code, and the other way round.
void test_primitive(RayFrame frame, Origin origin, real3 dir, uint slot, inout SlotHit hit) {
  bool sphere = is_sphere(int(slot));
  if (TREE_TRIANGLES && !sphere) test_triangle(frame, origin, dir, slot, hit);
  if (TREE_SPHERES && sphere) {
    real3 normal;
    real far_root;
    real t = intersect_sphere_point(fetch_sphere(int(slot)), origin, dir, hit.t, normal, far_root);
    if (COUNT_CROSSINGS) {
      if (slot_visible(slot)) crossings += sphere_crossings(t, far_root, hit.t);
    } else if (FIRST_HITS) {
      if (slot_visible(slot)) {
        hit.t = list_sphere_hits(t, far_root, hit.t, slot);
        hit.slot = first_id[0];
      }
    } else if (t < hit.t && slot_visible(slot)) {
      hit.t = t;
      hit.slot = slot;
    }
  }
}

// A triangle's or plane's normal turned to face the ray.
real3 facing_the_ray(real3 normal, real3 dir) { return dot(normal, dir) > 0.0 ? -normal : normal; }

// The winner's normal, facing the ray: a sphere's is computed again from its intersection (once
// per ray), at its far root where the first hits list it so (VKRAY_HIT_FAR_ROOT).
real3 primitive_normal(uint slot, Origin origin, real3 dir) {
  real3 normal;
  bool far = FIRST_HITS && (slot & VKRAY_HIT_FAR_ROOT) != 0u;
  slot &= ~VKRAY_HIT_FAR_ROOT;
  if (TREE_SPHERES && is_sphere(int(slot))) {
    real far_root;
    real3 far_normal;
    intersect_sphere_point(fetch_sphere(int(slot)), origin, dir, uintBitsToFloat(0x7f800000u), normal, far_root, far_normal);
    return far ? far_normal : normal;
  }
  normal = fetch_normal(int(slot));
  return facing_the_ray(normal, dir);
}

// INSTANCES: instance `index`'s rows of A and its translation T (see VKRAY_TEXELS_PER_INSTANCE_*).
struct Placement {
  real3 row0, row1, row2;
#ifdef VKRAY_FLOAT64
  dvec3 translation;
#else
  vec3 translation_hi, translation_lo;
#endif
};

Placement fetch_placement(uint index) {
#ifdef VKRAY_FLOAT64
  int first = VKRAY_TEXELS_PER_INSTANCE_FLOAT64 * int(index);
  dvec4 r0 = point_from_texels(FETCH(instances, first), FETCH(instances, first + 1)).value;
  dvec4 r1 = point_from_texels(FETCH(instances, first + 2), FETCH(instances, first + 3)).value;
  dvec4 r2 = point_from_texels(FETCH(instances, first + 4), FETCH(instances, first + 5)).value;
  return Placement(r0.xyz, r1.xyz, r2.xyz, dvec3(r0.w, r1.w, r2.w));
#else
  int first = VKRAY_TEXELS_PER_INSTANCE_FLOAT32 * int(index);
  vec4 r0 = FETCH(instances, first), r1 = FETCH(instances, first + 1), r2 = FETCH(instances, first + 2);
  vec3 lo = use_lo_parts ? FETCH(instances, first + 3).xyz : vec3(0.0);
  return Placement(r0.xyz, r1.xyz, r2.xyz, vec3(r0.w, r1.w, r2.w), lo);
#endif
}

// A times v, each row's dot product `precise` (the same bits in every pipeline).
real3 times_rows(Placement placement, real3 v) {
  precise real3 product = real3(dot(placement.row0, v), dot(placement.row1, v), dot(placement.row2, v));
  return product;
}

// The ray in the instance's mesh coordinates: origin A (o - T), o - T from hi and lo parts as a
// vertex relative to the camera is, and direction A d (not unit length: t stays the world's).
void ray_in_mesh(Placement placement, Origin origin, real3 dir, out Origin mesh_origin, out real3 mesh_dir) {
#ifdef VKRAY_FLOAT64
  mesh_origin = Origin(times_rows(placement, origin.position - placement.translation));
#else
  vec3 from_instance = -relative_to_camera(placement.translation_hi, placement.translation_lo, origin.hi, origin.lo);
  mesh_origin = Origin(times_rows(placement, from_instance), vec3(0.0));
#endif
  mesh_dir = times_rows(placement, dir);
}

// A mesh normal of the instance in world coordinates, facing the world's ray: A^T n (the inverse
// transpose of the linear map). Whether it faces the ray is the same in both coordinates,
// (A^T n).d = n.(A d).
real3 instance_normal(uint slot, uint instance, real3 dir) {
  Placement placement = fetch_placement(instance);
  real3 normal = fetch_normal(int(slot));
  precise real3 world = normal.x * placement.row0 + normal.y * placement.row1 + normal.z * placement.row2;
  // Over its largest component: A's rows are as long as 1 / the instance's scale (1e20 for one
  // 1e-20 across), whose square, in the normalization after, would leave float32's range.
  precise real3 scaled = world / max(max(abs(world.x), abs(world.y)), abs(world.z));
  return facing_the_ray(scaled, dir);
}

// Every sphere, then every triangle in batches of VKRAY_TRIANGLE_BATCH (one loop iteration each);
// with `placed` (INSTANCES), then every instance: the records after the world's triangles, up to
// one of another kind, each naming its instance and its mesh's slots (whole batches), which are
// tested with the ray in the mesh's coordinates.
PrimitiveHit nearest_primitive_brute_force(RayFrame frame, Origin origin, real3 dir, real t_max, uint sphere_count,
                                           uint triangle_slots, bool placed) {
  PrimitiveHit result = PrimitiveHit(t_max, real3(0.0), false, VKRAY_HIT_NONE, VKRAY_NO_INSTANCE);
  for (uint i = 0; i < sphere_count; ++i) {
    real3 normal;
    real far_root;
    real t = intersect_sphere_point(fetch_point(spheres, int(i)), origin, dir, result.t, normal, far_root);
    if (COUNT_CROSSINGS) {
      if (apart_visible(i)) crossings += sphere_crossings(t, far_root, result.t);
    } else if (FIRST_HITS) {
      if (apart_visible(i)) result.t = list_sphere_hits(t, far_root, result.t, VKRAY_HIT_SPHERE_APART | i);
    } else if (t < result.t && apart_visible(i)) {
      result.t = t;
      result.normal = normal;
      result.id = VKRAY_HIT_SPHERE_APART | i;
    }
  }
  SlotHit hit = SlotHit(result.t, no_primitive, VKRAY_NO_INSTANCE);
  for (uint batch = 0; batch < triangle_slots; batch += VKRAY_TRIANGLE_BATCH) {
    [[unroll]] for (uint k = 0; k < VKRAY_TRIANGLE_BATCH; ++k) test_triangle(frame, origin, dir, batch + k, hit);
  }
  for (uint entry = triangle_slots; INSTANCES && placed; ++entry) {
    uvec4 record = FETCH(primitives, int(entry));
    if ((record.w & VKRAY_PRIMITIVE_KIND_BITS) != VKRAY_PRIMITIVE_INSTANCE) break;
    if (!slot_visible(entry)) continue;
    Origin mesh_origin;
    real3 mesh_dir;
    ray_in_mesh(fetch_placement(record.x), origin, dir, mesh_origin, mesh_dir);
    RayFrame mesh_frame = make_ray_frame(mesh_dir);
    listing_instance = record.x;
    for (uint batch = record.y; batch < record.y + record.z; batch += VKRAY_TRIANGLE_BATCH) {
      real before = hit.t;
      [[unroll]] for (uint k = 0; k < VKRAY_TRIANGLE_BATCH; ++k) test_triangle(mesh_frame, mesh_origin, mesh_dir, batch + k, hit);
      if (hit.t != before) hit.instance = record.x;
    }
    listing_instance = VKRAY_NO_INSTANCE;
  }
  if (FIRST_HITS) {
    result.t = hit.t;  // the list's bound; its hits' normals are read when they are written
  } else if (hit.slot != no_primitive) {
    real3 normal = INSTANCES && hit.instance != VKRAY_NO_INSTANCE ? instance_normal(hit.slot, hit.instance, dir)
                                                                  : primitive_normal(hit.slot, origin, dir);
    result = PrimitiveHit(hit.t, normal, false, hit.slot, hit.instance);
  }
  return result;
}

const uint no_node = 0x7fffffffu;  // `current` once the stack has run dry; no node has this index

// The walk's stack in registers (see VKRAY_SPEC_STACK_REGISTERS): the top entry in top.x, each
// vector's w spilling into the next one's x. Every vector past STACK_REGISTERS is removed by
// specialization, with its moves.
struct RegisterStack {
  uvec4 top, r1, r2, r3, r4, r5, r6, r7;
};

void push_registers(inout RegisterStack s, uint entry) {
  if (STACK_REGISTERS > 28) s.r7 = uvec4(s.r6.w, s.r7.xyz);
  if (STACK_REGISTERS > 24) s.r6 = uvec4(s.r5.w, s.r6.xyz);
  if (STACK_REGISTERS > 20) s.r5 = uvec4(s.r4.w, s.r5.xyz);
  if (STACK_REGISTERS > 16) s.r4 = uvec4(s.r3.w, s.r4.xyz);
  if (STACK_REGISTERS > 12) s.r3 = uvec4(s.r2.w, s.r3.xyz);
  if (STACK_REGISTERS > 8) s.r2 = uvec4(s.r1.w, s.r2.xyz);
  if (STACK_REGISTERS > 4) s.r1 = uvec4(s.top.w, s.r1.xyz);
  s.top = uvec4(entry, s.top.xyz);
}

uint pop_registers(inout RegisterStack s) {
  uint entry = s.top.x;
  s.top = uvec4(s.top.yzw, s.r1.x);
  if (STACK_REGISTERS > 4) s.r1 = uvec4(s.r1.yzw, s.r2.x);
  if (STACK_REGISTERS > 8) s.r2 = uvec4(s.r2.yzw, s.r3.x);
  if (STACK_REGISTERS > 12) s.r3 = uvec4(s.r3.yzw, s.r4.x);
  if (STACK_REGISTERS > 16) s.r4 = uvec4(s.r4.yzw, s.r5.x);
  if (STACK_REGISTERS > 20) s.r5 = uvec4(s.r5.yzw, s.r6.x);
  if (STACK_REGISTERS > 24) s.r6 = uvec4(s.r6.yzw, s.r7.x);
  if (STACK_REGISTERS > 28) s.r7 = uvec4(s.r7.yzw, 0u);
  return entry;
}

// An entry the walk pushes below an instance's mesh tree: reached, the walk returns to the world's ray.
const uint instance_marker = 0x7ffffffeu;

// The tree walk, nearer child first, the other on a stack; boxes entered beyond the nearest hit so
// far are skipped. Each iteration takes one step down the tree and tests one primitive of the leaf
// found last: llvmpipe runs both sides of every branch masked, so an iteration costs the node step
// plus the primitive test whatever the ray needs; doing both every time wastes neither. (A node may
// be tested against a nearest hit not yet updated by its leaf's last primitive; that only makes the
// test looser, never culls a hit.) An occlusion query (ANY_HIT) stops at its first hit.
// An instance met in a leaf (INSTANCES) turns the ray into its mesh's coordinates and continues the
// same loop in the mesh's tree: what remained of the world's walk (the node being stepped, the
// leaf's other primitives) goes on the stack under instance_marker, whose pop restores the world's
// ray once the mesh's last leaf is done. One loop keeps lavapipe's lanes in step whichever level
// each is on. One level of instances: an instanced mesh's tree holds triangles alone.
PrimitiveHit nearest_primitive_in_tree(RayFrame frame, Origin origin, real3 dir, real t_max) {
  real3 inv_dir = safe_inverse(dir);
#ifdef VKRAY_FLOAT64
  dvec3 box_origin = origin.position;
  vec3 box_margin = vec3(0.0);
#else
  vec3 box_origin = origin.hi;
  vec3 box_margin = abs(origin.lo);
#endif
  // The ray the walk tests with: the world's, or an instance's mesh's (INSTANCES).
  RayFrame walk_frame = frame;
  Origin walk_origin = origin;
  real3 walk_dir = dir;
  real3 walk_inv_dir = inv_dir;
  real3 walk_box_origin = box_origin;
  vec3 walk_box_margin = box_margin;
  uint instance = VKRAY_NO_INSTANCE;
  SlotHit hit = SlotHit(t_max, no_primitive, VKRAY_NO_INSTANCE);
  bool unfinished = false;
  // A walk holds at most one entry per inner node on its path; an instance's adds three.
  uint stack[INSTANCES ? 2 * VKRAY_BVH_MAX_DEPTH + 3 : VKRAY_BVH_MAX_DEPTH];  // STACK_REGISTERS == 0 only
  RegisterStack registers = RegisterStack(uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u),
                                          uvec4(0u));
  uint stack_size = 0;
#define PUSH_ENTRY(entry)                                   \
  if (STACK_REGISTERS > 0) push_registers(registers, entry); \
  else stack[stack_size] = entry;                            \
  ++stack_size;
#define POP_ENTRY(into)                                                        \
  if (stack_size == 0) {                                                       \
    into = no_node;                                                            \
  } else {                                                                     \
    --stack_size;                                                              \
    into = STACK_REGISTERS > 0 ? pop_registers(registers) : stack[stack_size]; \
  }
  uint current = 0;  // the root, always an inner node
  uint leaf_next = 0;  // the leaf's primitives still to test: [leaf_next, leaf_end)
  uint leaf_end = 0;
  uint iterations = 0;
  while ((current != no_node || leaf_next < leaf_end) && !(ANY_HIT && hit.slot != no_primitive)) {
    if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
      unfinished = true;
      break;
    }
    ++iterations;
    if (leaf_next < leaf_end) {
      uint slot = leaf_next++;
      uvec4 record = INSTANCES ? FETCH(primitives, int(slot)) : uvec4(0u);
      if (INSTANCES && (record.w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_INSTANCE) {
        if (slot_visible(slot)) {
          if (current != no_node) {
            PUSH_ENTRY(current)
          }
          if (leaf_next < leaf_end) {
            PUSH_ENTRY(VKRAY_BVH_LEAF_BIT | (leaf_next << VKRAY_BVH_LEAF_COUNT_BITS) | (leaf_end - leaf_next - 1u))
          }
          PUSH_ENTRY(instance_marker)
          instance = record.x;
          listing_instance = instance;
          ray_in_mesh(fetch_placement(instance), origin, dir, walk_origin, walk_dir);
          walk_frame = make_ray_frame(walk_dir);
          walk_inv_dir = safe_inverse(walk_dir);
#ifdef VKRAY_FLOAT64
          walk_box_origin = walk_origin.position;
#else
          walk_box_origin = walk_origin.hi;
#endif
          walk_box_margin = vec3(0.0);
          current = record.y;
          leaf_next = leaf_end;
        }
      } else {
        real before = hit.t;
        test_primitive(walk_frame, walk_origin, walk_dir, slot, hit);
        if (INSTANCES && hit.t != before) hit.instance = instance;
      }
    }

    bool pop = false;
    if (INSTANCES && current == instance_marker) {
      // Back to the world's ray once the mesh's last leaf is done.
      if (leaf_next == leaf_end) {
        walk_frame = frame;
        walk_origin = origin;
        walk_dir = dir;
        walk_inv_dir = inv_dir;
        walk_box_origin = box_origin;
        walk_box_margin = box_margin;
        instance = VKRAY_NO_INSTANCE;
        listing_instance = VKRAY_NO_INSTANCE;
        pop = true;
      }
    } else if ((current & VKRAY_BVH_LEAF_BIT) != 0) {
      // A leaf waits until the previous one is done.
      if (leaf_next == leaf_end) {
        leaf_next = (current & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
        leaf_end = leaf_next + (current & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
        pop = true;
      }
    } else if (current != no_node) {
      real2 enter;
      bvec2 hits = ray_hits_boxes(FETCH(bvh_bounds, 4 * int(current)), FETCH(bvh_bounds, 4 * int(current) + 1),
                                  FETCH(bvh_bounds, 4 * int(current) + 2), walk_box_origin, walk_box_margin,
                                  walk_inv_dir, hit.t, enter);
      uvec2 children = FETCH(bvh_links, 4 * int(current) + 3).xy;
      // A tree of one leaf is a root with that leaf as both children (Bvh::nodes): visited once.
      if (EVERY_CROSSING_ONCE && children.x == children.y) hits.y = false;
      bool second_first = hits.y && (!hits.x || enter.y < enter.x);
      if (hits.x && hits.y) {
        PUSH_ENTRY(second_first ? children.x : children.y)
        current = second_first ? children.y : children.x;
      } else if (hits.x || hits.y) {
        current = hits.x ? children.x : children.y;
      } else {
        pop = true;
      }
    }
    if (pop) {
      POP_ENTRY(current)
    }
  }
#undef PUSH_ENTRY
#undef POP_ENTRY
  PrimitiveHit result = PrimitiveHit(hit.t, real3(0.0), unfinished, hit.slot, hit.instance);
  if (hit.slot != no_primitive && !FIRST_HITS) {
    result.normal = INSTANCES && hit.instance != VKRAY_NO_INSTANCE ? instance_normal(hit.slot, hit.instance, dir)
                                                                   : primitive_normal(hit.slot, origin, dir);
  }
  return result;
}

#endif  // VKRAY_PRIMITIVES_GLSL
