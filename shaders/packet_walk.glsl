// The packet walk (VKRAY_SEARCH_BVH_PACKET): the camera rays of a subgroup walk the tree together,
// one node at a time for all of them, as ray packets do on CPUs (Wald, Slusallek, Benthin and
// Wagner, "Interactive Rendering with Coherent Ray Tracing", 2001; Reshetov, Soupikov and Hurley,
// "Multi-Level Ray Tracing Algorithm", 2005, for packets larger than the SIMD width). Each
// invocation traces VKRAY_PACKET_ROWS rays down one column of the packet (raycast.comp), so a
// lavapipe subgroup of 8 lanes carries the 64 rays of an 8x8 block of pixels.
//
// Built for llvmpipe (Mesa 25), which runs a subgroup as the lanes of one SIMD vector and loads
// every lane's texel separately, so that what a node or leaf costs is paid once per 64 rays:
// - everything that steers the walk is uniform across the subgroup: the lanes never diverge;
// - lanes 0-3 fetch a node's four texels at once, and every lane takes them by a broadcast from a
//   constant lane (one extract and splat on llvmpipe);
// - lane k prepares the leaf's k-th primitive (a triangle's camera-relative vertices and edge
//   planes, or a sphere), which then reaches every ray by broadcast;
// - a node's boxes and a leaf's triangles meet the packet as a whole first, by bounds of its rays,
//   and its rays one by one only where that leaves them in (rays_hit_boxes, packet_misses_triangle).
// On the bunny at 1920x1080 this took 36 ms against 149 for per-ray walks (Mesa 25.0.7), where
// one ray a lane took 82 ms, two 49 and four 43.
// Instances (INSTANCES): a leaf's instances come after its other entries (place_instances). The
// packet enters the first the call's mask lets through, its rays taken into the mesh's coordinates
// (ray_in_mesh): they share one origin there too, so the walk and its tests are the world's. What
// remains of the leaf goes on the stack, under instance_marker, whose pop takes the world's rays
// back, as in the per-ray walk (nearest_primitive_in_tree).
// Compiled into the modules with VKRAY_DOUBLE_EDGES (CPU devices with shaderFloat64): the
// triangle test below takes its edge planes in double.
#ifndef VKRAY_PACKET_WALK_GLSL
#define VKRAY_PACKET_WALK_GLSL

#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require

#include "gpu_layout.h"
#include "primitives.glsl"

// The device's subgroup size where it is 8 (lavapipe on 256-bit vectors), else 0: with 8, the
// bitwise or and the minimum over a packet are made of constant-lane broadcasts, which llvmpipe 25
// runs as vector shuffles, where its subgroupOr and subgroupMin loop over the lanes.
layout(constant_id = VKRAY_SPEC_SUBGROUP_SIZE) const uint SUBGROUP_SIZE = 0;

uint packet_or(uint v) {
  if (SUBGROUP_SIZE != 8u) return subgroupOr(v);
  return ((subgroupBroadcast(v, 0u) | subgroupBroadcast(v, 1u)) | (subgroupBroadcast(v, 2u) | subgroupBroadcast(v, 3u))) |
         ((subgroupBroadcast(v, 4u) | subgroupBroadcast(v, 5u)) | (subgroupBroadcast(v, 6u) | subgroupBroadcast(v, 7u)));
}

float packet_min(float value) {
  if (SUBGROUP_SIZE != 8u) return subgroupMin(value);
  return select_min(select_min(select_min(subgroupBroadcast(value, 0u), subgroupBroadcast(value, 1u)),
                               select_min(subgroupBroadcast(value, 2u), subgroupBroadcast(value, 3u))),
                    select_min(select_min(subgroupBroadcast(value, 4u), subgroupBroadcast(value, 5u)),
                               select_min(subgroupBroadcast(value, 6u), subgroupBroadcast(value, 7u))));
}

// Exact: negation is, and the minimum of the negated values is the negated maximum.
float packet_max(float value) { return -packet_min(-value); }

vec3 packet_min(vec3 value) { return vec3(packet_min(value.x), packet_min(value.y), packet_min(value.z)); }
vec3 packet_max(vec3 value) { return vec3(packet_max(value.x), packet_max(value.y), packet_max(value.z)); }

