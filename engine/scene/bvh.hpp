// A binary bounding volume hierarchy over primitive boxes, built on the host with the surface area
// heuristic by Embree's builder (rtcBuildBVH) into vkray's own layout. Only the topology and the
// primitive order are kept here: each consumer computes the node bounds in its own precision from
// its own copy of the primitives (float32 for the GPU, double for the reference), so a box always
// holds exactly the primitives as that consumer tests them.
#pragma once

#include "shaders/gpu_layout.h"

#include <glm/vec3.hpp>

#include <array>
#include <bit>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace vkray {

struct Box {
  glm::dvec3 lower;
  glm::dvec3 upper;
};

// The float next to `value`, a finite float, toward -infinity: std::nextafter's result, inline (that
// is a library call, and a refit takes about twenty a triangle: the bunny's refit spent a tenth of
// its time in it).
inline float next_float_down(float value) {
  if (value == 0.0f) return -std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<uint32_t>(value);
  return std::bit_cast<float>(value > 0.0f ? bits - 1u : bits + 1u);
}
inline float next_float_up(float value) { return -next_float_down(-value); }

// The float nearest to `value` on its lower (upper) side: rounding box corners outward keeps a
// float box around what the double box holds.
inline float float_below(double value) {
  const auto rounded = static_cast<float>(value);
  return static_cast<double>(rounded) <= value ? rounded : next_float_down(rounded);
}
inline float float_above(double value) {
  const auto rounded = static_cast<float>(value);
  return static_cast<double>(rounded) >= value ? rounded : next_float_up(rounded);
}

// A child reference as the shader reads it (see VKRAY_BVH_* in shaders/gpu_layout.h): an inner
// node's index, or a leaf's first primitive (in Bvh::primitive_order) and count.
inline bool is_leaf(uint32_t child) { return (child & VKRAY_BVH_LEAF_BIT) != 0; }
inline uint32_t leaf_first(uint32_t child) { return (child & ~VKRAY_BVH_LEAF_BIT) >> VKRAY_BVH_LEAF_COUNT_BITS; }
inline uint32_t leaf_count(uint32_t child) { return (child & ((1u << VKRAY_BVH_LEAF_COUNT_BITS) - 1u)) + 1u; }
uint32_t make_leaf(uint32_t first, uint32_t count);

struct BvhBuildOptions {
  // SAH cost of one node visit relative to one primitive test (Embree's traversalCost /
  // intersectionCost). Leaves hold at most VKRAY_BVH_MAX_LEAF_SIZE primitives. 4: a node step fetches
  // four texels and tests two boxes against one triangle's three texels, and a deeper tree costs
  // stack traffic; on the bunny at 1920x1080 on lavapipe, traversal costs 1, 2, 4 and 8 gave about
  // 190, 179, 170 and 172 ms (best of 7 frames, leaves of up to 4) and 4 also gives the fewest nodes.
  // Leaves of up to 8 then kept the time (165 ms) and took the bunny from 67.6 to 59.6 device bytes
  // a triangle (48 of them the triangle itself).
  float traversal_cost = 4.0f;
  float intersection_cost = 1.0f;
  uint32_t max_leaf_size = VKRAY_BVH_MAX_LEAF_SIZE;
  // Called now and then with the fraction done (0..1), from Embree's threads.
  std::function<void(double)> progress;
};

struct Bvh {
  // Node 0 is the root; every node has exactly two children (a tree of one primitive references
  // its single leaf twice, so the nearest-hit walk needs no special case for a lone leaf; counting
  // crossings or listing first hits skips the second).
  std::vector<std::array<uint32_t, 2>> nodes;
  // Leaves reference ranges of this array; entries are indices into the builder's input boxes.
  std::vector<uint32_t> primitive_order;
  uint32_t depth = 0;  // edges on the longest root-to-leaf path
};

// Builds the tree over `boxes` (at least one; boxes may be flat). Throws std::runtime_error when
// Embree fails and std::length_error beyond VKRAY_BVH_MAX_PRIMITIVES.
Bvh build_bvh(const std::vector<Box>& boxes, const BvhBuildOptions& options = {});

// Bounds of the children of every node `update(node)` selects, in one pass from the leaves up, from
// `primitive_box(index into primitive_order)` and the bounds of the nodes below; BoxType is any type
// with lower/upper members of a vector type. `update` must select a node's parent with it (a refit
// of what moved: the nodes above the moved leaves); `bounds` holds one entry a node.
template <typename BoxType, typename PrimitiveBox, typename Update>
void update_child_bounds(const Bvh& bvh, std::vector<std::array<BoxType, 2>>& bounds, PrimitiveBox primitive_box,
                         Update update) {
  auto merge = [](BoxType a, const BoxType& b) {
    for (int axis = 0; axis < 3; ++axis) {
      a.lower[axis] = a.lower[axis] < b.lower[axis] ? a.lower[axis] : b.lower[axis];
      a.upper[axis] = a.upper[axis] > b.upper[axis] ? a.upper[axis] : b.upper[axis];
    }
    return a;
  };
  auto box_of = [&](uint32_t child) {
    if (!is_leaf(child)) return merge(bounds[child][0], bounds[child][1]);
    BoxType box = primitive_box(leaf_first(child));
    for (uint32_t k = 1; k < leaf_count(child); ++k) box = merge(box, primitive_box(leaf_first(child) + k));
    return box;
  };
  // Children always have larger indices than their parent (depth-first order), so a reverse sweep
  // sees every child before its parent.
  for (size_t node = bvh.nodes.size(); node-- > 0;) {
    if (!update(node)) continue;
    for (int side = 0; side < 2; ++side) bounds[node][side] = box_of(bvh.nodes[node][side]);
  }
}

// Bounds of every node's two children (update_child_bounds of them all).
template <typename BoxType, typename PrimitiveBox>
std::vector<std::array<BoxType, 2>> child_bounds(const Bvh& bvh, PrimitiveBox primitive_box) {
  std::vector<std::array<BoxType, 2>> bounds(bvh.nodes.size());
  update_child_bounds(bvh, bounds, primitive_box, [](size_t) { return true; });
  return bounds;
}

}  // namespace vkray
