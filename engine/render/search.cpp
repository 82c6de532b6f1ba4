#include "engine/render/search.hpp"

#include "engine/vulkan/raycast_pipeline.hpp"
#include "shaders/gpu_layout.h"

#include <stdexcept>

namespace vkray {
namespace {

std::string runs_anywhere(const GpuDeviceInfo&, const ShaderVariant&) { return {}; }

// The packet walk's needs (shaders/packet_walk.glsl).
std::string packet_walk_obstacle(const GpuDeviceInfo& device, const ShaderVariant& shader) {
  if (shader.precision != Precision::float32) return "the float64 shader walks the tree per ray";
  if (resolve_edges(device, shader.edges) != EdgeArithmetic::double_products) {
    return "it takes its edge planes in double (double edge functions: the automatic choice where the device runs "
           "doubles fast; elsewhere asked for, where it has shaderFloat64)";
  }
  if (shader.generic) return "the generic shader walks the tree per ray";
  if (!shader.stack_in_registers) return "it keeps its stack in registers";
  if (shader.triangle_test != VKRAY_TRIANGLE_WATERTIGHT) return "it has its own watertight triangle test";
  if (shader.workgroup_width != VKRAY_WORKGROUP_X || shader.workgroup_height != VKRAY_WORKGROUP_Y || !shader.morton_order) {
    return "it lays out its own 8x8 workgroups";
  }
  if (device.subgroup_size < VKRAY_BVH_MAX_LEAF_SIZE) return "it needs subgroups of at least 8 invocations";
  return {};
}

std::string ray_query_obstacle(const GpuDeviceInfo& device, const ShaderVariant& shader) {
  if (!device.ray_query) {
    return "it has no ray queries (VK_KHR_ray_query, VK_KHR_acceleration_structure and buffer device addresses)";
  }
  if (shader.precision != Precision::float32 || shader.storage_geometry || shader.generic) {
    return "the ray-query traversal exists for the float32 shader, with texel buffers, specialized";
  }
  return {};
}

const SearchInfo search_table[] = {
    {PrimitiveSearch::brute_force, "brute-force", VKRAY_SEARCH_BRUTE_FORCE, "every primitive tested, no tree",
     runs_anywhere},
    {PrimitiveSearch::bvh_per_ray, "per-ray", VKRAY_SEARCH_BVH_PER_RAY,
     "BVH, each ray its own stack (the default but on llvmpipe from Mesa 25)", runs_anywhere},
    {PrimitiveSearch::bvh_packet, "packet", VKRAY_SEARCH_BVH_PACKET,
     "BVH, a subgroup's camera rays together, 8 an invocation, double edge functions (the default on llvmpipe from "
     "Mesa 25)",
     packet_walk_obstacle},
    {PrimitiveSearch::ray_query, "ray-query", VKRAY_SEARCH_RAY_QUERY,
     "the device's acceleration structures, vkray's tests on its candidates (ray queries)", ray_query_obstacle},
};

constexpr const char* automatic_name = "auto";

}  // namespace

std::span<const SearchInfo> searches() { return search_table; }

const SearchInfo& search_info(PrimitiveSearch search) {
  for (const auto& info : search_table) {
    if (info.search == search) return info;
  }
  throw std::logic_error("search_info: automatic is no search of its own");
}

std::string traversal_names() {
  std::string names = automatic_name;
  for (const auto& info : search_table) names += std::string(", ") + info.name;
  return names;
}

std::optional<PrimitiveSearch> traversal_from_name(std::string_view name) {
  if (name == automatic_name) return PrimitiveSearch::automatic;
  for (const auto& info : search_table) {
    if (name == info.name) return info.search;
  }
  return std::nullopt;
}

const char* traversal_name(PrimitiveSearch search) {
  return search == PrimitiveSearch::automatic ? automatic_name : search_info(search).name;
}

std::string search_obstacle(PrimitiveSearch search, const GpuDeviceInfo& device, const ShaderVariant& shader) {
  if (search == PrimitiveSearch::automatic) return {};
  return search_info(search).obstacle(device, shader);
}

// Brute force beats the tree up to brute_force_max_primitives triangles and spheres on lavapipe.
// Measured with `vkray bench --size 640x480 --variants brute-force,per-ray` (best of 5 frames):
// random triangles 4: 7.6 against 11.4 ms, 8: 10.4 / 10.9, 16: 23.0 / 9.8, 32: 25.1 / 18.6;
// random spheres 8: 9.3 / 11.5, 16: 13.6 / 11.4, 32: 25.7 / 16.9, 10000: 6395 / 48.6.
// Where the packet walk runs, triangles always go into a tree: brute force tests each triangle per
// ray in batches of VKRAY_TRIANGLE_BATCH, and the packet walk beats it from one triangle on (Mesa
// 25.0.7, 1920x1080, `vkray bench SCENE --variants default,packet`: one triangle filling the frame
// 140.3 against 26.0 ms, one out of view 78.9 against 13.9), while a lone sphere is still faster
// tested one by one (21.7 against 26.9 ms).
PrimitiveSearch choose_search(size_t triangle_count, size_t sphere_count, bool packet_walk) {
  if (packet_walk && triangle_count > 0) return PrimitiveSearch::bvh_per_ray;
  return triangle_count + sphere_count <= brute_force_max_primitives ? PrimitiveSearch::brute_force
                                                                     : PrimitiveSearch::bvh_per_ray;
}

bool packet_walk_fits(uint32_t depth) { return depth <= VKRAY_STACK_REGISTERS_MAX; }

// Apart, the walk's loop holds the triangle test alone. On lavapipe that loop's size is its speed:
// the built-in scene at 960x540 took 46-54 ms a frame with its sphere in the tree, 19-21 ms apart
// (fastest of 20 frames, two runs of `vkray bench --variants default`).
bool keeps_spheres_apart(size_t triangle_count, size_t sphere_count) {
  return triangle_count > 0 && sphere_count <= brute_force_max_primitives;
}

}  // namespace vkray
