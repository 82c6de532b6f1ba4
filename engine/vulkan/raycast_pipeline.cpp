#include "engine/vulkan/raycast_pipeline.hpp"

#include "engine/stopwatch.hpp"
#include "engine/vulkan/shader_modules.hpp"

#include <chrono>

namespace vkray {

EdgeArithmetic resolve_edges(const GpuDeviceInfo& device, EdgeArithmetic requested) {
  if (requested != EdgeArithmetic::automatic) return requested;
  return device.fast_float64 ? EdgeArithmetic::double_products : EdgeArithmetic::float_error_free;
}

// The module for `specialization`: the defines each of its choices takes (shaders/raycast.comp).
const EmbeddedShader& raycast_module(const PipelineSpecialization& specialization, EdgeArithmetic edges) {
  const ShaderVariant& variant = specialization.variant;
  const bool ray_query = specialization.search_mode == VKRAY_SEARCH_RAY_QUERY;
  if (variant.precision == Precision::float64) return embedded_shader("raycast.comp", {"VKRAY_FLOAT64"});
  const bool double_edges = edges == EdgeArithmetic::double_products;
  const char* layout = ray_query ? "VKRAY_RAY_QUERY" : variant.storage_geometry ? "VKRAY_STORAGE_GEOMETRY" : "";
  if (*layout && double_edges) return embedded_shader("raycast.comp", {layout, "VKRAY_DOUBLE_EDGES"});
  if (*layout) return embedded_shader("raycast.comp", {layout});
  if (double_edges) return embedded_shader("raycast.comp", {"VKRAY_DOUBLE_EDGES"});
  return embedded_shader("raycast.comp", {});
}

RaycastPipeline::RaycastPipeline(VulkanContext& context, PipelineSpecialization specialization)
    : context_(context), specialization_(specialization) {
  const bool float64 = specialization.variant.precision == Precision::float64;
  if (float64 && !context.info.shader_float64) {
    throw GpuError(context.info.name + " has no float64 arithmetic in shaders (shaderFloat64); use --precision float");
  }
  const EdgeArithmetic edges = resolve_edges(context.info, specialization.variant.edges);
  if (!float64 && edges == EdgeArithmetic::double_products && !context.info.shader_float64) {
    throw GpuError(context.info.name + " has no float64 arithmetic in shaders (shaderFloat64) for double edge functions");
  }
  if (float64 && specialization.variant.storage_geometry) {
    throw std::invalid_argument("storage-buffer geometry exists for float32 shaders only");
  }
  if (ray_query() && (float64 || specialization.variant.storage_geometry || specialization.variant.generic)) {
    throw GpuError("the ray-query traversal exists for the float32 shader, with texel buffers, specialized");
  }
  // The bindings as the module declares them: geometry as texel or storage buffers, the ray
  // queries' top-level structure where it has one.
  shader_.emplace(context.device, raycast_module(specialization, edges));
  const vk::PushConstantRange push_range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(gpu::RayGenParams));
  const vk::DescriptorSetLayout set_layout = *shader_->layout;
  layout_ = vk::raii::PipelineLayout(context.device, vk::PipelineLayoutCreateInfo({}, set_layout, push_range));
}

