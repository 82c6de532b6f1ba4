// The device's own acceleration structures for the ray-query traversal (VK_KHR_acceleration_structure):
// a bottom-level structure per mesh over its triangles, one over the spheres' boxes, and a
// top-level one holding an instance of each. Built on the device, compacted, for fast tracing.
#pragma once

#include "engine/vulkan/buffer.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace vkray {

struct StructureInput {
  // Each distinct vertex, in `vertex_stride`-byte records whose first 12 bytes are its float x, y,
  // z (a GpuPoint's hi part: positions relative to the scene's anchor); every triangle's three
  // vertex indices, mesh by mesh; each mesh's first primitive slot and triangle count.
  const GpuBuffer* vertices = nullptr;
  uint32_t vertex_count = 0;
  vk::DeviceSize vertex_stride = 0;
  std::vector<std::array<uint32_t, 3>> triangles;
  // Each mesh's instance mask is its ray mask (8 bits, as Vulkan's): a ray query whose cull mask
  // shares no bit with it is never proposed its triangles. The spheres' instance takes every bit;
  // the shader tests each sphere's own mask.
  struct Range {
    uint32_t first_slot, count;
    uint8_t mask = 0xff;
  };
  std::vector<Range> meshes;
  // The spheres' boxes (min x, y, z, max x, y, z) and their first slot.
  std::vector<std::array<float, 6>> sphere_boxes;
  uint32_t first_sphere_slot = 0;
};

class AccelerationStructures {
 public:
  // Throws GpuError where the device lacks ray queries or a mesh has more triangles than one
  // structure may hold. The instance of each structure carries its first slot as its custom
  // index (24 bits): a candidate's slot is that plus its primitive index.
  AccelerationStructures(VulkanContext& context, const StructureInput& input);

  vk::AccelerationStructureKHR top() const { return *top_; }
  vk::DeviceSize bytes() const { return bytes_; }  // device memory of every structure, compacted
  double build_ms() const { return build_ms_; }

 private:
  struct Structure {
    GpuBuffer storage;
    vk::raii::AccelerationStructureKHR handle{nullptr};
  };
  struct Build;  // what one bottom structure holds
  static std::vector<Build> describe_builds(const VulkanContext& context, const StructureInput& input,
                                            const GpuBuffer& indices, const GpuBuffer& boxes);
  void build_bottom(VulkanContext& context, const std::vector<Build>& builds, vk::DeviceSize alignment);
  void build_top(VulkanContext& context, const std::vector<Build>& builds, vk::DeviceSize alignment);

  std::vector<Structure> bottom_;
  GpuBuffer top_storage_;
  vk::raii::AccelerationStructureKHR top_{nullptr};
  vk::DeviceSize bytes_ = 0;
  double build_ms_ = 0.0;
};

}  // namespace vkray
