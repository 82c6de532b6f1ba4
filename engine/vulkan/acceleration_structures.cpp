#include "engine/vulkan/acceleration_structures.hpp"

#include "engine/stopwatch.hpp"

#include <chrono>
#include <cstring>

namespace vkray {
namespace {

constexpr auto input_usage =
    vk::BufferUsageFlagBits::eAccelerationStructureBuildInputReadOnlyKHR | vk::BufferUsageFlagBits::eShaderDeviceAddress;
constexpr auto storage_usage =
    vk::BufferUsageFlagBits::eAccelerationStructureStorageKHR | vk::BufferUsageFlagBits::eShaderDeviceAddress;
// A custom index holds 24 bits.
constexpr uint32_t max_custom_index = (1u << 24) - 1;

// A build reads what the host or a transfer wrote; a structure is read by the builds after it.
constexpr auto build_stage = vk::PipelineStageFlagBits::eAccelerationStructureBuildKHR;
constexpr auto input_stages = vk::PipelineStageFlagBits::eTransfer | vk::PipelineStageFlagBits::eHost;
const vk::MemoryBarrier inputs_written(vk::AccessFlagBits::eTransferWrite | vk::AccessFlagBits::eHostWrite,
                                       vk::AccessFlagBits::eShaderRead);
const vk::MemoryBarrier structures_built(vk::AccessFlagBits::eAccelerationStructureWriteKHR,
                                         vk::AccessFlagBits::eAccelerationStructureReadKHR);

vk::DeviceSize align_up(vk::DeviceSize value, vk::DeviceSize alignment) {
  return alignment == 0 ? value : (value + alignment - 1) / alignment * alignment;
}

}  // namespace

// One structure to build: its geometry, how many primitives, and what its instance carries.
struct AccelerationStructures::Build {
  vk::AccelerationStructureGeometryKHR geometry;
  uint32_t primitives = 0;
  uint32_t primitive_offset = 0;  // bytes into the index data
  uint32_t first_slot = 0;
  uint8_t mask = 0xff;  // the instance's
  bool placed = false;  // StructureInput::Range::placed
};

// What to build, a structure per mesh and one for the spheres; throws where one is more than the
// device or the 24-bit custom index allows.
std::vector<AccelerationStructures::Build> AccelerationStructures::describe_builds(const VulkanContext& context,
                                                                                  const StructureInput& input,
                                                                                  const GpuBuffer& indices,
                                                                                  const GpuBuffer& boxes) {
  std::vector<Build> builds;
  uint32_t triangles_before = 0;
  for (const auto& mesh : input.meshes) {
    Build build;
    const vk::AccelerationStructureGeometryTrianglesDataKHR triangles(
        vk::Format::eR32G32B32Sfloat, device_address(context, *input.vertices), input.vertex_stride,
        input.vertex_count - 1, vk::IndexType::eUint32, device_address(context, indices));
    // Not opaque: every candidate goes to the shader, which tests it itself; each once (a device may
    // otherwise propose a primitive it split twice), which counting crossings and listing first hits need.
    build.geometry = vk::AccelerationStructureGeometryKHR(vk::GeometryTypeKHR::eTriangles, triangles,
                                                          vk::GeometryFlagBitsKHR::eNoDuplicateAnyHitInvocation);
    build.primitives = mesh.count;
    build.primitive_offset = triangles_before * static_cast<uint32_t>(sizeof(input.triangles[0]));
    build.first_slot = mesh.first_slot;
    build.mask = mesh.mask;
    build.placed = mesh.placed;
    builds.push_back(build);
    triangles_before += mesh.count;
  }
  if (!input.sphere_boxes.empty()) {
    Build build;
    const vk::AccelerationStructureGeometryAabbsDataKHR aabbs(device_address(context, boxes), sizeof(input.sphere_boxes[0]));
    build.geometry = vk::AccelerationStructureGeometryKHR(vk::GeometryTypeKHR::eAabbs, aabbs,
                                                          vk::GeometryFlagBitsKHR::eNoDuplicateAnyHitInvocation);
    build.primitives = static_cast<uint32_t>(input.sphere_boxes.size());
    build.first_slot = input.first_sphere_slot;
    builds.push_back(build);
  }
  for (const Build& build : builds) {
    if (build.primitives > context.info.max_structure_primitives) {
      throw GpuError("a mesh of " + std::to_string(build.primitives) + " triangles is more than " + context.info.name +
                     " puts in one acceleration structure (" + std::to_string(context.info.max_structure_primitives) + ")");
    }
    if (build.first_slot + build.primitives - 1 > max_custom_index) {
      throw GpuError("ray queries take scenes of up to " + std::to_string(max_custom_index + 1) + " triangles and spheres");
    }
  }

  return builds;
}

AccelerationStructures::AccelerationStructures(VulkanContext& context, const StructureInput& input) {
  if (!context.info.ray_query) {
    throw GpuError(context.info.name + " has no ray queries (VK_KHR_ray_query, VK_KHR_acceleration_structure and buffer "
                                       "device addresses): use another traversal");
  }
  const auto start = Clock::now();
  // The build's inputs, on the device; dropped once the structures are built.
  GpuBuffer indices, boxes;
  if (!input.triangles.empty()) {
    indices = upload_buffer(context, input.triangles.data(), input.triangles.size() * sizeof(input.triangles[0]), input_usage);
  }
  if (!input.sphere_boxes.empty()) {
    boxes = upload_buffer(context, input.sphere_boxes.data(), input.sphere_boxes.size() * sizeof(input.sphere_boxes[0]),
                          input_usage);
  }

  const std::vector<Build> builds = describe_builds(context, input, indices, boxes);
  alignment_ = std::max<vk::DeviceSize>(1, context.info.structure_scratch_alignment);
  if (!builds.empty()) build_bottom(context, builds);
  // Each bottom structure's instance, in place, its first slot as its custom index.
  const vk::TransformMatrixKHR identity(std::array<std::array<float, 4>, 3>{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}});
  for (size_t k = 0; k < bottom_.size(); ++k) {
    const vk::DeviceAddress address = context.device.getAccelerationStructureAddressKHR(
        vk::AccelerationStructureDeviceAddressInfoKHR(*bottom_[k].handle));
    bottom_instance_.emplace_back(identity, builds[k].first_slot, builds[k].mask, 0,
                                  vk::GeometryInstanceFlagBitsKHR::eForceNoOpaque, address);
    placed_.push_back(builds[k].placed);
  }
  for (const StructureInput::Placement& placement : input.placements) {
    if (placement.instance + 1 > max_custom_index) {
      throw GpuError("ray queries take scenes of up to " + std::to_string(max_custom_index) + " instances");
    }
  }
  build_top(context, input.placements);
  build_ms_ = elapsed_ms(start);
}