// A leaf's primitive as the lane that prepared it holds it: for a triangle with camera-relative
// vertices a, b, c, the normals of the planes through the camera and each edge, a x b, b x c and
// c x a, and det(a, b, c); for a sphere, its centre and radius.
struct PacketPrimitive {
  bool sphere;
  dvec3 edge_ab, edge_bc, edge_ca;
  double volume;
  Point center_radius;
};

// Lane k's PacketPrimitive, for every lane. A macro: a broadcast's lane must be a constant
// expression (SPIR-V 1.3).
#define VKRAY_BROADCAST_PRIMITIVE(p, k)                                                                        \
  PacketPrimitive(subgroupBroadcast(p.sphere, k), subgroupBroadcast(p.edge_ab, k), subgroupBroadcast(p.edge_bc, k), \
                  subgroupBroadcast(p.edge_ca, k), subgroupBroadcast(p.volume, k),                                     \
                  Point(subgroupBroadcast(p.center_radius.hi, k), subgroupBroadcast(p.center_radius.lo, k)))

PacketPrimitive prepare_packet_primitive(uint slot, Origin origin) {
  PacketPrimitive primitive;
  uvec4 record = FETCH(primitives, int(slot));
  // An instance's record holds no vertex indices; the walk enters it instead of testing it.
  if (INSTANCES && (record.w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_INSTANCE) record = uvec4(0u);
  primitive.sphere = TREE_SPHERES && (!TREE_TRIANGLES || (record.w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_SPHERE);
  primitive.center_radius = TREE_SPHERES ? fetch_point(vertices, int(record.x)) : Point(vec4(0.0), vec4(0.0));
  if (TREE_TRIANGLES) {
    // Floats to double are exact, and so is each product of two of them (48 of 53 bits): every
    // component of a cross product is rounded once. A triangle's vertices are in lexicographic
    // order (make_gpu_scene), so an edge (p, q), p before q, gives p x q or (as c x a) q x p in
    // every triangle that has it, bit for bit the same up to sign: `precise` keeps the operations
    // as written, and (-n) . d is then exactly -(n . d).
    dvec3 a = dvec3(point_from_origin(fetch_point(vertices, int(record.x)), origin));
    dvec3 b = dvec3(point_from_origin(fetch_point(vertices, int(record.y)), origin));
    dvec3 c = dvec3(point_from_origin(fetch_point(vertices, int(record.z)), origin));
    precise dvec3 ab = cross(a, b);
    precise dvec3 bc = cross(b, c);
    precise dvec3 ca = cross(c, a);
    precise double volume = dot(a, bc);
    primitive.edge_ab = ab;
    primitive.edge_bc = bc;
    primitive.edge_ca = ca;
    primitive.volume = volume;
  }
  return primitive;
}

// A ray from the camera in direction d meets the triangle where the signed volumes d . (a x b),
// d . (b x c), d . (c x a) share a sign (zeros allowed), at t = det(a, b, c) / their sum. These are
// Woop, Benthin and Wald's edge functions up to a positive factor, without the ray's shear, since
// every ray starts at the camera; they are watertight for the same reason as theirs: a ray through
// an edge shared by two triangles gets exact negatives of one value in the two (see
// prepare_packet_primitive), so at least one takes it. Each sign is that of a double sum within a
// few 2^-53 of its terms: no rounding of the float vertices' own size decides a side.
float packet_triangle_t(PacketPrimitive triangle, dvec3 dir, float t_max) {
  precise double w_ab = dot(dir, triangle.edge_ab);
  precise double w_bc = dot(dir, triangle.edge_bc);
  precise double w_ca = dot(dir, triangle.edge_ca);
  bool inside = (w_ab >= 0.0 && w_bc >= 0.0 && w_ca >= 0.0) || (w_ab <= 0.0 && w_bc <= 0.0 && w_ca <= 0.0);
  precise double sum = (w_ab + w_bc) + w_ca;
  if (!inside || sum == 0.0) return t_max;  // sum 0: the ray lies in the triangle's plane
  float t = float(triangle.volume / sum);
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// The box of a packet's directions, component by component, and the larger magnitude of its ends.
struct DirectionBox {
  dvec3 lo, hi, magnitude;
};

// Whether no ray of the packet can pass inside the triangle (packet_triangle_t): where an edge
// function d . n is negative for every direction d of the box and another one positive, every ray
// is outside. Over a box, d . n ranges from the sum of the smaller of lo_i n_i and hi_i n_i to the
// sum of the larger (Moore's interval arithmetic; the culling of triangles by a packet's bounds as in
// Reshetov, Soupikov and Hurley 2005). Each of these sums and each ray's d . n in the test is within
// 3 * 2^-53 * sum |d_i n_i| of its exact value, so a sign is taken as certain only beyond
// 2^-48 * sum magnitude_i |n_i|, more than twice that: a culled triangle is one the test would
// reject for every ray of the packet, and the walk's hits are the same bit for bit.
bool packet_misses_triangle(PacketPrimitive triangle, DirectionBox dirs) {
  bool negative = false, positive = false;
  [[unroll]] for (uint e = 0; e < 3; ++e) {
    dvec3 n = e == 0 ? triangle.edge_ab : (e == 1 ? triangle.edge_bc : triangle.edge_ca);
    dvec3 at_lo = dirs.lo * n, at_hi = dirs.hi * n;
    dvec3 low = min(at_lo, at_hi), high = max(at_lo, at_hi);
    double margin = 3.552713678800501e-15LF * dot(dirs.magnitude, abs(n));
    negative = negative || (high.x + high.y) + high.z < -margin;
    positive = positive || (low.x + low.y) + low.z > margin;
  }
  return negative && positive;
}

// One of a leaf's primitives, placed by `instance` (INSTANCES), against the invocation's rays:
// where it is nearer than a ray's nearest hit so far, it becomes that ray's.
void test_packet_primitive(PacketPrimitive primitive, uint slot, uint instance, Origin origin, vec3 dirs[VKRAY_PACKET_ROWS],
                           dvec3 double_dirs[VKRAY_PACKET_ROWS], inout float t_max[VKRAY_PACKET_ROWS],
                           inout uint slots[VKRAY_PACKET_ROWS], inout uint instances[VKRAY_PACKET_ROWS]) {
  if (TREE_SPHERES && (!TREE_TRIANGLES || primitive.sphere)) {
    [[unroll]] for (uint r = 0; r < VKRAY_PACKET_ROWS; ++r) {
      vec3 normal;
      float t = intersect_sphere_point(primitive.center_radius, origin, dirs[r], t_max[r], normal);
      if (t < t_max[r]) t_max[r] = t, slots[r] = slot, instances[r] = instance;
    }
  } else {
    [[unroll]] for (uint r = 0; r < VKRAY_PACKET_ROWS; ++r) {
      float t = packet_triangle_t(primitive, double_dirs[r], t_max[r]);
      if (t < t_max[r]) t_max[r] = t, slots[r] = slot, instances[r] = instance;
    }
  }
}

// The rays as the walk tests them, all from `origin` (the world's, or an instance's mesh's): each
// one's inverse direction and its direction in double; for tests of the packet as a whole, the
// box of its directions (culling a leaf's triangles, packet_misses_triangle) and of their inverses
// (the interval test of a node's boxes, rays_hit_boxes). Rays past the image's edge count too: they
// only widen the bounds.
struct PacketRays {
  Origin origin;
  vec3 dirs[VKRAY_PACKET_ROWS];
  vec3 inv_dirs[VKRAY_PACKET_ROWS];
  dvec3 double_dirs[VKRAY_PACKET_ROWS];
  vec3 box_margin;
  DirectionBox dir_box;
  vec3 inv_lo, inv_hi;
};

PacketRays packet_rays(Origin origin, vec3 dirs[VKRAY_PACKET_ROWS]) {
  PacketRays rays;
  rays.origin = origin;
  rays.dirs = dirs;
  [[unroll]] for (uint r = 0; r < VKRAY_PACKET_ROWS; ++r) {
    rays.inv_dirs[r] = safe_inverse(dirs[r]);
    rays.double_dirs[r] = dvec3(dirs[r]);
  }
  rays.box_margin = abs(origin.lo);
  vec3 dir_lo = dirs[0], dir_hi = dirs[0], inv_lo = rays.inv_dirs[0], inv_hi = rays.inv_dirs[0];
  [[unroll]] for (uint r = 1; r < VKRAY_PACKET_ROWS; ++r) {
    dir_lo = min(dir_lo, dirs[r]);
    dir_hi = max(dir_hi, dirs[r]);
    inv_lo = min(inv_lo, rays.inv_dirs[r]);
    inv_hi = max(inv_hi, rays.inv_dirs[r]);
  }
  dir_lo = packet_min(dir_lo);
  dir_hi = packet_max(dir_hi);
  rays.dir_box = DirectionBox(dvec3(dir_lo), dvec3(dir_hi), dvec3(max(abs(dir_lo), abs(dir_hi))));
  rays.inv_lo = packet_min(inv_lo);
  rays.inv_hi = packet_max(inv_hi);
  return rays;
}

// The nearest hit of each of the invocation's rays, all from the camera `origin`, each searched up
// to its t_max (0 for rays past the image's edge: they never steer the walk), and the instance
// placing it (INSTANCES; else VKRAY_NO_INSTANCE).
void nearest_primitives_packet(Origin origin, vec3 dirs[VKRAY_PACKET_ROWS], inout float t_max[VKRAY_PACKET_ROWS],
                               out uint slots[VKRAY_PACKET_ROWS], out uint instances[VKRAY_PACKET_ROWS], out bool unfinished) {
  PacketRays walk = packet_rays(origin, dirs);
  uint instance = VKRAY_NO_INSTANCE;  // the one whose mesh the walk is in
  float row_t_max = t_max[0];
  [[unroll]] for (uint r = 0; r < VKRAY_PACKET_ROWS; ++r) {
    slots[r] = no_primitive;
    instances[r] = VKRAY_NO_INSTANCE;
    row_t_max = max(row_t_max, t_max[r]);
  }
  // The rays' largest t_max, for the interval test of a node's boxes.
  float packet_t_max = packet_max(row_t_max);
  uint lane = gl_SubgroupInvocationID;
  unfinished = false;
  RegisterStack stack = RegisterStack(uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u), uvec4(0u),
                                      uvec4(0u));
  uint stack_size = 0;
  uint current = 0;  // the root, always an inner node
  uint iterations = 0;
  while (true) {
    if (LOOP_BUDGET > 0 && iterations == LOOP_BUDGET) {
      unfinished = true;
      break;
    }
    ++iterations;
    bool pop;
    if (INSTANCES && current == instance_marker) {  // the mesh's last leaf is done: the world's rays again
      walk = packet_rays(origin, dirs);
      instance = VKRAY_NO_INSTANCE;
      pop = true;
    } else if ((current & VKRAY_BVH_LEAF_BIT) != 0) {
      uint first = (current & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS;
      uint count = (current & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u;
      // Lanes past the leaf's end prepare its last primitive again: every lane has work, none reads
      // past the buffer.
      uint mine_slot = first + min(lane, count - 1u);
      PacketPrimitive mine = prepare_packet_primitive(mine_slot, walk.origin);
      bool mine_instance = INSTANCES && (FETCH(primitives, int(mine_slot)).w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_INSTANCE;
      // A primitive the call's mask hides is missed by every ray, as one the packet misses.
      bool mine_missed = mine_instance || (TREE_TRIANGLES && !mine.sphere && packet_misses_triangle(mine, walk.dir_box)) ||
                         !slot_visible(mine_slot);
      // One line a slot, since a broadcast's lane must be a constant.
#define VKRAY_TEST_LEAF_SLOT(k) \
  if (count > k && !subgroupBroadcast(mine_missed, k)) test_packet_primitive(VKRAY_BROADCAST_PRIMITIVE(mine, k), first + k, instance, walk.origin, walk.dirs, walk.double_dirs, t_max, slots, instances)
      VKRAY_TEST_LEAF_SLOT(0u);
      VKRAY_TEST_LEAF_SLOT(1u);
      VKRAY_TEST_LEAF_SLOT(2u);
      VKRAY_TEST_LEAF_SLOT(3u);
      VKRAY_TEST_LEAF_SLOT(4u);
      VKRAY_TEST_LEAF_SLOT(5u);
      VKRAY_TEST_LEAF_SLOT(6u);
      VKRAY_TEST_LEAF_SLOT(7u);
#undef VKRAY_TEST_LEAF_SLOT
#if VKRAY_BVH_MAX_LEAF_SIZE != 8
#error "a slot line per leaf slot"
#endif
      // An occlusion query's ray with a hit searches no further: its bound, and so its t, drops to 0.
      if (ANY_HIT) {
        [[unroll]] for (uint r = 0; r < VKRAY_PACKET_ROWS; ++r) t_max[r] = slots[r] != no_primitive ? 0.0 : t_max[r];
      }
      row_t_max = t_max[0];
      [[unroll]] for (uint r = 1; r < VKRAY_PACKET_ROWS; ++r) row_t_max = max(row_t_max, t_max[r]);
      packet_t_max = packet_max(row_t_max);
      if (ANY_HIT && packet_t_max == 0.0) break;
      pop = true;
      // The leaf's first instance the mask lets through, entered; the rest of the leaf (instances
      // alone) under the marker.
      uint entering = INSTANCES ? packet_or(mine_instance && lane < count && slot_visible(mine_slot) ? 1u << lane : 0u) : 0u;
      if (entering != 0u) {
        uint k = findLSB(entering);
        if (k + 1u < count) {
          push_registers(stack, VKRAY_BVH_LEAF_BIT | ((first + k + 1u) << VKRAY_BVH_LEAF_COUNT_BITS) | (count - k - 2u));
          ++stack_size;
        }
        push_registers(stack, instance_marker);
        ++stack_size;
        uvec4 record = FETCH(primitives, int(first + k));
        instance = record.x;
        Placement placement = fetch_placement(instance);
        Origin mesh_origin;
        vec3 mesh_dirs[VKRAY_PACKET_ROWS];
        [[unroll]] for (uint r = 0; r < VKRAY_PACKET_ROWS; ++r) ray_in_mesh(placement, origin, dirs[r], mesh_origin, mesh_dirs[r]);
        walk = packet_rays(mesh_origin, mesh_dirs);
        current = record.y;
        pop = false;
      }
    } else {
      // Lane k fetches the node's texel k & 3 (GpuBvhNode): bounds x, y, z, then the children.
      vec4 texel = FETCH(bvh_bounds, 4 * int(current) + int(lane & 3u));
      vec4 bounds_x = subgroupBroadcast(texel, 0u);
      vec4 bounds_y = subgroupBroadcast(texel, 1u);
      vec4 bounds_z = subgroupBroadcast(texel, 2u);
      uvec2 children = floatBitsToUint(subgroupBroadcast(texel.xy, 3u));
      // Per child: whether any ray enters it, and the nearest entry among the rays tested. First
      // for the whole packet by interval arithmetic (one test, conservative); then, for the
      // children that one leaves in, ray by ray a row at a time, only until each has a ray that
      // enters it: where one does, the packet goes in, whatever the other rows (interval culling
      // and the first ray that hits, as in Wald, Boulos and Shirley, "Ray Tracing Deformable
      // Scenes Using Dynamic Bounding Volume Hierarchies", ACM TOG 26(1), 2007). The middle rows
      // go first, the likeliest to meet a box that meets the packet at all: room.json at
      // 1920x1080 took 45.7-51.7 ms with them first, 46.2-52.5 in order (three runs each).
      vec2 packet_enter;
      bvec2 maybe = rays_hit_boxes(bounds_x, bounds_y, bounds_z, walk.origin.hi, walk.box_margin, walk.inv_lo, walk.inv_hi,
                                   packet_t_max, packet_enter);
      const float never = 3.0e38;
      vec2 enter = vec2(never);
      bool first_hit = false, second_hit = false;
      if (maybe.x || maybe.y) {
        [[unroll]] for (uint k = 0; k < VKRAY_PACKET_ROWS; ++k) {
#if VKRAY_PACKET_ROWS != 8
#error "a row order for 8 rows"
#endif
          const uint row_order[8] = uint[8](3u, 4u, 0u, 7u, 1u, 6u, 2u, 5u);
          uint r = row_order[k];
          vec2 ray_enter;
          bvec2 hits = ray_hits_boxes(bounds_x, bounds_y, bounds_z, walk.origin.hi, walk.box_margin, walk.inv_dirs[r], t_max[r],
                                      ray_enter);
          enter = select_min(enter, mix(vec2(never), ray_enter, hits));
          uint either = packet_or((hits.x ? 1u : 0u) | (hits.y ? 2u : 0u));
          first_hit = first_hit || (either & 1u) != 0u;
          second_hit = second_hit || (either & 2u) != 0u;
          if ((first_hit || !maybe.x) && (second_hit || !maybe.y)) break;
        }
      }
      pop = !first_hit && !second_hit;
      if (first_hit && second_hit) {
        bool second_first = packet_min(enter.y) < packet_min(enter.x);
        push_registers(stack, second_first ? children.x : children.y);
        ++stack_size;
        current = second_first ? children.y : children.x;
      } else if (first_hit || second_hit) {
        current = first_hit ? children.x : children.y;
      }
    }
    if (pop) {
      if (stack_size == 0) break;
      --stack_size;
      current = pop_registers(stack);
    }
  }
}

#endif  // VKRAY_PACKET_WALK_GLSL
