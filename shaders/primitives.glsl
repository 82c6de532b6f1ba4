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
// What the tree may hold: in the generic variant, both kinds.
const bool TREE_TRIANGLES = GENERIC || TREE_HAS_TRIANGLES;
const bool TREE_SPHERES = GENERIC || TREE_HAS_SPHERES;

layout(binding = VKRAY_BINDING_SPHERES) uniform samplerBuffer spheres;        // GpuSphere
layout(binding = VKRAY_BINDING_PRIMITIVES) uniform samplerBuffer primitives;  // GpuPrimitive: 3 texels
layout(binding = VKRAY_BINDING_BVH_BOUNDS) uniform samplerBuffer bvh_bounds;  // GpuBvhNode: 4 texels
layout(binding = VKRAY_BINDING_BVH_LINKS) uniform usamplerBuffer bvh_links;   // the same, as uints

const uint no_primitive = 0xffffffffu;

struct PrimitiveHit {
  float t;          // t_max when nothing nearer was found
  vec3 normal;      // unit geometric normal (not yet facing the ray)
  bool unfinished;  // the walk ran out of LOOP_BUDGET: the host must finish this ray
};

// The nearest hit among primitive slots so far; the normal is read once, for the winner.
struct SlotHit {
  float t;
  uint slot;
};

void test_triangle(RayFrame frame, vec3 origin, vec3 dir, vec3 v0, vec3 v1, vec3 v2, uint slot, inout SlotHit hit) {
  float t = intersect_triangle(frame, origin, dir, v0, v1, v2, hit.t);
  if (t < hit.t) {
    hit.t = t;
    hit.slot = slot;
  }
}

// One primitive slot. Specialized on what the tree holds: a tree of triangles alone has no sphere
// code, and the other way round.
void test_primitive(RayFrame frame, vec3 origin, vec3 dir, uint slot, inout SlotHit hit) {
  int texel = 3 * int(slot);
  vec4 a = texelFetch(primitives, texel);
  vec4 b = TREE_TRIANGLES ? texelFetch(primitives, texel + 1) : vec4(0.0);
  if (TREE_TRIANGLES) test_triangle(frame, origin, dir, a.xyz, b.xyz, texelFetch(primitives, texel + 2).xyz, slot, hit);
  if (TREE_SPHERES && (!TREE_TRIANGLES || b.w == VKRAY_SPHERE_MARK)) {
    float t = intersect_sphere(origin - a.xyz, a.w, dir, hit.t);
    if (t < hit.t) {
      hit.t = t;
      hit.slot = slot;
    }
  }
}

vec3 primitive_normal(uint slot, vec3 origin, vec3 dir, float t) {
  int texel = 3 * int(slot);
  vec4 a = texelFetch(primitives, texel);
  vec4 b = texelFetch(primitives, texel + 1);
  if (TREE_SPHERES && (!TREE_TRIANGLES || b.w == VKRAY_SPHERE_MARK)) return (origin - a.xyz + t * dir) / a.w;
  return vec3(a.w, b.w, texelFetch(primitives, texel + 2).w);
}

// Every sphere, then every triangle in batches of VKRAY_TRIANGLE_BATCH (one loop iteration each).
PrimitiveHit nearest_primitive_brute_force(RayFrame frame, vec3 origin, vec3 dir, float t_max, uint sphere_count,
                                           uint triangle_slots) {
  PrimitiveHit result = PrimitiveHit(t_max, vec3(0.0), false);
  for (uint i = 0; i < sphere_count; ++i) {
    vec4 sphere = texelFetch(spheres, int(i));
    vec3 f = origin - sphere.xyz;
    float t = intersect_sphere(f, sphere.w, dir, result.t);
    if (t < result.t) {
      result.t = t;
      result.normal = (f + t * dir) / sphere.w;
    }
  }
  SlotHit hit = SlotHit(result.t, no_primitive);
  for (uint batch = 0; batch < triangle_slots; batch += VKRAY_TRIANGLE_BATCH) {
    [[unroll]] for (uint k = 0; k < VKRAY_TRIANGLE_BATCH; ++k) {
      int texel = 3 * int(batch + k);
      test_triangle(frame, origin, dir, texelFetch(primitives, texel).xyz, texelFetch(primitives, texel + 1).xyz,
                    texelFetch(primitives, texel + 2).xyz, batch + k, hit);
    }
  }
  if (hit.slot != no_primitive) result = PrimitiveHit(hit.t, primitive_normal(hit.slot, origin, dir, hit.t), false);
  return result;
}

