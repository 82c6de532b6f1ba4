// Nearest triangle along a ray: brute force over every triangle (tiny meshes), or a walk of the
// BVH, per ray or per subgroup packet (VKRAY_SPEC_TRIANGLE_MODE). Triangles and nodes are laid out
// as shaders/gpu_layout.h describes.
#ifndef VKRAY_TRIANGLES_GLSL
#define VKRAY_TRIANGLES_GLSL

#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_EXT_control_flow_attributes : require

#include "gpu_layout.h"
#include "intersect.glsl"

layout(constant_id = VKRAY_SPEC_TRIANGLE_COUNT) const uint TRIANGLE_SLOTS = 0;
layout(constant_id = VKRAY_SPEC_TRIANGLE_MODE) const uint TRIANGLE_MODE = VKRAY_TRIANGLES_NONE;
layout(constant_id = VKRAY_SPEC_LOOP_BUDGET) const uint LOOP_BUDGET = 0;

layout(binding = VKRAY_BINDING_TRIANGLES) uniform samplerBuffer triangles;     // GpuTriangle: 3 texels
layout(binding = VKRAY_BINDING_BVH_BOUNDS) uniform samplerBuffer bvh_bounds;   // GpuBvhNode: 4 texels
layout(binding = VKRAY_BINDING_BVH_LINKS) uniform usamplerBuffer bvh_links;    // the same, as uints

const uint no_triangle = 0xffffffffu;

struct TriangleHit {
  float t;     // t_max when nothing nearer was found
  uint slot;   // the triangle's slot, or no_triangle
  bool unfinished;  // the walk ran out of LOOP_BUDGET: the host must finish this ray
};

vec3 triangle_normal(uint slot) {
  int texel = 3 * int(slot);
  return vec3(texelFetch(triangles, texel).w, texelFetch(triangles, texel + 1).w, texelFetch(triangles, texel + 2).w);
}

void test_triangle(RayFrame frame, vec3 origin, vec3 v0, vec3 v1, vec3 v2, uint slot, inout TriangleHit hit) {
  float t = intersect_triangle(frame, origin, v0, v1, v2, hit.t);
  if (t < hit.t) {
    hit.t = t;
    hit.slot = slot;
  }
}

void fetch_and_test_triangle(RayFrame frame, vec3 origin, uint slot, inout TriangleHit hit) {
  int texel = 3 * int(slot);
  test_triangle(frame, origin, texelFetch(triangles, texel).xyz, texelFetch(triangles, texel + 1).xyz,
                texelFetch(triangles, texel + 2).xyz, slot, hit);
}

TriangleHit nearest_triangle_brute_force(RayFrame frame, vec3 origin, float t_max) {
  TriangleHit hit = TriangleHit(t_max, no_triangle, false);
  for (uint batch = 0; batch < TRIANGLE_SLOTS; batch += VKRAY_TRIANGLE_BATCH) {
    [[unroll]] for (uint k = 0; k < VKRAY_TRIANGLE_BATCH; ++k) fetch_and_test_triangle(frame, origin, batch + k, hit);
  }
  return hit;
}

const uint no_node = 0x7fffffffu;  // `current` once the stack has run dry; no node has this index

// The tree walk, nearer child first, the other on a stack; boxes entered beyond the nearest hit so
// far are skipped. Each iteration takes one step down the tree and tests one triangle of the leaf
// found last: llvmpipe runs both sides of every branch masked, so an iteration costs the node step
// plus the triangle test whatever the ray needs; doing both every time wastes neither. (A node may
// be tested against a nearest hit not yet updated by its leaf's last triangle; that only makes the
// test looser, never culls a hit.)
// `packet` false: each ray walks on its own (per-ray stack). `packet` true: the rays of a subgroup
// walk together, as Embree's packets do on the CPU: one node at a time for all of them, descending
// where any ray's box test passes, nearer child first by majority; every value steering the walk is
// uniform across the subgroup, so the lanes never diverge and share one stack's contents.
TriangleHit nearest_triangle_in_tree(RayFrame frame, vec3 origin, vec3 inv_dir, float t_max, const bool packet) {
  TriangleHit hit = TriangleHit(t_max, no_triangle, false);
  uint stack[VKRAY_BVH_MAX_DEPTH];
  uint stack_size = 0;
  uint current = 0;  // the root, always an inner node
  uint leaf_next = 0;  // the leaf's triangles still to test: [leaf_next, leaf_end)
  uint leaf_end = 0;
  uint iterations = 0;
  while (current != no_node || leaf_next < leaf_end) {
    if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
      hit.unfinished = true;
      break;
    }
    ++iterations;
    if (leaf_next < leaf_end) fetch_and_test_triangle(frame, origin, leaf_next++, hit);

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
  return hit;
}

TriangleHit nearest_triangle(vec3 origin, vec3 dir, float t_max) {
  RayFrame frame = make_ray_frame(dir);
  if (TRIANGLE_MODE == VKRAY_TRIANGLES_BRUTE_FORCE) return nearest_triangle_brute_force(frame, origin, t_max);
  vec3 inv_dir = safe_inverse(dir);
  return nearest_triangle_in_tree(frame, origin, inv_dir, t_max, TRIANGLE_MODE == VKRAY_TRIANGLES_BVH_PACKET);
}

#endif  // VKRAY_TRIANGLES_GLSL