void AccelerationStructures::place(VulkanContext& context, const std::vector<StructureInput::Placement>& placements) {
  const auto start = Clock::now();
  bytes_ -= top_bytes_;
  build_top(context, placements);
  build_ms_ = elapsed_ms(start);
}

// Builds the bottom structures side by side, then copies each into storage of its compacted size.
void AccelerationStructures::build_bottom(VulkanContext& context, const std::vector<Build>& builds) {
  const vk::raii::Device& device = context.device;
  const vk::DeviceSize alignment = alignment_;
  // Sizes, storage and scratch: each build its own part of one scratch buffer, so they need no
  // barrier between them.
  const auto flags = vk::BuildAccelerationStructureFlagBitsKHR::ePreferFastTrace |
                     vk::BuildAccelerationStructureFlagBitsKHR::eAllowCompaction;
  std::vector<vk::AccelerationStructureBuildGeometryInfoKHR> infos;
  std::vector<vk::DeviceSize> scratch_offsets;
  vk::DeviceSize scratch_size = 0;
  std::vector<Structure> built(builds.size());
  for (size_t k = 0; k < builds.size(); ++k) {
    vk::AccelerationStructureBuildGeometryInfoKHR info(vk::AccelerationStructureTypeKHR::eBottomLevel, flags,
                                                        vk::BuildAccelerationStructureModeKHR::eBuild, {}, {}, builds[k].geometry);
    const auto sizes =
        device.getAccelerationStructureBuildSizesKHR(vk::AccelerationStructureBuildTypeKHR::eDevice, info, builds[k].primitives);
    built[k].storage = create_device_buffer(context, sizes.accelerationStructureSize, storage_usage);
    built[k].handle = vk::raii::AccelerationStructureKHR(
        device, vk::AccelerationStructureCreateInfoKHR({}, *built[k].storage.buffer, 0, sizes.accelerationStructureSize,
                                                       vk::AccelerationStructureTypeKHR::eBottomLevel));
    info.dstAccelerationStructure = *built[k].handle;
    scratch_size = align_up(scratch_size, alignment);
    scratch_offsets.push_back(scratch_size);
    scratch_size += sizes.buildScratchSize;
    infos.push_back(info);
  }
  GpuBuffer scratch = create_device_buffer(
      context, std::max<vk::DeviceSize>(scratch_size + alignment, 1),
      vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress);
  const vk::DeviceAddress scratch_base = align_up(device_address(context, scratch), alignment);
  std::vector<vk::AccelerationStructureBuildRangeInfoKHR> ranges;
  for (size_t k = 0; k < builds.size(); ++k) {
    infos[k].scratchData.deviceAddress = scratch_base + scratch_offsets[k];
    ranges.emplace_back(builds[k].primitives, builds[k].primitive_offset, 0, 0);
  }
  std::vector<const vk::AccelerationStructureBuildRangeInfoKHR*> range_pointers;
  for (const auto& range : ranges) range_pointers.push_back(&range);

  // Build, then measure what compaction leaves.
  const vk::raii::QueryPool compacted_sizes(
      device, vk::QueryPoolCreateInfo({}, vk::QueryType::eAccelerationStructureCompactedSizeKHR,
                                      std::max<uint32_t>(1, static_cast<uint32_t>(builds.size()))));
  std::vector<vk::AccelerationStructureKHR> handles;
  for (const auto& structure : built) handles.push_back(*structure.handle);
  {
    context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      commands.pipelineBarrier(input_stages, build_stage, {},
                               inputs_written, {}, {});
      commands.buildAccelerationStructuresKHR(infos, range_pointers);
      commands.pipelineBarrier(build_stage, build_stage, {}, structures_built, {}, {});
      commands.resetQueryPool(*compacted_sizes, 0, static_cast<uint32_t>(handles.size()));
      commands.writeAccelerationStructuresPropertiesKHR(handles, vk::QueryType::eAccelerationStructureCompactedSizeKHR,
                                                        *compacted_sizes, 0);
    });
    const auto [result, sizes] = compacted_sizes.getResults<vk::DeviceSize>(
        0, static_cast<uint32_t>(handles.size()), handles.size() * sizeof(vk::DeviceSize), sizeof(vk::DeviceSize),
        vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
    if (result != vk::Result::eSuccess) throw GpuError("the acceleration structures' compacted sizes did not arrive");
    bottom_.resize(built.size());
    for (size_t k = 0; k < built.size(); ++k) {
      bottom_[k].storage = create_device_buffer(context, sizes[k], storage_usage);
      bottom_[k].handle = vk::raii::AccelerationStructureKHR(
          device, vk::AccelerationStructureCreateInfoKHR({}, *bottom_[k].storage.buffer, 0, sizes[k],
                                                         vk::AccelerationStructureTypeKHR::eBottomLevel));
      bytes_ += sizes[k];
    }
    context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      for (size_t k = 0; k < built.size(); ++k) {
        commands.copyAccelerationStructureKHR(vk::CopyAccelerationStructureInfoKHR(
            *built[k].handle, *bottom_[k].handle, vk::CopyAccelerationStructureModeKHR::eCompact));
      }
      commands.pipelineBarrier(build_stage, build_stage, {}, structures_built, {}, {});
    });
  }
}

