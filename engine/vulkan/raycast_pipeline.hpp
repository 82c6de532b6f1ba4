// The compute pipeline of shaders/raycast.comp: its descriptor set, push constants, and one
// pipeline per set of requested outputs, specialized on the scene (PipelineSpecialization).
#pragma once

#include "engine/frame.hpp"
#include "engine/vulkan/shader_variant.hpp"
#include "engine/vulkan/context.hpp"
#include "engine/vulkan/shader_modules.hpp"
#include "shaders/gpu_layout.h"

#include <array>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <optional>

namespace vkray {

// What the pipelines are specialized on besides the outputs (see VKRAY_SPEC_* in gpu_layout.h).
struct PipelineSpecialization {
  uint32_t spheres = 0;
  uint32_t planes = 0;
  uint32_t triangle_slots = 0;
  uint32_t search_mode = VKRAY_SEARCH_BRUTE_FORCE;
  bool tree_has_triangles = false;
  bool tree_has_spheres = false;
  uint32_t loop_budget = 0;
  uint32_t stack_registers = 0;  // VKRAY_SPEC_STACK_REGISTERS
  bool masks = false;            // VKRAY_SPEC_MASKS
  bool instances = false;        // VKRAY_SPEC_INSTANCES
  ShaderVariant variant;
  bool operator==(const PipelineSpecialization&) const = default;
};

// Where a pipeline's rays come from and where its outputs go.
enum class RaycastMode : uint32_t {
  image_buffers,  // a camera's pixels into output buffers
  image_target,   // a camera's pixels into the storage image (VKRAY_SPEC_IMAGE_TARGET)
  given_rays,     // the caller's rays (VKRAY_RAY_INPUT_RAYS) into output buffers
  given_directions,  // the caller's rays from one origin (VKRAY_RAY_INPUT_DIRECTIONS) into output buffers
  caller_arrays,     // the caller's rays from one origin read, and hits written, in its own memory
  points,            // the caller's points (VKRAY_RAY_INPUT_POINTS): their nearest points or winding numbers
};

// Whether the caller gives what is traced (rays or points), laid out as rows of `width` entries.
inline bool is_given(RaycastMode mode) {
  return mode == RaycastMode::given_rays || mode == RaycastMode::given_directions || mode == RaycastMode::caller_arrays ||
         mode == RaycastMode::points;
}

// How float32 shaders on `device` take the triangle edge functions for `requested` (see
// EdgeArithmetic): automatic is double products where the device runs doubles fast
// (GpuDeviceInfo::fast_float64), float elsewhere.
EdgeArithmetic resolve_edges(const GpuDeviceInfo& device, EdgeArithmetic requested);

class RaycastPipeline {
 public:
  RaycastPipeline(VulkanContext& context, PipelineSpecialization specialization);
  const PipelineSpecialization& specialization() const { return specialization_; }

  // The pipeline for this set of outputs, with or without the lo parts of positions
  // (VKRAY_SPEC_LO_PARTS), in `mode`, for `query` and the first `hits` hits (VKRAY_SPEC_HITS), created on first request. `created_ms` receives
  // the creation time, 0 when it was already there. Threads may ask for different pipelines at once
  // (Renderer::prepare_pipelines makes several together); each is compiled outside the lock.
  const vk::raii::Pipeline& pipeline(AovSet aovs, bool lo_parts, RaycastMode mode, double& created_ms,
                                     HitQuery query = HitQuery::nearest, uint32_t hits = 1);

  // What each binding (VKRAY_BINDING_*) reads or writes: a storage buffer, a texel view or a
  // storage image (in the GENERAL layout).
  struct Resources {
    std::array<vk::Buffer, VKRAY_BINDING_COUNT> buffers;
    std::array<vk::DeviceSize, VKRAY_BINDING_COUNT> offsets{};  // where each storage buffer's binding starts
    std::array<vk::BufferView, VKRAY_BINDING_COUNT> texel_views;
    std::array<vk::ImageView, VKRAY_BINDING_COUNT> images;
    vk::AccelerationStructureKHR top_structure;  // the ray-query traversal's
  };
  // The descriptor type of each binding (see gpu_layout.h), as the module declares it
  // (binding_types): geometry as texel or storage buffers, as the variant reads it; the ray-query
  // traversal's pipelines have one binding more, its top-level structure.
  vk::DescriptorType binding_type(uint32_t binding) const;
  bool ray_query() const;
  uint32_t binding_count() const;
  // Points every binding of the descriptor set at its resource.
  void bind_resources(const Resources& resources);

  void bind(const vk::raii::CommandBuffer& commands, const vk::raii::Pipeline& pipeline,
            const gpu::RayGenParams& params) const;
  // True at the first call for `pipeline` alone: lavapipe compiles a pipeline's code at its first
  // dispatch, not when it is made (Renderer::Impl::dispatch_tile runs that one small and untimed).
  bool first_dispatch(const vk::raii::Pipeline& pipeline);

 private:
  VulkanContext& context_;
  PipelineSpecialization specialization_;
  std::optional<ShaderBindings> shader_;  // the module and its descriptor set
  vk::raii::PipelineLayout layout_{nullptr};
  std::map<uint64_t, vk::raii::Pipeline> pipelines_;  // by AovSet bits, bit 32 the lo parts, the mode from bit 33
  std::unique_ptr<std::mutex> pipelines_lock_ = std::make_unique<std::mutex>();  // a pointer: the class moves
  std::set<VkPipeline> dispatched_;
};

}  // namespace vkray
