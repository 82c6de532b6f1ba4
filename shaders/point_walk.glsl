// Point queries (VKRAY_RAY_INPUT_POINTS): for each point, the nearest point of the scene
// (VKRAY_HIT_QUERY_NEAREST) or the generalized winding number (VKRAY_HIT_QUERY_WINDING), in the same
// tree, slots and precision as rays (primitives.glsl). Positions are taken relative to the query
// point from their hi and lo parts, as vertices relative to a ray's origin: what is near the point
// keeps float32's digits of its own distance, however far both lie from the anchor.
//
// The nearest point: planes and spheres tested one by one first, then the tree walked nearer box
// first, a box skipped where its distance (a lower bound) is past the best so far. An instance's
// mesh is walked with the point taken into its coordinates, its boxes' distances there shrunk by the
// placement's least scale (a lower bound of the world's), its triangles measured in the world's
// coordinates: an unevenly scaled placement still gives the world's nearest point.
//
// The winding number (Jacobson, Kavan and Sorkine-Hornung 2013): each triangle's solid angle over
// 4 pi, signed by its winding; a subtree whose box the point lies outside by its cap
// (engine/scene/winding_caps.hpp: exact, the fan of its boundary's edges to its box's centre); an
// instance's mesh's at the point taken into its coordinates; 1 inside a sphere, 1 behind a plane.
#ifndef VKRAY_POINT_WALK_GLSL
#define VKRAY_POINT_WALK_GLSL

#include "point_geometry.h"

GEOMETRY_BUFFER(VKRAY_BINDING_PLACEMENTS, GeometryTexel, GeometrySampler, placements);  // INSTANCES
GEOMETRY_BUFFER(VKRAY_BINDING_WINDING_CAPS, uvec4, usamplerBuffer, winding_caps);     // by node
GEOMETRY_BUFFER(VKRAY_BINDING_CAP_EDGES, uvec4, usamplerBuffer, cap_edges);           // two edges a texel

const bool WINDING = HIT_QUERY == VKRAY_HIT_QUERY_WINDING;
#ifdef VKRAY_FLOAT64
const real box_shrink = 1.0LF - 1e-15LF;  // (GLSL's literals are floats without LF)
const real four_pi = 12.566370614359172954LF;
#else
// A box's distance computed in float32 is below the exact one after this: its four roundings (the
// differences, the squares, their sum, the square root) are each within 2^-24.
const real box_shrink = 1.0 - 4.8e-7;
const real four_pi = 12.566370614359172954;
#endif

// The loop budget of devices that stop loops (LOOP_BUDGET): every iteration of every loop counts;
// a point that needs more is left to the host.
uint point_iterations = 0u;
bool point_unfinished = false;
bool point_step() {
  if (LOOP_BUDGET > 0 && ++point_iterations >= LOOP_BUDGET) point_unfinished = true;
  return !point_unfinished;
}

// A point's position relative to the query point.
real3 from_query(Point point, Origin query) { return point_from_origin(point, query); }

// The distance from the query point (`p` its hi part, `margin` the size of its lo part) to the box
// lower .. upper, never above the exact one.
real box_distance(vec3 lower, vec3 upper, real3 p, vec3 margin) {
  real3 below = real3(lower - margin) - p;
  real3 above = p - real3(upper + margin);
  return length(max(max(below, above), real3(0.0))) * box_shrink;
}

// Child `side`'s box of `node`, in the node's four texels' layout (GpuBvhNode).
void child_box(uint node, int side, out vec3 lower, out vec3 upper) {
  vec4 x = FETCH(bvh_bounds, 4 * int(node)), y = FETCH(bvh_bounds, 4 * int(node) + 1), z = FETCH(bvh_bounds, 4 * int(node) + 2);
  lower = vec3(x[side], y[side], z[side]);
  upper = vec3(x[side + 2], y[side + 2], z[side + 2]);
}

