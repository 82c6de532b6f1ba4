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

void test_triangle(RayFrame frame, vec3 origin, uint slot, inout TriangleHit hit) {
  int texel = 3 * int(slot);
  float t = intersect_triangle(frame, origin, texelFetch(triangles, texel).xyz, texelFetch(triangles, texel + 1).xyz,
                               texelFetch(triangles, texel + 2).xyz, hit.t);
  if (t < hit.t) {
    hit.t = t;
    hit.slot = slot;
  }
}

// A leaf's triangles, unrolled to the largest leaf (a constant trip count: no loop for llvmpipe's
// iteration cap to count).
void test_leaf(RayFrame frame, vec3 origin, uint leaf, inout TriangleHit hit) {
  uint first = (leaf & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
  uint count = (leaf & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
  [[unroll]] for (uint k = 0; k < VKRAY_BVH_MAX_LEAF_SIZE; ++k) {
    if (k < count) test_triangle(frame, origin, first + k, hit);
  }
}

TriangleHit nearest_triangle_brute_force(RayFrame frame, vec3 origin, float t_max) {
  TriangleHit hit = TriangleHit(t_max, no_triangle, false);
  for (uint batch = 0; batch < TRIANGLE_SLOTS; batch += VKRAY_TRIANGLE_BATCH) {
    [[unroll]] for (uint k = 0; k < VKRAY_TRIANGLE_BATCH; ++k) test_triangle(frame, origin, batch + k, hit);
  }
  return hit;
}

// Each ray walks the tree on its own: nearer child first, the other on a stack; boxes entered
// beyond the nearest hit so far are skipped.
TriangleHit nearest_triangle_per_ray(RayFrame frame, vec3 origin, vec3 inv_dir, float t_max) {
  TriangleHit hit = TriangleHit(t_max, no_triangle, false);
  uint stack[VKRAY_BVH_MAX_DEPTH];
  uint stack_size = 0;
  uint current = 0;  // the root, always an inner node
  uint iterations = 0;
  while (true) {
    if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
      hit.unfinished = true;
      break;
    }
    ++iterations;
    if ((current & VKRAY_BVH_LEAF_BIT) == 0) {
      vec2 enter;
      bvec2 hits = ray_hits_boxes(texelFetch(bvh_bounds, 4 * int(current)), texelFetch(bvh_bounds, 4 * int(current) + 1),
                                  texelFetch(bvh_bounds, 4 * int(current) + 2), origin, inv_dir, hit.t, enter);
      uvec2 children = texelFetch(bvh_links, 4 * int(current) + 3).xy;
      if (hits.x && hits.y) {
        bool second_first = enter.y < enter.x;
        stack[stack_size++] = second_first ? children.x : children.y;
        current = second_first ? children.y : children.x;
        continue;
      }
      if (hits.x || hits.y) {
        current = hits.x ? children.x : children.y;
        continue;
      }
    } else {
      test_leaf(frame, origin, current, hit);
    }
    if (stack_size == 0) break;
    current = stack[--stack_size];
  }
  return hit;
}

// The rays of a subgroup walk the tree together, as Embree's packets do on the CPU: one node at a
// time for all of them, descending where any ray's box test passes, nearer child first by majority.
// Every value steering the walk is uniform across the subgroup, so its lanes never diverge:
// lavapipe runs divergent lanes masked, and coherent primary rays mostly want the same nodes.
TriangleHit nearest_triangle_packet(RayFrame frame, vec3 origin, vec3 inv_dir, float t_max) {
  TriangleHit hit = TriangleHit(t_max, no_triangle, false);
  uint stack[VKRAY_BVH_MAX_DEPTH];
  uint stack_size = 0;
  uint current = 0;
  uint iterations = 0;
  while (true) {
    if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
      hit.unfinished = true;
      break;
    }
    ++iterations;
    if ((current & VKRAY_BVH_LEAF_BIT) == 0) {
      vec2 enter;
      bvec2 hits = ray_hits_boxes(texelFetch(bvh_bounds, 4 * int(current)), texelFetch(bvh_bounds, 4 * int(current) + 1),
                                  texelFetch(bvh_bounds, 4 * int(current) + 2), origin, inv_dir, hit.t, enter);
      uvec2 children = texelFetch(bvh_links, 4 * int(current) + 3).xy;
      bool any_first = subgroupAny(hits.x);
      bool any_second = subgroupAny(hits.y);
      if (any_first && any_second) {
        bool prefers_second = hits.y && (!hits.x || enter.y < enter.x);
        bool prefers_first = hits.x && !prefers_second;
        bool second_first = subgroupBallotBitCount(subgroupBallot(prefers_second)) >
                            subgroupBallotBitCount(subgroupBallot(prefers_first));
        stack[stack_size++] = second_first ? children.x : children.y;
        current = second_first ? children.y : children.x;
        continue;
      }
      if (any_first || any_second) {
        current = any_first ? children.x : children.y;
        continue;
      }
    } else {
      test_leaf(frame, origin, current, hit);
    }
    if (stack_size == 0) break;
    current = stack[--stack_size];
  }
  return hit;
}

TriangleHit nearest_triangle(vec3 origin, vec3 dir, float t_max) {
  RayFrame frame = make_ray_frame(dir);
  if (TRIANGLE_MODE == VKRAY_TRIANGLES_BRUTE_FORCE) return nearest_triangle_brute_force(frame, origin, t_max);
  vec3 inv_dir = safe_inverse(dir);
  if (TRIANGLE_MODE == VKRAY_TRIANGLES_BVH_PER_RAY) return nearest_triangle_per_ray(frame, origin, inv_dir, t_max);
  return nearest_triangle_packet(frame, origin, inv_dir, t_max);
}

#endif  // VKRAY_TRIANGLES_GLSL
