#include "engine/scene/bvh.hpp"

#include <embree3/rtcore.h>
#include <glm/common.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace vkray {
namespace {

// The builder's own tree, allocated by Embree's thread-local allocator and freed with the RTCBVH.
struct BuildNode {
  bool leaf;
  uint32_t count;  // leaf: primitives; inner node: always 2
  void* children[2];
  uint32_t primitives[VKRAY_BVH_MAX_LEAF_SIZE];
};

void* create_node(RTCThreadLocalAllocator allocator, unsigned int child_count, void*) {
  auto* node = static_cast<BuildNode*>(rtcThreadLocalAlloc(allocator, sizeof(BuildNode), alignof(BuildNode)));
  *node = BuildNode{false, child_count, {nullptr, nullptr}, {}};
  return node;
}

void set_node_children(void* node, void** children, unsigned int child_count, void*) {
  for (unsigned int i = 0; i < child_count; ++i) static_cast<BuildNode*>(node)->children[i] = children[i];
}

void set_node_bounds(void*, const RTCBounds**, unsigned int, void*) {}  // bounds are recomputed per consumer

void* create_leaf(RTCThreadLocalAllocator allocator, const RTCBuildPrimitive* primitives, size_t count, void*) {
  auto* node = static_cast<BuildNode*>(rtcThreadLocalAlloc(allocator, sizeof(BuildNode), alignof(BuildNode)));
  *node = BuildNode{true, static_cast<uint32_t>(count), {nullptr, nullptr}, {}};
  for (size_t i = 0; i < count; ++i) node->primitives[i] = primitives[i].primID;
  return node;
}

bool report_progress(void* user, double fraction) {
  (*static_cast<const std::function<void(double)>*>(user))(fraction);
  return true;
}

RTCDevice embree_device() {
  static const RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw std::runtime_error("cannot start Embree (rtcNewDevice failed)");
  return device;
}

// Flattens the builder's tree depth first (a child always after its parent, the first child right
// after it), appending leaf primitives to primitive_order in the same order.
class Flattener {
 public:
  explicit Flattener(Bvh& bvh) : bvh_(bvh) {}

  uint32_t add(const BuildNode* node, uint32_t depth) {
    bvh_.depth = std::max(bvh_.depth, depth);
    if (node->leaf) {
      const auto first = static_cast<uint32_t>(bvh_.primitive_order.size());
      bvh_.primitive_order.insert(bvh_.primitive_order.end(), node->primitives, node->primitives + node->count);
      return make_leaf(first, node->count);
    }
    const auto index = static_cast<uint32_t>(bvh_.nodes.size());
    bvh_.nodes.push_back({});
    const uint32_t first = add(static_cast<const BuildNode*>(node->children[0]), depth + 1);
    const uint32_t second = add(static_cast<const BuildNode*>(node->children[1]), depth + 1);
    bvh_.nodes[index] = {first, second};
    return index;
  }

 private:
  Bvh& bvh_;
};

}  // namespace

uint32_t make_leaf(uint32_t first, uint32_t count) {
  return VKRAY_BVH_LEAF_BIT | (first << VKRAY_BVH_LEAF_COUNT_BITS) | (count - 1u);
}

Bvh build_bvh(const std::vector<Box>& boxes, const BvhBuildOptions& options) {
  if (boxes.empty()) throw std::invalid_argument("build_bvh: no primitives");
  if (boxes.size() > VKRAY_BVH_MAX_PRIMITIVES) {
    throw std::length_error(std::to_string(boxes.size()) + " primitives in one BVH; at most " +
                            std::to_string(VKRAY_BVH_MAX_PRIMITIVES) + " fit its leaf references");
  }
  // Embree's builder works on float boxes. Rounding outward keeps every box valid; the tree's
  // topology is all that is kept, so the rounding only nudges SAH decisions.
  std::vector<RTCBuildPrimitive> primitives(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    const Box& box = boxes[i];
    primitives[i] = {float_below(box.lower.x), float_below(box.lower.y), float_below(box.lower.z), 0,
                     float_above(box.upper.x),   float_above(box.upper.y),   float_above(box.upper.z),   static_cast<unsigned>(i)};
  }

  RTCBVH builder = rtcNewBVH(embree_device());
  RTCBuildArguments arguments = rtcDefaultBuildArguments();
  arguments.buildQuality = RTC_BUILD_QUALITY_MEDIUM;  // binned SAH; HIGH would add spatial splits
  arguments.maxBranchingFactor = 2;
  arguments.maxDepth = VKRAY_BVH_MAX_DEPTH;
  arguments.minLeafSize = 1;
  arguments.maxLeafSize = std::min<uint32_t>(options.max_leaf_size, VKRAY_BVH_MAX_LEAF_SIZE);
  arguments.traversalCost = options.traversal_cost;
  arguments.intersectionCost = options.intersection_cost;
  arguments.bvh = builder;
  arguments.primitives = primitives.data();
  arguments.primitiveCount = primitives.size();
  arguments.primitiveArrayCapacity = primitives.size();
  arguments.createNode = create_node;
  arguments.setNodeChildren = set_node_children;
  arguments.setNodeBounds = set_node_bounds;
  arguments.createLeaf = create_leaf;
  if (options.progress) {
    arguments.buildProgress = report_progress;
    arguments.userPtr = const_cast<std::function<void(double)>*>(&options.progress);
  }

  Bvh bvh;
  try {
    const auto* root = static_cast<const BuildNode*>(rtcBuildBVH(&arguments));
    if (const RTCError error = rtcGetDeviceError(embree_device()); !root || error != RTC_ERROR_NONE) {
      throw std::runtime_error("Embree's BVH builder failed (RTCError " + std::to_string(error) + ")");
    }
    bvh.nodes.reserve(2 * boxes.size() / std::max<uint32_t>(1, arguments.maxLeafSize) + 1);
    bvh.primitive_order.reserve(boxes.size());
    Flattener flattener(bvh);
    if (root->leaf) {
      // A lone leaf: a root whose two children are that leaf (see Bvh::nodes).
      bvh.nodes.push_back({});
      const uint32_t leaf = flattener.add(root, 1);
      bvh.nodes[0] = {leaf, leaf};
    } else {
      flattener.add(root, 0);
    }
  } catch (...) {
    rtcReleaseBVH(builder);
    throw;
  }
  rtcReleaseBVH(builder);
  return bvh;
}

}  // namespace vkray
