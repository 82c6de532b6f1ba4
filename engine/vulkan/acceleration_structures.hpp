// The device's own acceleration structures for the ray-query traversal (VK_KHR_acceleration_structure):
// a bottom-level structure per mesh over its triangles, one over the spheres' boxes, and a
// top-level one holding an instance of each, in place, and one of an instanced mesh's for each
// placement of it. Built on the device, compacted, for fast tracing; the top level built anew
// where the placements move.
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
  // A `placed` mesh's triangles are in its own coordinates: the top level holds it only where
  // `placements` place it.
  struct Range {
    uint32_t first_slot, count;
    uint8_t mask = 0xff;
    bool placed = false;
  };
  std::vector<Range> meshes;
  // Each placement of a placed mesh (`mesh`: its index in `meshes`): the rows of the 3x4 map from its
  // coordinates to the world's (relative to the anchor, as the vertices are), its mask, and the
  // scene's instance, which the shader reads back as the instance's shader binding table record
  // offset minus one (a ray query has no shader binding table, so the field is free; 0 is the
  // world's own meshes and spheres).
  struct Placement {
    uint32_t mesh = 0;
    std::array<std::array<float, 4>, 3> to_world{};
    uint8_t mask = 0xff;
    uint32_t instance = 0;
  };
  std::vector<Placement> placements;
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

  // The top level built anew for `placements` (the same meshes placed elsewhere, as
  // StructureInput::placements): a new top(), so descriptor sets naming the old one must be
  // written again.
  void place(VulkanContext& context, const std::vector<StructureInput::Placement>& placements);

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
  void build_bottom(VulkanContext& context, const std::vector<Build>& builds);
  void build_top(VulkanContext& context, const std::vector<StructureInput::Placement>& placements);

  vk::DeviceSize alignment_ = 1;  // of build scratch memory
  std::vector<Structure> bottom_;
  // Each bottom structure's instance as the top level holds it in place (a placed mesh's, its
  // transform and mask left for each placement to set), and whether it is placed.
  std::vector<vk::AccelerationStructureInstanceKHR> bottom_instance_;
  std::vector<bool> placed_;
  vk::DeviceSize top_bytes_ = 0;
  GpuBuffer top_storage_;
  vk::raii::AccelerationStructureKHR top_{nullptr};
  vk::DeviceSize bytes_ = 0;
  double build_ms_ = 0.0;
};

}  // namespace vkray