// The query point's hi part and the margin its lo part asks of boxes.
real3 query_hi(Origin query) {
#ifdef VKRAY_FLOAT64
  return query.position;
#else
  return query.hi;
#endif
}
vec3 query_margin(Origin query) {
#ifdef VKRAY_FLOAT64
  return vec3(0.0);
#else
  return abs(query.lo);
#endif
}

// An instance's linear map (its rows) and least scale, for the world's distances (VKRAY_BINDING_PLACEMENTS);
// and whether its mesh is closed (the fourth texel's x: 1 where its boundary is empty).
struct LinearMap {
  real3 row0, row1, row2;
  real least_scale;
};
LinearMap fetch_linear_map(uint instance) {
#ifdef VKRAY_FLOAT64
  int first = 6 * int(instance);
  dvec4 r0 = point_from_texels(FETCH(placements, first), FETCH(placements, first + 1)).value;
  dvec4 r1 = point_from_texels(FETCH(placements, first + 2), FETCH(placements, first + 3)).value;
  dvec4 r2 = point_from_texels(FETCH(placements, first + 4), FETCH(placements, first + 5)).value;
  return LinearMap(r0.xyz, r1.xyz, r2.xyz, r0.w);
#else
  int first = 3 * int(instance);
  vec4 r0 = FETCH(placements, first), r1 = FETCH(placements, first + 1), r2 = FETCH(placements, first + 2);
  return LinearMap(r0.xyz, r1.xyz, r2.xyz, r0.w);
#endif
}
bool mesh_closed(uint instance) {
#ifdef VKRAY_FLOAT64
  return FETCH(placements, 6 * int(instance) + 2).w != 0u;
#else
  return FETCH(placements, 3 * int(instance) + 1).w != 0.0;
#endif
}
real3 times_linear(LinearMap map, real3 v) {
  precise real3 product = real3(dot(map.row0, v), dot(map.row1, v), dot(map.row2, v));
  return product;
}

// ---- The nearest point --------------------------------------------------------------------------

struct Nearest {
  real distance;  // the query's largest where nothing nearer was found
  real3 offset;   // from the query point to the nearest point
  uint id;        // its slot, a tagged sphere or plane (VKRAY_HIT_*), or VKRAY_HIT_NONE
  uint instance;  // the instance placing it, or VKRAY_NO_INSTANCE
};

// Whether what lies `distance` away (at least) cannot be nearer than the best so far. The query's
// largest distance is inclusive, as the reference's: a point on a surface is found at 0 of it.
bool beyond(real distance, Nearest best) { return distance > best.distance || (distance == best.distance && best.id != VKRAY_HIT_NONE); }

void offer(inout Nearest best, real3 offset, uint id, uint instance) {
  real distance = length(offset);
  if (!beyond(distance, best)) best = Nearest(distance, offset, id, instance);
}

// The offset to triangle (a, b, c), its vertices relative to the query point.
real3 offset_to_triangle(real3 a, real3 b, real3 c) {
  real2 weights = nearest_on_triangle(a, b, c);
  precise real3 offset = a + weights.x * (b - a) + weights.y * (c - a);
  return offset;
}

// The offset to a sphere (centre and radius), from the query point.
real3 offset_to_sphere(Point sphere, Origin query) {
#ifdef VKRAY_FLOAT64
  real3 f = query.position - sphere.value.xyz;
  real radius = sphere.value.w;
#else
  vec3 f_hi, f_lo;
  sphere_offset(sphere.hi.xyz, sphere.lo.xyz, query.hi, query.lo, f_hi, f_lo);
  vec3 f = f_hi + f_lo;
  float radius = sphere.hi.w + sphere.lo.w;
#endif
  real from_centre = length(f);
  // At the centre every point of the surface is nearest: the one along x.
  return from_centre > 0.0 ? f * (radius / from_centre - 1.0) : real3(radius, 0.0, 0.0);
}

