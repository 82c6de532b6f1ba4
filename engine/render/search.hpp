// How rays find the nearest triangle or sphere: each search declared once, with the one name the
// command line (--traversal), Python (traversal=) and the bench's rows use, the shader's mode, and
// what it needs of the device and the shader. Planes are infinite and always tested one by one.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/vulkan/shader_variant.hpp"

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace vkray {

// automatic is the renderer's choice (choose_search), not a search of its own.
enum class PrimitiveSearch : uint32_t {
  automatic,
  brute_force,  // every primitive tested, no tree
  bvh_per_ray,  // the BVH, each ray its own stack
  bvh_packet,   // the BVH, a subgroup's camera rays together (shaders/packet_walk.glsl)
  ray_query,    // the device's acceleration structures, vkray's tests on its candidates (ray_query_walk.glsl)
};

struct SearchInfo {
  PrimitiveSearch search;
  const char* name;         // --traversal, traversal=, the bench's row
  uint32_t shader_mode;     // VKRAY_SEARCH_*
  const char* description;  // for the help texts and the bench's legend
  // Why `device` cannot run it with `shader`; empty where it can.
  std::string (*obstacle)(const GpuDeviceInfo& device, const ShaderVariant& shader);
};

// Every search, in the order the bench and the help texts list them.
std::span<const SearchInfo> searches();
const SearchInfo& search_info(PrimitiveSearch search);

// "auto", then every search's name: what --traversal and traversal= take.
std::string traversal_names();
// The search a --traversal name means (automatic for "auto"); none for another name.
std::optional<PrimitiveSearch> traversal_from_name(std::string_view name);
// The name traversal_from_name takes for `search` ("auto" for automatic).
const char* traversal_name(PrimitiveSearch search);

// Why `search` cannot run on `device` with `shader` (empty where it can; automatic always can).
std::string search_obstacle(PrimitiveSearch search, const GpuDeviceInfo& device, const ShaderVariant& shader);

// At most this many triangles and spheres together are tested one by one rather than through a
// tree where the packet walk does not run (see choose_search).
inline constexpr size_t brute_force_max_primitives = 8;

// The automatic choice for a scene of `triangle_count` triangles and `sphere_count` spheres, before
// any tree is built: brute force for a handful of them, the BVH per ray beyond; with `packet_walk`
// (the renderer favours it) a tree for any triangle, which becomes the packet walk once its depth
// is known to fit (packet_walk_fits).
PrimitiveSearch choose_search(size_t triangle_count, size_t sphere_count, bool packet_walk = false);

// Whether the packet walk takes a tree `depth` edges deep: it keeps its stack in registers.
bool packet_walk_fits(uint32_t depth);

// A handful of spheres beside triangles stay out of the tree, tested one by one before its walk.
bool keeps_spheres_apart(size_t triangle_count, size_t sphere_count);

}  // namespace vkray