const uint no_node = 0x7fffffffu;  // `current` once the stack has run dry; no node has this index

// The tree walk, nearer child first, the other on a stack; boxes entered beyond the nearest hit so
// far are skipped. Each iteration takes one step down the tree and tests one primitive of the leaf
// found last: llvmpipe runs both sides of every branch masked, so an iteration costs the node step
// plus the primitive test whatever the ray needs; doing both every time wastes neither. (A node may
// be tested against a nearest hit not yet updated by its leaf's last primitive; that only makes the
// test looser, never culls a hit.)
// `packet` false: each ray walks on its own (per-ray stack). `packet` true: the rays of a subgroup
// walk together, as Embree's packets do on the CPU: one node at a time for all of them, descending
// where any ray's box test passes, nearer child first by majority; every value steering the walk is
// uniform across the subgroup, so the lanes never diverge and share one stack's contents.
PrimitiveHit nearest_primitive_in_tree(RayFrame frame, vec3 origin, vec3 dir, float t_max, const bool packet) {
  vec3 inv_dir = safe_inverse(dir);
  SlotHit hit = SlotHit(t_max, no_primitive);
  bool unfinished = false;
  uint stack[VKRAY_BVH_MAX_DEPTH];
  uint stack_size = 0;
  uint current = 0;  // the root, always an inner node
  uint leaf_next = 0;  // the leaf's primitives still to test: [leaf_next, leaf_end)
  uint leaf_end = 0;
  uint iterations = 0;
  while (current != no_node || leaf_next < leaf_end) {
    if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
      unfinished = true;
      break;
    }
    ++iterations;
    if (leaf_next < leaf_end) test_primitive(frame, origin, dir, leaf_next++, hit);

    bool pop = false;
    if ((current & VKRAY_BVH_LEAF_BIT) != 0) {
      // A leaf waits until the previous one is done.
      if (leaf_next == leaf_end) {
        leaf_next = (current & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
        leaf_end = leaf_next + (current & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
        pop = true;
      }
    } else if (current != no_node) {
      vec2 enter;
      bvec2 hits = ray_hits_boxes(texelFetch(bvh_bounds, 4 * int(current)), texelFetch(bvh_bounds, 4 * int(current) + 1),
                                  texelFetch(bvh_bounds, 4 * int(current) + 2), origin, inv_dir, hit.t, enter);
      uvec2 children = texelFetch(bvh_links, 4 * int(current) + 3).xy;
      bool prefers_second = hits.y && (!hits.x || enter.y < enter.x);
      bool second_first = prefers_second;
      if (packet) {
        hits = bvec2(subgroupAny(hits.x), subgroupAny(hits.y));
        bool prefers_first = hits.x && !prefers_second;
        second_first = subgroupBallotBitCount(subgroupBallot(prefers_second)) >
                       subgroupBallotBitCount(subgroupBallot(prefers_first));
      }
      if (hits.x && hits.y) {
        stack[stack_size++] = second_first ? children.x : children.y;
        current = second_first ? children.y : children.x;
      } else if (hits.x || hits.y) {
        current = hits.x ? children.x : children.y;
      } else {
        pop = true;
      }
    }
    if (pop) current = stack_size > 0 ? stack[--stack_size] : no_node;
  }
  PrimitiveHit result = PrimitiveHit(hit.t, vec3(0.0), unfinished);
  if (hit.slot != no_primitive) result.normal = primitive_normal(hit.slot, origin, dir, hit.t);
  return result;
}

// `counts`: RayGenParams.counts, read only by the generic variant.
PrimitiveHit nearest_primitive(vec3 origin, vec3 dir, float t_max, uvec4 counts) {
  RayFrame frame = make_ray_frame(dir);
  uint search_mode = GENERIC ? counts.w : SEARCH_MODE;
  if (search_mode == VKRAY_SEARCH_BRUTE_FORCE) {
    return nearest_primitive_brute_force(frame, origin, dir, t_max, GENERIC ? counts.x : SPHERE_COUNT,
                                         GENERIC ? counts.z : TRIANGLE_SLOTS);
  }
  return nearest_primitive_in_tree(frame, origin, dir, t_max, search_mode == VKRAY_SEARCH_BVH_PACKET);
}

#endif  // VKRAY_PRIMITIVES_GLSL