// The nearest of an instance's triangles, its mesh's tree walked with the query point in the mesh's
// coordinates.
void nearest_in_instance(uint instance, uint root, Origin query, inout Nearest best) {
  Origin mesh_query;
  real3 unused;
  ray_in_mesh(fetch_placement(instance), query, real3(0.0), mesh_query, unused);
  LinearMap map = fetch_linear_map(instance);
  real3 p = query_hi(mesh_query);
  uint stack_node[VKRAY_BVH_MAX_DEPTH];
  float stack_distance[VKRAY_BVH_MAX_DEPTH];
  uint depth = 1;
  stack_node[0] = root;
  stack_distance[0] = 0.0;
  while (depth > 0 && point_step()) {
    --depth;
    uint node = stack_node[depth];
    if (beyond(real(stack_distance[depth]), best)) continue;
    uvec2 children = FETCH(bvh_links, 4 * int(node) + 3).xy;
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children.y == children.x) break;
      vec3 lower, upper;
      child_box(node, side, lower, upper);
      real distance = map.least_scale * box_distance(lower, upper, p, vec3(0.0));
      if (beyond(distance, best)) continue;
      uint child = children[side];
      if ((child & VKRAY_BVH_LEAF_BIT) == 0u) {
        stack_node[depth] = child;
        stack_distance[depth] = float(distance) * (1.0 - 1.2e-7);  // rounded down
        ++depth;
        continue;
      }
      uint first = (child & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
      uint count = (child & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
      for (uint slot = first; slot < first + count; ++slot) {
        real3 a, b, c;
        fetch_triangle(int(slot), mesh_query, a, b, c);  // relative to the point, in the mesh's coordinates
        offer(best, offset_to_triangle(times_linear(map, a), times_linear(map, b), times_linear(map, c)), slot, instance);
      }
    }
  }
}

// One slot of the world: a triangle, a tree's sphere, or an instance.
void nearest_in_slot(uint slot, Origin query, inout Nearest best) {
  if (!slot_visible(slot)) return;
  uvec4 record = FETCH(primitives, int(slot));
  uint kind = record.w & VKRAY_PRIMITIVE_KIND_BITS;
  if (INSTANCES && kind == VKRAY_PRIMITIVE_INSTANCE) {
    nearest_in_instance(record.x, record.y, query, best);
  } else if (TREE_SPHERES && kind == VKRAY_PRIMITIVE_SPHERE) {
    offer(best, offset_to_sphere(fetch_sphere(int(slot)), query), slot, VKRAY_NO_INSTANCE);
  } else if (record.x != record.y) {  // (not a brute-force batch's padding: zero area, vertex 0 thrice)
    real3 a, b, c;
    fetch_triangle(int(slot), query, a, b, c);
    offer(best, offset_to_triangle(a, b, c), slot, VKRAY_NO_INSTANCE);
  }
}

