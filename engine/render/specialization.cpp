#include "engine/render/specialization.hpp"

#include "engine/render/search.hpp"

#include <algorithm>
#include <string>

namespace vkray {
namespace {

// Loop iterations of raycast.comp outside the tree walk, for each of an invocation's rays the
// planes and spheres tested one by one and the loops over those rays, and a margin for the few
// iterations the compiler may keep where it fails to unroll a constant-trip loop.
uint64_t fixed_loop_iterations(const GpuSceneShape& shape) {
  constexpr uint64_t loop_margin = 16;
  constexpr uint64_t loops_over_rays = 4;
  const uint64_t rays = shape.search == PrimitiveSearch::bvh_packet ? VKRAY_PACKET_ROWS : 1;
  uint64_t iterations = rays * (uint64_t{shape.spheres_apart} + shape.planes + loops_over_rays) + loop_margin;
  iterations += shape.brute_force_triangle_slots / VKRAY_TRIANGLE_BATCH + shape.brute_force_placed_iterations;
  return iterations;
}

// VKRAY_SPEC_STACK_REGISTERS for a tree `depth` edges deep: a walk holds at most one stack entry per
// inner node on its path, `depth` of them.
uint32_t stack_registers_for_depth(uint32_t depth) {
  if (depth > VKRAY_STACK_REGISTERS_MAX) return 0;
  return std::max<uint32_t>(4, (depth + 3) / 4 * 4);
}

}  // namespace

uint32_t tree_loop_budget(const GpuSceneShape& shape, const GpuDeviceInfo& device, uint32_t requested) {
  const uint64_t loop_limit = device.max_loop_iterations;
  const uint64_t fixed_iterations = fixed_loop_iterations(shape);
  if (loop_limit > 0 && fixed_iterations >= loop_limit) {
    throw GpuError("this scene needs " + std::to_string(fixed_iterations) + " shader loop iterations per pixel, but " +
                   device.name + " stops a shader after " + std::to_string(loop_limit) +
                   " and would silently drop geometry; use another device (--device)");
  }
  if (shape.search == PrimitiveSearch::brute_force || (loop_limit == 0 && requested == 0)) return 0;
  uint64_t budget = loop_limit > 0 ? loop_limit - fixed_iterations : UINT32_MAX;
  if (requested > 0) budget = std::min<uint64_t>(budget, requested);
  return static_cast<uint32_t>(budget);
}

PipelineSpecialization specialization_for(const GpuSceneShape& shape, uint32_t depth, uint32_t loop_budget,
                                          const ShaderVariant& shader) {
  PipelineSpecialization specialization;
  specialization.spheres = shape.spheres_apart;
  specialization.planes = shape.planes;
  specialization.triangle_slots = shape.brute_force_triangle_slots;
  specialization.search_mode = search_info(shape.search).shader_mode;
  specialization.tree_has_triangles = shape.tree_has_triangles;
  specialization.tree_has_spheres = shape.tree_has_spheres;
  specialization.masks = shape.masks;
  specialization.instances = shape.instances;
  specialization.loop_budget = loop_budget;
  const bool stack_in_registers = shader.stack_in_registers && !shader.generic;
  specialization.stack_registers = !stack_in_registers                           ? 0
                                   : shape.search == PrimitiveSearch::bvh_packet ? VKRAY_STACK_REGISTERS_MAX
                                                                                 : stack_registers_for_depth(depth);
  specialization.variant = shader;
  return specialization;
}

}  // namespace vkray