const vk::raii::Pipeline& RaycastPipeline::pipeline(AovSet aovs, bool lo_parts, RaycastMode mode, double& created_ms,
                                                    HitQuery query, uint32_t hits) {
  created_ms = 0.0;
  // The output bits in the low word, then the lo parts, the mode (three bits) and the query above every
  // output's bit (Aov::hit is 256, where the lo parts once were: two different pipelines shared a key).
  const uint64_t key = uint64_t{aovs.bits()} | (uint64_t{lo_parts} << 32) | (uint64_t{static_cast<uint32_t>(mode)} << 33) |
                       (uint64_t{static_cast<uint32_t>(query)} << 36) | (uint64_t{hits} << 40);
  {
    const std::lock_guard lock(*pipelines_lock_);
    if (auto found = pipelines_.find(key); found != pipelines_.end()) return found->second;
  }

  const auto start = Clock::now();
  // One 32-bit value per VKRAY_SPEC_* id (SPIR-V booleans are 32-bit), stored at the id's index.
  std::array<uint32_t, VKRAY_SPEC_COUNT> values{};
  values[VKRAY_SPEC_SPHERE_COUNT] = specialization_.spheres;
  values[VKRAY_SPEC_PLANE_COUNT] = specialization_.planes;
  values[VKRAY_SPEC_TRIANGLE_SLOTS] = specialization_.triangle_slots;
  values[VKRAY_SPEC_SEARCH_MODE] = specialization_.search_mode;
  values[VKRAY_SPEC_TREE_HAS_TRIANGLES] = specialization_.tree_has_triangles ? 1u : 0u;
  values[VKRAY_SPEC_TREE_HAS_SPHERES] = specialization_.tree_has_spheres ? 1u : 0u;
  values[VKRAY_SPEC_LOOP_BUDGET] = specialization_.loop_budget;
  values[VKRAY_SPEC_WRITE_DEPTH] = aovs.has(Aov::depth) ? 1u : 0u;
  values[VKRAY_SPEC_WRITE_NORMAL] = aovs.has(Aov::normal) ? 1u : 0u;
  values[VKRAY_SPEC_WRITE_UV] = aovs.has(Aov::uv) ? 1u : 0u;
  values[VKRAY_SPEC_WRITE_HIT] = aovs.has(Aov::hit) ? 1u : 0u;
  const ShaderVariant& variant = specialization_.variant;
  values[VKRAY_SPEC_SPHERE_FORMULA] = variant.sphere_formula;
  values[VKRAY_SPEC_TRIANGLE_TEST] = variant.triangle_test;
  values[VKRAY_SPEC_WORKGROUP_X] = variant.workgroup_width;
  values[VKRAY_SPEC_WORKGROUP_Y] = variant.workgroup_height;
  values[VKRAY_SPEC_MORTON_ORDER] = variant.morton_order ? 1u : 0u;
  values[VKRAY_SPEC_GENERIC] = variant.generic ? 1u : 0u;
  values[VKRAY_SPEC_COORDINATES] = variant.coordinates;
  values[VKRAY_SPEC_LO_PARTS] = lo_parts ? 1u : 0u;
  values[VKRAY_SPEC_IMAGE_TARGET] = mode == RaycastMode::image_target ? 1u : 0u;
  values[VKRAY_SPEC_RAY_INPUT] = mode == RaycastMode::given_rays         ? VKRAY_RAY_INPUT_RAYS
                                : mode == RaycastMode::given_directions ? VKRAY_RAY_INPUT_DIRECTIONS
                                : mode == RaycastMode::caller_arrays    ? VKRAY_RAY_INPUT_CALLER_DIRECTIONS
                                : mode == RaycastMode::points           ? VKRAY_RAY_INPUT_POINTS
                                                                        : VKRAY_RAY_INPUT_NONE;
  values[VKRAY_SPEC_STACK_REGISTERS] = specialization_.stack_registers;
  values[VKRAY_SPEC_SUBGROUP_SIZE] = context_.info.subgroup_size == 8 ? 8u : 0u;
  values[VKRAY_SPEC_HIT_QUERY] = static_cast<uint32_t>(query);
  values[VKRAY_SPEC_MASKS] = specialization_.masks ? 1u : 0u;
  values[VKRAY_SPEC_HITS] = hits;
  values[VKRAY_SPEC_INSTANCES] = specialization_.instances ? 1u : 0u;
  std::array<vk::SpecializationMapEntry, values.size()> entries;
  for (uint32_t id = 0; id < entries.size(); ++id) entries[id] = vk::SpecializationMapEntry(id, id * 4u, 4u);
  const vk::SpecializationInfo specialization(entries, vk::ArrayProxyNoTemporaries<const uint32_t>(values));
  const vk::PipelineShaderStageCreateInfo stage({}, vk::ShaderStageFlagBits::eCompute, *shader_->module, "main", &specialization);
  // Vulkan synchronizes a pipeline cache within the implementation (it is no externally synchronized
  // parameter of vkCreateComputePipelines): pipelines are compiled side by side.
  vk::raii::Pipeline created(context_.device, context_.pipeline_cache->handle(), vk::ComputePipelineCreateInfo({}, stage, *layout_));
  const std::lock_guard lock(*pipelines_lock_);
  auto [entry, inserted] = pipelines_.emplace(key, std::move(created));
  context_.pipeline_cache->save();
  created_ms = elapsed_ms(start);
  return entry->second;
}

bool RaycastPipeline::first_dispatch(const vk::raii::Pipeline& pipeline) {
  const std::lock_guard lock(*pipelines_lock_);
  return dispatched_.insert(*pipeline).second;
}

bool RaycastPipeline::ray_query() const { return specialization_.search_mode == VKRAY_SEARCH_RAY_QUERY; }

uint32_t RaycastPipeline::binding_count() const { return static_cast<uint32_t>(shader_->types.size()); }

vk::DescriptorType RaycastPipeline::binding_type(uint32_t binding) const { return shader_->types.at(binding); }

void RaycastPipeline::bind_resources(const Resources& resources) {
  std::array<vk::DescriptorBufferInfo, VKRAY_BINDING_COUNT> buffer_infos;
  std::array<vk::DescriptorImageInfo, VKRAY_BINDING_COUNT> image_infos;
  std::vector<vk::WriteDescriptorSet> writes(binding_count());
  const vk::WriteDescriptorSetAccelerationStructureKHR top_structure(resources.top_structure);
  for (uint32_t i = 0; i < binding_count(); ++i) {
    writes[i] = vk::WriteDescriptorSet(*shader_->set, i, 0, 1, binding_type(i));
    switch (binding_type(i)) {
      case vk::DescriptorType::eAccelerationStructureKHR:
        writes[i].setPNext(&top_structure);
        break;
      case vk::DescriptorType::eStorageBuffer:
        buffer_infos[i] = vk::DescriptorBufferInfo(resources.buffers[i], resources.offsets[i], VK_WHOLE_SIZE);
        writes[i].setPBufferInfo(&buffer_infos[i]);
        break;
      case vk::DescriptorType::eStorageImage:
        image_infos[i] = vk::DescriptorImageInfo({}, resources.images[i], vk::ImageLayout::eGeneral);
        writes[i].setPImageInfo(&image_infos[i]);
        break;
      default:
        writes[i].setPTexelBufferView(&resources.texel_views[i]);
        break;
    }
  }
  context_.device.updateDescriptorSets(writes, {});
}

void RaycastPipeline::bind(const vk::raii::CommandBuffer& commands, const vk::raii::Pipeline& pipeline,
                           const gpu::RayGenParams& params) const {
  commands.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline);
  commands.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *layout_, 0, {*shader_->set}, {});
  commands.pushConstants<gpu::RayGenParams>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, params);
}

}  // namespace vkray