Nearest nearest_point(Origin query, real max_distance) {
  Nearest best = Nearest(max_distance, real3(0.0), VKRAY_HIT_NONE, VKRAY_NO_INSTANCE);
  for (uint i = 0; i < PLANE_COUNT; ++i) {
    if (!apart_visible(SPHERE_COUNT + i)) continue;
#ifdef VKRAY_FLOAT64
    dvec4 plane = fetch_point(planes, 2 * int(i) + 1).value;
    real reach = plane.w - dot(plane.xyz, query.position);  // dot(n, plane's point - query)
    real3 normal = plane.xyz;
#else
    Point plane = fetch_point(planes, 2 * int(i) + 1);
    vec3 normal = plane.hi.xyz;
    precise float reach = (plane.hi.w - dot(normal, query.hi)) + (plane.lo.w - dot(normal, query.lo));
#endif
    offer(best, reach * normal, VKRAY_HIT_PLANE | i, VKRAY_NO_INSTANCE);
  }
  for (uint i = 0; i < SPHERE_COUNT; ++i) {
    if (apart_visible(i)) offer(best, offset_to_sphere(fetch_point(spheres, int(i)), query), VKRAY_HIT_SPHERE_APART | i, VKRAY_NO_INSTANCE);
  }
  if (SEARCH_MODE == VKRAY_SEARCH_BRUTE_FORCE) {
    for (uint slot = 0; slot < TRIANGLE_SLOTS && point_step(); ++slot) nearest_in_slot(slot, query, best);
    // With instances, their records after the world's triangles, up to one of another kind.
    for (uint slot = TRIANGLE_SLOTS; INSTANCES && point_step(); ++slot) {
      if ((FETCH(primitives, int(slot)).w & VKRAY_PRIMITIVE_KIND_BITS) != VKRAY_PRIMITIVE_INSTANCE) break;
      uvec4 record = FETCH(primitives, int(slot));
      if (!slot_visible(slot)) continue;
      // The mesh's whole batches of slots, each triangle measured in the world's coordinates.
      Origin mesh_query;
      real3 unused;
      ray_in_mesh(fetch_placement(record.x), query, real3(0.0), mesh_query, unused);
      LinearMap map = fetch_linear_map(record.x);
      for (uint mesh_slot = record.y; mesh_slot < record.y + record.z && point_step(); ++mesh_slot) {
        uvec4 triangle = FETCH(primitives, int(mesh_slot));
        if (triangle.x == triangle.y) continue;  // padding: a batch's zero-area fill
        real3 a, b, c;
        fetch_triangle(int(mesh_slot), mesh_query, a, b, c);
        offer(best, offset_to_triangle(times_linear(map, a), times_linear(map, b), times_linear(map, c)), mesh_slot, record.x);
      }
    }
    return best;
  }
  real3 p = query_hi(query);
  vec3 margin = query_margin(query);
  uint stack_node[VKRAY_BVH_MAX_DEPTH];
  float stack_distance[VKRAY_BVH_MAX_DEPTH];
  uint depth = 1;
  stack_node[0] = 0u;
  stack_distance[0] = 0.0;
  while (depth > 0 && point_step()) {
    --depth;
    uint node = stack_node[depth];
    if (beyond(real(stack_distance[depth]), best)) continue;
    uvec2 children = FETCH(bvh_links, 4 * int(node) + 3).xy;
    real2 distance;
    vec3 lower, upper;
    child_box(node, 0, lower, upper);
    distance.x = box_distance(lower, upper, p, margin);
    child_box(node, 1, lower, upper);
    distance.y = children.y == children.x ? uintBitsToFloat(0x7f800000u) : box_distance(lower, upper, p, margin);
    // The farther pushed first: the nearer is walked next.
    int near_side = distance.y < distance.x ? 1 : 0;
    for (int k = 0; k < 2; ++k) {
      int side = k == 0 ? 1 - near_side : near_side;
      if (beyond(distance[side], best)) continue;
      uint child = children[side];
      if ((child & VKRAY_BVH_LEAF_BIT) == 0u) {
        stack_node[depth] = child;
        stack_distance[depth] = float(distance[side]) * (1.0 - 1.2e-7);
        ++depth;
        continue;
      }
      uint first = (child & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
      uint count = (child & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
      for (uint slot = first; slot < first + count && point_step(); ++slot) nearest_in_slot(slot, query, best);
    }
  }
  return best;
}

// ---- The winding number -------------------------------------------------------------------------

// A triangle slot's solid angle from the query point (its vertices relative to it), signed by its
// winding (the stored order turned where VKRAY_PRIMITIVE_FLIPPED says).
real slot_solid_angle(uint slot, Origin query) {
  real3 a, b, c;
  fetch_triangle(int(slot), query, a, b, c);
  real angle = solid_angle(a, b, c);
  return (FETCH(primitives, int(slot)).w & VKRAY_PRIMITIVE_FLIPPED) != 0u ? -angle : angle;
}

// A child's cap's solid angles: each boundary edge (a -> b) with the child's box's centre.
real cap_solid_angles(uint first, uint count, real3 centre, Origin query) {
  real total = 0.0;
  for (uint e = first; e < first + count && point_step(); ++e) {
    uvec4 pair = FETCH(cap_edges, int(e / 2u));
    uvec2 edge = (e & 1u) == 0u ? pair.xy : pair.zw;
    real3 a = from_query(fetch_point(vertices, int(edge.x)), query);
    real3 b = from_query(fetch_point(vertices, int(edge.y)), query);
    total += solid_angle(a, b, centre);
  }
  return total;
}

// Whether `p` lies in the box lower .. upper.
bool box_holds(vec3 lower, vec3 upper, real3 p) { return all(lessThanEqual(real3(lower), p)) && all(lessThanEqual(p, real3(upper))); }

// The solid angles at `query` (4 pi times the winding number) of the subtree `child` of `node` (on
// `side`), where the point lies far enough from its box for the cap standing for it; false where it
// must be walked.
bool capped_solid_angle(uint node, int side, uvec4 caps, Origin query, inout real total) {
  vec3 lower, upper;
  child_box(node, side, lower, upper);
  real3 p = query_hi(query);
  uint first = side == 0 ? caps.x : caps.z;
  // Where the point lies half the box's diagonal from it or more, the box's points, and the fan's,
  // are seen within 90 degrees of each other (the box is convex): each fan term's denominator is at
  // least |a||b||c|, its angle well conditioned. Nearer, the subtree is walked.
  if (first == VKRAY_NO_CAP || box_distance(lower, upper, p, query_margin(query)) < 0.5 * real(length(upper - lower))) return false;
  // The centre relative to the point: the box's bounds are anchored as the point's hi part is.
  real3 centre = real3(0.5 * (lower + upper)) - p;
#ifndef VKRAY_FLOAT64
  centre -= query.lo;
#endif
  total += cap_solid_angles(first, side == 0 ? caps.y : caps.w, centre, query);
  return true;
}

// An instance's mesh's solid angles at `query` taken into its coordinates, its tree below `root`
// walked with its caps. (GLSL has no recursion: the world's walk below calls this one, which meets
// triangles alone.)
real instance_solid_angle(uint instance, uint root, Origin query) {
  Origin mesh_query;
  real3 unused;
  ray_in_mesh(fetch_placement(instance), query, real3(0.0), mesh_query, unused);
  // Outside its mesh's box, a closed mesh's is 0 (its caps cancel: no need to sum them).
  vec3 lower0, upper0, lower1, upper1;
  child_box(root, 0, lower0, upper0);
  child_box(root, 1, lower1, upper1);
  if (mesh_closed(instance) && !box_holds(min(lower0, lower1), max(upper0, upper1), query_hi(mesh_query))) return 0.0;
  real total = 0.0;
  uint stack_node[VKRAY_BVH_MAX_DEPTH];
  uint depth = 1;
  stack_node[0] = root;
  while (depth > 0 && point_step()) {
    uint node = stack_node[--depth];
    uvec2 children = FETCH(bvh_links, 4 * int(node) + 3).xy;
    uvec4 caps = FETCH(winding_caps, int(node));
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children.y == children.x) break;
      uint child = children[side];
      if ((child & VKRAY_BVH_LEAF_BIT) == 0u) {
        if (!capped_solid_angle(node, side, caps, mesh_query, total)) stack_node[depth++] = child;
        continue;
      }
      uint first = (child & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
      uint count = (child & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
      for (uint slot = first; slot < first + count && point_step(); ++slot) total += slot_solid_angle(slot, mesh_query);
    }
  }
  return total;
}

// Whether `query` lies inside the sphere `sphere` (centre and radius).
bool inside_sphere(Point sphere, Origin query) {
#ifdef VKRAY_FLOAT64
  return length(query.position - sphere.value.xyz) < sphere.value.w;
#else
  vec3 f_hi, f_lo;
  sphere_offset(sphere.hi.xyz, sphere.lo.xyz, query.hi, query.lo, f_hi, f_lo);
  return length(f_hi + f_lo) < sphere.hi.w + sphere.lo.w;
#endif
}

// The world's tree: its triangles, spheres and instances.
real world_solid_angle(Origin query) {
  real total = 0.0;
  uint stack_node[VKRAY_BVH_MAX_DEPTH];
  uint depth = 1;
  stack_node[0] = 0u;
  while (depth > 0 && point_step()) {
    uint node = stack_node[--depth];
    uvec2 children = FETCH(bvh_links, 4 * int(node) + 3).xy;
    uvec4 caps = FETCH(winding_caps, int(node));
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children.y == children.x) break;
      uint child = children[side];
      if ((child & VKRAY_BVH_LEAF_BIT) == 0u) {
        if (!capped_solid_angle(node, side, caps, query, total)) stack_node[depth++] = child;
        continue;
      }
      uint first = (child & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
      uint count = (child & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
      for (uint slot = first; slot < first + count && point_step(); ++slot) {
        if (!slot_visible(slot)) continue;
        uvec4 record = FETCH(primitives, int(slot));
        uint kind = record.w & VKRAY_PRIMITIVE_KIND_BITS;
        if (INSTANCES && kind == VKRAY_PRIMITIVE_INSTANCE) {
          total += instance_solid_angle(record.x, record.y, query);
        } else if (TREE_SPHERES && kind == VKRAY_PRIMITIVE_SPHERE) {
          if (inside_sphere(fetch_sphere(int(slot)), query)) total += four_pi;
        } else {
          total += slot_solid_angle(slot, query);
        }
      }
    }
  }
  return total;
}

real winding_number(Origin query) {
  real total = 0.0;
  for (uint i = 0; i < PLANE_COUNT; ++i) {
    if (!apart_visible(SPHERE_COUNT + i)) continue;
#ifdef VKRAY_FLOAT64
    dvec4 plane = fetch_point(planes, 2 * int(i) + 1).value;
    real reach = plane.w - dot(plane.xyz, query.position);
#else
    Point plane = fetch_point(planes, 2 * int(i) + 1);
    precise float reach = (plane.hi.w - dot(plane.hi.xyz, query.hi)) + (plane.lo.w - dot(plane.hi.xyz, query.lo));
#endif
    if (reach > 0.0) total += four_pi;  // the plane lies ahead along its normal: the point is behind it
  }
  for (uint i = 0; i < SPHERE_COUNT; ++i) {
    if (apart_visible(i) && inside_sphere(fetch_point(spheres, int(i)), query)) total += four_pi;
  }
  if (SEARCH_MODE != VKRAY_SEARCH_BRUTE_FORCE) return (total + world_solid_angle(query)) / four_pi;
  for (uint slot = 0; slot < TRIANGLE_SLOTS && point_step(); ++slot) {
    uvec4 record = FETCH(primitives, int(slot));
    if (record.x != record.y && slot_visible(slot)) total += slot_solid_angle(slot, query);  // (not a batch's padding)
  }
  for (uint slot = TRIANGLE_SLOTS; INSTANCES && point_step(); ++slot) {
    uvec4 record = FETCH(primitives, int(slot));
    if ((record.w & VKRAY_PRIMITIVE_KIND_BITS) != VKRAY_PRIMITIVE_INSTANCE) break;
    if (!slot_visible(slot)) continue;
    Origin mesh_query;
    real3 unused;
    ray_in_mesh(fetch_placement(record.x), query, real3(0.0), mesh_query, unused);
    for (uint mesh_slot = record.y; mesh_slot < record.y + record.z && point_step(); ++mesh_slot) {
      uvec4 triangle = FETCH(primitives, int(mesh_slot));
      if (triangle.x != triangle.y) total += slot_solid_angle(mesh_slot, mesh_query);
    }
  }
  return total / four_pi;
}

#endif  // VKRAY_POINT_WALK_GLSL