void AccelerationStructures::build_top(VulkanContext& context, const std::vector<StructureInput::Placement>& placements) {
  const vk::raii::Device& device = context.device;
  const vk::DeviceSize alignment = alignment_;
  // The top: each bottom structure in place but a placed mesh's (the scene's positions are already
  // where they belong), then each placement of a placed mesh.
  std::vector<vk::AccelerationStructureInstanceKHR> instances;
  for (size_t k = 0; k < bottom_.size(); ++k) {
    if (!placed_[k]) instances.push_back(bottom_instance_[k]);
  }
  for (const StructureInput::Placement& placement : placements) {
    const vk::AccelerationStructureInstanceKHR& mesh = bottom_instance_.at(placement.mesh);
    instances.emplace_back(vk::TransformMatrixKHR(placement.to_world), mesh.instanceCustomIndex, placement.mask,
                           placement.instance + 1, vk::GeometryInstanceFlagBitsKHR::eForceNoOpaque,
                           mesh.accelerationStructureReference);
  }
  GpuBuffer instance_buffer;
  vk::AccelerationStructureGeometryKHR top_geometry(vk::GeometryTypeKHR::eInstances,
                                                    vk::AccelerationStructureGeometryInstancesDataKHR(VK_FALSE, {}));
  if (!instances.empty()) {
    instance_buffer = upload_buffer(context, instances.data(), instances.size() * sizeof(instances[0]), input_usage);
    top_geometry.geometry.instances.data.deviceAddress = device_address(context, instance_buffer);
  }
  vk::AccelerationStructureBuildGeometryInfoKHR top_info(vk::AccelerationStructureTypeKHR::eTopLevel,
                                                          vk::BuildAccelerationStructureFlagBitsKHR::ePreferFastTrace,
                                                          vk::BuildAccelerationStructureModeKHR::eBuild, {}, {}, top_geometry);
  const auto instance_count = static_cast<uint32_t>(instances.size());
  const auto top_sizes =
      device.getAccelerationStructureBuildSizesKHR(vk::AccelerationStructureBuildTypeKHR::eDevice, top_info, instance_count);
  top_storage_ = create_device_buffer(context, top_sizes.accelerationStructureSize, storage_usage);
  top_ = vk::raii::AccelerationStructureKHR(
      device, vk::AccelerationStructureCreateInfoKHR({}, *top_storage_.buffer, 0, top_sizes.accelerationStructureSize,
                                                     vk::AccelerationStructureTypeKHR::eTopLevel));
  top_bytes_ = top_sizes.accelerationStructureSize;
  bytes_ += top_bytes_;
  GpuBuffer top_scratch = create_device_buffer(context, top_sizes.buildScratchSize + alignment,
                                               vk::BufferUsageFlagBits::eStorageBuffer | vk::BufferUsageFlagBits::eShaderDeviceAddress);
  top_info.dstAccelerationStructure = *top_;
  top_info.scratchData.deviceAddress = align_up(device_address(context, top_scratch), alignment);
  const vk::AccelerationStructureBuildRangeInfoKHR top_range(instance_count, 0, 0, 0);
  const vk::AccelerationStructureBuildRangeInfoKHR* top_ranges[] = {&top_range};
  context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    commands.pipelineBarrier(input_stages, build_stage, {},
                             inputs_written, {}, {});
    commands.buildAccelerationStructuresKHR(top_info, top_ranges);
    // Every later ray query reads the structures.
    commands.pipelineBarrier(build_stage, vk::PipelineStageFlagBits::eComputeShader, {}, structures_built, {}, {});
  });
}

}  // namespace vkray
