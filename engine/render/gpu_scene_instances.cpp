// A GpuScene's instances: each instanced mesh stored once in its own coordinates with its tree, the
// instances' texels, and the world's level over the instances' placed boxes (place_instances).
#include "engine/render/gpu_scene_encoding.hpp"

#include <glm/gtc/matrix_access.hpp>
#include <glm/matrix.hpp>

namespace vkray {
using namespace scene_encoding;

// What an instanced scene's world level is built from (GpuScene::instance_level).
struct InstanceLevel {
  std::vector<EncodedPrimitive> world;  // the world's own triangles and tree spheres
  std::vector<Bounds> mesh_box;         // by mesh: an instanced mesh's triangles' box, in its coordinates
  std::vector<uint32_t> root;           // by mesh: its tree's root node
  uint32_t deepest_mesh = 0;            // the deepest mesh tree's depth
  size_t world_slots = 0, world_nodes = 0;
  double world_radius = 0.0;  // the largest distance from the anchor of a sphere's surface or a world vertex
  BvhBuildOptions bvh;
};

namespace scene_encoding {

// Instanced mesh `mesh_index`'s triangles in its own coordinates (relative to its origin, not the
// anchor: a ray is taken there), their vertices stored once for all its instances; the instance's
// mask stands for theirs.
std::vector<EncodedPrimitive> encode_instanced_mesh(GpuScene& gpu, const Scene& scene, uint32_t mesh_index) {
  const Mesh& mesh = scene.meshes[mesh_index];
  VertexTable vertex_table(gpu.vertices, gpu.precision);
  std::vector<EncodedPrimitive> triangles;
  for (uint32_t triangle_index = 0; triangle_index < mesh.triangles.size(); ++triangle_index) {
    const CanonicalTriangle triangle = canonical_triangle(mesh, triangle_index, glm::dvec3(0.0));
    if (triangle.normal == glm::dvec3(0.0)) {
      gpu.left_out.push_back({mesh_index, triangle_index});
      continue;
    }
    std::array<uint32_t, 3> index;
    for (size_t c = 0; c < 3; ++c) index[c] = vertex_table.index(triangle.v[c]);
    const gpu::GpuPrimitive record{glm::uvec4(index[0], index[1], index[2], triangle.word(every_mask_bit))};
    triangles.push_back({record, triangle.normal, triangle.box(), {mesh_index, triangle_index}});
  }
  return triangles;
}

// What place_instances needs of every layout: the instanced meshes' boxes and the radius of the
// world's own primitives about the anchor.
std::shared_ptr<InstanceLevel> make_instance_level(const GpuScene& gpu, const Scene& scene,
                                                   const std::vector<std::vector<EncodedPrimitive>>& instanced_triangles) {
  auto level = std::make_shared<InstanceLevel>();
  level->mesh_box.resize(scene.meshes.size());
  level->root.assign(scene.meshes.size(), 0);
  for (uint32_t m = 0; m < scene.meshes.size(); ++m) {
    for (const auto& triangle : instanced_triangles[m]) {
      level->mesh_box[m].add(glm::dvec3(triangle.box.lower)), level->mesh_box[m].add(glm::dvec3(triangle.box.upper));
    }
  }
  for (const Sphere& sphere : scene.spheres) {
    level->world_radius = std::max(level->world_radius, glm::length(sphere.center - gpu.anchor) + sphere.radius);
  }
  for (const Mesh& mesh : scene.meshes) {
    if (mesh.instanced) continue;
    for (const glm::dvec3& p : mesh.positions) level->world_radius = std::max(level->world_radius, glm::length(p - gpu.anchor));
  }
  return level;
}

// An instanced scene: the world's slots and nodes first, as many as its tree over its own
// primitives and the instances can take (a binary tree of n leaf entries has at most n - 1 inner
// nodes), then each instanced mesh's triangles and tree (their leaves' slots and inner nodes offset
// to where they land), then the world's tree itself (place_instances).
void lay_out_instances(GpuScene& gpu, const Scene& scene, std::vector<EncodedPrimitive> world,
                       const std::vector<std::vector<EncodedPrimitive>>& instanced_triangles, const BvhBuildOptions& options) {
  const std::shared_ptr<InstanceLevel> level = make_instance_level(gpu, scene, instanced_triangles);
  level->world = std::move(world);
  level->bvh = options;
  size_t placing = 0;
  for (const Instance& instance : scene.instances) placing += level->mesh_box[instance.mesh].empty() ? 0 : 1;
  level->world_slots = level->world.size() + placing;
  level->world_nodes = std::max<size_t>(level->world_slots, 2) - 1;
  const size_t texels = texels_per_normal(gpu.precision);
  gpu.primitives.resize(level->world_slots);
  gpu.normal_texels.resize(level->world_slots * texels);
  gpu.hit_sources.slots.resize(level->world_slots);
  gpu.bvh_nodes.resize(level->world_nodes);
  for (uint32_t m = 0; m < scene.meshes.size(); ++m) {
    if (instanced_triangles[m].empty()) continue;
    std::vector<Box> boxes;
    for (const auto& triangle : instanced_triangles[m]) boxes.push_back({glm::dvec3(triangle.box.lower), glm::dvec3(triangle.box.upper)});
    const Bvh tree = build_bvh(boxes, options);
    const auto first_slot = static_cast<uint32_t>(gpu.primitives.size());
    const auto first_node = static_cast<uint32_t>(gpu.bvh_nodes.size());
    for (const uint32_t i : tree.primitive_order) {
      const EncodedPrimitive& triangle = instanced_triangles[m][i];
      gpu.primitives.push_back(triangle.primitive);
      append_normal(gpu.normal_texels, triangle.normal, gpu.precision);
      gpu.hit_sources.slots.push_back(triangle.source);
    }
    for (gpu::GpuBvhNode node : encode_nodes(tree, [&](uint32_t slot) { return instanced_triangles[m][tree.primitive_order[slot]].box; })) {
      for (int side = 0; side < 2; ++side) {
        const uint32_t child = node.children[side];
        node.children[side] = is_leaf(child) ? make_leaf(leaf_first(child) + first_slot, leaf_count(child)) : child + first_node;
      }
      gpu.bvh_nodes.push_back(node);
    }
    level->root[m] = first_node;
    level->deepest_mesh = std::max(level->deepest_mesh, tree.depth);
  }
  gpu.instance_level = std::move(level);
  place_instances(gpu, scene);
}

// Brute force with instances, after the world's triangles: a record for each instance whose mesh
// has triangles (its index, its mesh's first slot and slots, its mask), a zero-area record that ends
// the list (nearest_primitive_brute_force), then each instanced mesh's triangles in whole batches.
void lay_out_brute_force_instances(GpuScene& gpu, const Scene& scene,
                                   const std::vector<std::vector<EncodedPrimitive>>& instanced_triangles) {
  std::vector<uint32_t> first_slot(scene.meshes.size(), 0);
  size_t records = 0;
  for (const Instance& instance : scene.instances) records += instanced_triangles[instance.mesh].empty() ? 0 : 1;
  size_t next = gpu.primitives.size() + records + 1;
  for (uint32_t m = 0; m < scene.meshes.size(); ++m) {
    first_slot[m] = static_cast<uint32_t>(next);
    next += batched_slots(instanced_triangles[m].size());
  }
  uint64_t iterations = records + 1;
  auto add_slot = [&](const gpu::GpuPrimitive& record, const glm::dvec3& normal, ObjectPrimitive source) {
    gpu.primitives.push_back(record);
    append_normal(gpu.normal_texels, normal, gpu.precision);
    gpu.hit_sources.slots.push_back(source);
  };
  for (uint32_t k = 0; k < scene.instances.size(); ++k) {
    const Instance& instance = scene.instances[k];
    const uint32_t slots = batched_slots(instanced_triangles[instance.mesh].size());
    if (slots == 0) continue;
    add_slot({glm::uvec4(k, first_slot[instance.mesh], slots, primitive_word(VKRAY_PRIMITIVE_INSTANCE, instance.mask))},
             glm::dvec3(0.0), {});
    iterations += slots / VKRAY_TRIANGLE_BATCH;
  }
  add_slot(gpu::GpuPrimitive{}, glm::dvec3(0.0), {});
  for (uint32_t m = 0; m < scene.meshes.size(); ++m) {
    for (const EncodedPrimitive& triangle : instanced_triangles[m]) add_slot(triangle.primitive, triangle.normal, triangle.source);
    pad_slots(gpu, first_slot[m] + batched_slots(instanced_triangles[m].size()));
  }
  gpu.brute_force_placed_iterations = static_cast<uint32_t>(std::min<uint64_t>(iterations, UINT32_MAX));
  gpu.instance_level = make_instance_level(gpu, scene, instanced_triangles);
  place_instances(gpu, scene);
}

}  // namespace scene_encoding

namespace {

// Each instance's map into its mesh's coordinates (VKRAY_TEXELS_PER_INSTANCE_*; fetch_placement).
void write_instance_texels(GpuScene& gpu, const Scene& scene) {
  gpu.instance_texels.clear();
  for (const Instance& instance : scene.instances) {
    const glm::dmat3 to_mesh = glm::inverse(instance.linear);
    const glm::dvec3 translation = instance.translation - gpu.anchor;
    if (gpu.precision == Precision::float64) {
      for (int row = 0; row < 3; ++row) {
        const gpu::GpuPoint point = encode_point(glm::dvec4(glm::row(to_mesh, row), translation[row]), gpu.precision);
        gpu.instance_texels.push_back(point.first);
        gpu.instance_texels.push_back(point.second);
      }
      continue;
    }
    const gpu::GpuPoint split = encode_point(glm::dvec4(translation, 0.0), gpu.precision);
    for (int row = 0; row < 3; ++row) gpu.instance_texels.push_back(glm::vec4(glm::vec3(glm::row(to_mesh, row)), split.first[row]));
    gpu.instance_texels.push_back(split.second);
  }
}

}  // namespace

std::span<const uint32_t> instanced_mesh_roots(const GpuScene& gpu) {
  if (!gpu.instance_level) return {};
  return gpu.instance_level->root;
}

void place_instances(GpuScene& gpu, const Scene& scene) {
  const InstanceLevel& level = *gpu.instance_level;
  const bool first_placing = gpu.instance_texels.empty();
  // Each instance a primitive of the world's tree, boxed where it places its mesh; the radius about
  // the anchor (GpuScene::radius) grown to the placed boxes' corners.
  std::vector<EncodedPrimitive> entries = level.world;
  gpu.radius = level.world_radius;
  for (uint32_t k = 0; k < scene.instances.size(); ++k) {
    const Instance& instance = scene.instances[k];
    const Bounds& mesh_box = level.mesh_box[instance.mesh];
    if (mesh_box.empty()) continue;
    const Bounds placed = placed_box(mesh_box, instance);
    for (int corner = 0; corner < 8; ++corner) gpu.radius = std::max(gpu.radius, glm::length(placed.corner(corner) - gpu.anchor));
    const gpu::GpuPrimitive record{glm::uvec4(k, level.root[instance.mesh], 0, primitive_word(VKRAY_PRIMITIVE_INSTANCE, instance.mask))};
    entries.push_back({record, glm::dvec3(0.0), outward(placed.lower - gpu.anchor, placed.upper - gpu.anchor), {}});
  }
  write_instance_texels(gpu, scene);
  gpu.rewritten = {};
  gpu.rewritten.mesh_alone = true;
  gpu.rewritten.instances = true;
  // Brute force tests each instance where its record points; for ray queries the device's top-level
  // structure places the meshes (Renderer::set_transforms). Neither has a world's tree to build.
  if (gpu.search == PrimitiveSearch::brute_force || gpu.search == PrimitiveSearch::ray_query) return;
  std::vector<Box> boxes;
  boxes.reserve(entries.size());
  for (const auto& entry : entries) boxes.push_back({glm::dvec3(entry.box.lower), glm::dvec3(entry.box.upper)});
  Bvh bvh = build_bvh(boxes, level.bvh);
  // Each leaf's instances after its own primitives: the packet walk tests a leaf's primitives
  // together, then enters its instances one by one, what is left of the leaf waiting on its stack
  // as a leaf of instances alone (nearest_primitives_packet).
  const auto is_instance = [&](uint32_t entry) { return entry >= level.world.size(); };
  for (const auto& node : bvh.nodes) {
    for (const uint32_t child : node) {
      if (!is_leaf(child)) continue;
      const auto first = bvh.primitive_order.begin() + leaf_first(child);
      std::stable_partition(first, first + leaf_count(child), [&](uint32_t entry) { return !is_instance(entry); });
    }
  }
  const size_t texels = texels_per_normal(gpu.precision);
  for (size_t slot = 0; slot < entries.size(); ++slot) {
    const EncodedPrimitive& entry = entries[bvh.primitive_order[slot]];
    gpu.primitives[slot] = entry.primitive;
    write_normal(gpu.normal_texels.data() + slot * texels, entry.normal, gpu.precision);
    gpu.hit_sources.slots[slot] = entry.source;
  }
  const std::vector<gpu::GpuBvhNode> nodes = encode_nodes(bvh, [&](uint32_t slot) { return entries[bvh.primitive_order[slot]].box; });
  std::copy(nodes.begin(), nodes.end(), gpu.bvh_nodes.begin());
  std::fill(gpu.bvh_nodes.begin() + static_cast<std::ptrdiff_t>(nodes.size()),
            gpu.bvh_nodes.begin() + static_cast<std::ptrdiff_t>(level.world_nodes), gpu::GpuBvhNode{});
  // The walk's stack: the world's depth, three entries for an instance entered, the deepest mesh's
  // (see nearest_primitive_in_tree; the packet walk's takes two). Never lowered from one call to the
  // next, and for the per-ray walk four more than the first tree needs: a deeper stack specializes
  // its pipeline anew (on lavapipe ~170 ms). The packet walk's stack is always
  // VKRAY_STACK_REGISTERS_MAX, which the tree itself must fit (Renderer::set_transforms).
  const uint32_t stack = bvh.depth + 3 + level.deepest_mesh;
  gpu.bvh_depth = std::max(gpu.bvh_depth, first_placing && gpu.search != PrimitiveSearch::bvh_packet ? stack + 4 : stack);
  gpu.rewritten.slots = {0, level.world_slots};
  gpu.rewritten.nodes = {0, level.world_nodes};
}

}  // namespace vkray
