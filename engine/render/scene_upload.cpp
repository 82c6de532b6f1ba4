#include "engine/render/gpu_scene_encoding.hpp"
#include "engine/render/renderer_impl.hpp"
#include "engine/render/specialization.hpp"

#include <cstring>
#include <string>

namespace vkray {
namespace {

TexelBuffer make_texel_buffer(VulkanContext& context, const void* data, vk::DeviceSize bytes,
                              vk::BufferUsageFlags extra_usage = {}) {
  return texel_views_of(context, upload_buffer(context, data, bytes, geometry_usage | extra_usage));
}

uint32_t checked_count(size_t count, const char* what) {
  if (count > UINT32_MAX) throw InputError(std::string("too many ") + what + " for one scene");
  return static_cast<uint32_t>(count);
}

}  // namespace

std::vector<StructureInput::Placement> structure_placements(const GpuScene& gpu_scene, const Scene& scene) {
  std::vector<uint32_t> structure_of_mesh(scene.meshes.size(), UINT32_MAX);
  for (uint32_t k = 0; k < gpu_scene.structure_meshes.size(); ++k) {
    if (gpu_scene.structure_meshes[k].placed) structure_of_mesh[gpu_scene.structure_meshes[k].mesh] = k;
  }
  std::vector<StructureInput::Placement> placements;
  for (uint32_t k = 0; k < scene.instances.size(); ++k) {
    const Instance& instance = scene.instances[k];
    if (structure_of_mesh[instance.mesh] == UINT32_MAX) continue;  // a mesh without a triangle of non-zero area
    StructureInput::Placement placement;
    placement.mesh = structure_of_mesh[instance.mesh];
    const glm::dvec3 translation = instance.translation - gpu_scene.anchor;
    for (int row = 0; row < 3; ++row) {
      for (int column = 0; column < 3; ++column) placement.to_world[row][column] = static_cast<float>(instance.linear[column][row]);
      placement.to_world[row][3] = static_cast<float>(translation[row]);
    }
    placement.mask = static_cast<uint8_t>(instance.mask);
    placement.instance = k;
    placements.push_back(placement);
  }
  return placements;
}

void Renderer::Impl::upload_scene(const GpuScene& gpu_scene, const Scene& scene) {
  const vk::DeviceSize buffer_limit = binding_limit();
  auto upload = [&]<typename T>(const std::vector<T>& items, const char* what,
                                vk::BufferUsageFlags extra_usage = {}) -> std::optional<TexelBuffer> {
    static_assert(sizeof(T) % texel_bytes == 0);
    if (items.empty()) return std::nullopt;
    const vk::DeviceSize bytes = items.size() * sizeof(T);
    if (bytes > buffer_limit) {
      throw GpuError("the scene's " + std::string(what) + " take " + std::to_string(bytes >> 20) + " MiB, more than " +
                     context.info.name + " can bind as one buffer (" + std::to_string(buffer_limit >> 20) +
                     " MiB)");
    }
    return make_texel_buffer(context, items.data(), bytes, extra_usage);
  };
  spheres = upload(gpu_scene.spheres, "spheres");
  if (!gpu_scene.planes.empty()) {  // host-visible: their heights above the camera change every render
    const vk::DeviceSize bytes = gpu_scene.planes.size() * sizeof(gpu::GpuPlane);
    planes = texel_views_of(context, create_upload_buffer(context, bytes, geometry_usage));
    std::memcpy(planes->buffer.mapped, gpu_scene.planes.data(), bytes);
    gpu_planes = gpu_scene.planes;
    scene_planes = scene.planes;
  }
  primitives = upload(gpu_scene.primitives, "triangles and spheres");
  const bool ray_query = gpu_scene.search == PrimitiveSearch::ray_query;
  // The ray-query traversal's structures are built from the vertex buffer itself.
  vertices = upload(gpu_scene.vertices, "vertices",
                    ray_query ? vk::BufferUsageFlagBits::eAccelerationStructureBuildInputReadOnlyKHR |
                                    vk::BufferUsageFlagBits::eShaderDeviceAddress
                              : vk::BufferUsageFlags{});
  normals = upload(gpu_scene.normal_texels, "triangle normals");
  bvh_nodes = upload(gpu_scene.bvh_nodes, "BVH nodes");
  apart_masks = upload(gpu_scene.apart_masks, "masks");
  instances = upload(gpu_scene.instance_texels, "instances");
  hit_sources = gpu_scene.hit_sources;
  hit_source_table.reset();
  stats = SceneStats{gpu_scene.triangle_count, static_cast<uint32_t>(scene.spheres.size()),
                     gpu_scene.geometry_bytes(), static_cast<uint32_t>(gpu_scene.bvh_nodes.size()),
                     gpu_scene.bvh_depth, gpu_scene.search, 0};
  if (ray_query) {
    StructureInput input;
    input.vertices = &vertices->buffer;
    input.vertex_count = static_cast<uint32_t>(gpu_scene.vertices.size());
    input.vertex_stride = sizeof(gpu::GpuPoint);
    for (const auto& mesh : gpu_scene.structure_meshes) {
      // The mesh's mask, as each of its triangles' records carries it.
      const Mask mask = scene_encoding::primitive_mask(gpu_scene.primitives[mesh.first].indices.w);
      input.meshes.push_back({mesh.first, mesh.count, mask, mesh.placed});
      for (uint32_t slot = mesh.first; slot < mesh.first + mesh.count; ++slot) {
        const glm::uvec4& record = gpu_scene.primitives[slot].indices;
        input.triangles.push_back({record.x, record.y, record.z});
      }
    }
    input.placements = structure_placements(gpu_scene, scene);
    input.sphere_boxes = gpu_scene.sphere_boxes;
    input.first_sphere_slot = gpu_scene.structure_spheres.first;
    structures.emplace(context, input);
    stats.geometry_bytes += structures->bytes();
    timings.structures_ms = structures->build_ms();
  }
  stats.loop_budget = tree_loop_budget(gpu_scene.shape(), context.info, options.loop_budget);
  if (&host_scene != &scene) host_scene = scene;
  anchor = gpu_scene.anchor;
  scene_radius = gpu_scene.radius;
  counts = run_time_counts(gpu_scene, ray_mask);
  checked_count(gpu_scene.spheres.size(), "spheres");
  checked_count(gpu_scene.planes.size(), "planes");
  timings.bvh_build_ms = gpu_scene.bvh_build_ms;
  tree = gpu_scene.tree;
  keep_point_source(gpu_scene, false);
  // The tiles' bindings name the buffers replaced above: the next call binds anew.
  tile = TileOutputs{};
  parked_tile = TileOutputs{};
}

void Renderer::Impl::write_refitted(const GpuScene& gpu_scene) {
  // The items the refit rewrote (`per_item` array entries each), or all of them.
  auto write = [&]<typename T>(std::optional<TexelBuffer>& target, const std::vector<T>& items,
                                std::optional<GpuScene::ItemRange> range = std::nullopt, size_t per_item = 1) {
    const GpuScene::ItemRange whole{0, items.size() / per_item};
    const GpuScene::ItemRange written = range.value_or(whole);
    if (!target || written.empty()) return;
    const size_t item_bytes = per_item * sizeof(T);
    write_buffer(context, target->buffer, items.data() + written.first * per_item, (written.end - written.first) * item_bytes,
                 written.first * item_bytes);
  };
  const GpuScene::Rewritten& rewritten = gpu_scene.rewritten;
  write(primitives, gpu_scene.primitives, rewritten.slots);
  write(vertices, gpu_scene.vertices, rewritten.vertices);
  write(normals, gpu_scene.normal_texels, rewritten.slots, texels_per_normal(gpu_scene.precision));
  write(bvh_nodes, gpu_scene.bvh_nodes, rewritten.nodes);
  if (rewritten.instances) write(instances, gpu_scene.instance_texels);
  if (!rewritten.mesh_alone) write(spheres, gpu_scene.spheres);
  if (planes && !rewritten.mesh_alone) {  // their offsets from the anchor (the heights above the camera are set per render)
    gpu_planes = gpu_scene.planes;
    std::memcpy(planes->buffer.mapped, gpu_planes.data(), gpu_planes.size() * sizeof(gpu::GpuPlane));
  }
  anchor = gpu_scene.anchor;
  scene_radius = gpu_scene.radius;
  keep_point_source(gpu_scene, true);
}

void Renderer::Impl::make_placeholders() {
  placeholder = create_storage_buffer(context, texel_bytes);
  const std::array<uint32_t, 4> zero_texel{};
  placeholder_texels = make_texel_buffer(context, zero_texel.data(), texel_bytes);
  if (context.info.timestamp_period_ns > 0.0) {
    timestamps = vk::raii::QueryPool(context.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 3));
  }
}

void Renderer::Impl::check_workgroup() const {
  const ShaderVariant& shader = options.shader;
  const uint32_t group_size = shader.workgroup_width * shader.workgroup_height;
  if (group_size == 0 || group_size > context.limits.maxComputeWorkGroupInvocations ||
      shader.workgroup_width > context.limits.maxComputeWorkGroupSize[0] ||
      shader.workgroup_height > context.limits.maxComputeWorkGroupSize[1]) {
    throw GpuError(context.info.name + " has no " + std::to_string(shader.workgroup_width) + "x" +
                   std::to_string(shader.workgroup_height) + " compute workgroups");
  }
  const bool square_power_of_two = shader.workgroup_width == shader.workgroup_height && (group_size & (group_size - 1)) == 0;
  if (shader.morton_order && !(square_power_of_two && shader.workgroup_width <= 16)) {
    throw std::invalid_argument("Morton order needs a square power-of-two workgroup of at most 16x16");
  }
}

}  // namespace vkray
