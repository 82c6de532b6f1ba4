// A tree's GpuScene brought up to moved vertices in place (refit_in_place): the tree's shape kept,
// its boxes recomputed, only a moved mesh's part redone where nothing else can have changed.
#include "engine/render/gpu_scene_encoding.hpp"

#include "engine/parallel.hpp"

#include <atomic>

namespace vkray {
using namespace scene_encoding;

struct RefitState {
  std::vector<glm::dvec3> position;                  // each stored vertex, relative to the anchor
  std::vector<FloatBox> slot_box;                    // each slot's box
  std::vector<std::array<FloatBox, 2>> child_box;    // each node's children's boxes, before widening
  std::vector<uint32_t> parent;                      // each node's (the root's: no_node)
  std::vector<uint32_t> slot_node;                   // the node whose child is the slot's leaf
  std::vector<std::vector<uint32_t>> mesh_slots;     // the slots of each mesh's triangles
  std::vector<uint8_t> shares_vertices;              // by mesh: a stored vertex of it is another mesh's too
  static constexpr uint32_t no_node = UINT32_MAX;

  explicit RefitState(const GpuScene& gpu) : position(gpu.vertices.size()), slot_box(gpu.primitives.size()) {
    const Bvh& tree = *gpu.tree;
    child_box.resize(tree.nodes.size());
    parent.assign(tree.nodes.size(), no_node);
    slot_node.assign(gpu.primitives.size(), no_node);
    for (uint32_t node = 0; node < tree.nodes.size(); ++node) {
      for (const uint32_t child : tree.nodes[node]) {
        if (!is_leaf(child)) parent[child] = node;
        else for (uint32_t k = 0; k < leaf_count(child); ++k) slot_node[leaf_first(child) + k] = node;
      }
    }
    mesh_slots.resize(gpu.stored_vertex.size());
    for (uint32_t slot = 0; slot < gpu.hit_sources.slots.size(); ++slot) {
      const ObjectPrimitive source = gpu.hit_sources.slots[slot];
      if (source.object < mesh_slots.size()) mesh_slots[source.object].push_back(slot);
    }
    std::vector<uint32_t> owner(gpu.vertices.size(), no_node);
    shares_vertices.assign(gpu.stored_vertex.size(), 0);
    for (uint32_t mesh = 0; mesh < gpu.stored_vertex.size(); ++mesh) {
      for (const uint32_t stored : gpu.stored_vertex[mesh]) {
        if (stored == GpuScene::no_vertex) continue;
        if (owner[stored] != no_node && owner[stored] != mesh) shares_vertices[mesh] = shares_vertices[owner[stored]] = 1;
        owner[stored] = mesh;
      }
    }
  }
};

GpuScene::RefitStateHandle::RefitStateHandle() = default;
GpuScene::RefitStateHandle::RefitStateHandle(const RefitStateHandle&) {}
GpuScene::RefitStateHandle& GpuScene::RefitStateHandle::operator=(const RefitStateHandle&) {
  state.reset();
  return *this;
}
GpuScene::RefitStateHandle::RefitStateHandle(RefitStateHandle&&) noexcept = default;
GpuScene::RefitStateHandle& GpuScene::RefitStateHandle::operator=(RefitStateHandle&&) noexcept = default;
GpuScene::RefitStateHandle::~RefitStateHandle() = default;

bool refit_in_place(GpuScene& gpu, const Scene& scene, const ShaderVariant& shader, const SceneExtent& extent,
                    std::optional<uint32_t> moved_mesh) {
  if (!gpu.tree || gpu.stored_vertex.size() != scene.meshes.size()) return false;
  const SceneExtent anchored = anchored_extent(scene, shader, extent);
  // One mesh's part alone where nothing else can have changed: the anchor (every stored position is
  // relative to it) and the positions it shares with other meshes.
  std::unique_ptr<RefitState>& kept = gpu.refit_state.state;
  const bool one_mesh = moved_mesh && kept && anchored.anchor == gpu.anchor && !kept->shares_vertices[*moved_mesh];
  if (!kept) kept = std::make_unique<RefitState>(gpu);
  RefitState& state = *kept;
  gpu.anchor = anchored.anchor;
  gpu.radius = anchored.radius;
  gpu.rewritten = {};
  gpu.rewritten.mesh_alone = one_mesh;
  const auto updated = [&](size_t mesh) { return !one_mesh || mesh == *moved_mesh; };
  std::atomic<bool> fits = true;
  // The stored positions: every mesh vertex that shares one must still lie where the others do.
  std::vector<uint8_t> found(gpu.vertices.size(), 0);
  for (size_t m = 0; m < scene.meshes.size() && fits; ++m) {
    if (!updated(m)) continue;
    const std::vector<glm::dvec3>& positions = scene.meshes[m].positions;
    for (size_t k = 0; k < positions.size(); ++k) {
      const uint32_t stored = gpu.stored_vertex[m][k];
      if (stored == GpuScene::no_vertex) continue;
      const glm::dvec3 relative = positions[k] - gpu.anchor;
      if (!found[stored]) {
        found[stored] = 1, state.position[stored] = relative;
        const gpu::GpuPoint point = encode_point(glm::dvec4(relative, 0.0), gpu.precision);  // named first: see VertexTable::add
        gpu.vertices[stored] = point;
        gpu.rewritten.vertices.add(stored);
      } else if (state.position[stored] != relative) {
        fits = false;
      }
    }
  }
  for (const auto [mesh, triangle] : gpu.left_out) {
    if (fits && updated(mesh) && canonical_triangle(scene.meshes[mesh], triangle, gpu.anchor).normal != glm::dvec3(0.0)) {
      fits = false;
    }
  }
  if (!fits) return false;
  // Each slot's record, normal and box (of the moved mesh's slots alone, or of all); the spheres
  // where they are stored.
  std::vector<uint32_t> all_slots;
  if (!one_mesh) {
    all_slots.resize(gpu.primitives.size());
    for (uint32_t slot = 0; slot < all_slots.size(); ++slot) all_slots[slot] = slot;
  }
  const std::vector<uint32_t>& slots = one_mesh ? state.mesh_slots[*moved_mesh] : all_slots;
  const size_t texels = texels_per_normal(gpu.precision);
  parallel_for_chunks(slots.size(), [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end && fits; ++k) {
      const uint32_t slot = slots[k];
      const ObjectPrimitive source = gpu.hit_sources.slots[slot];
      gpu::GpuPrimitive& record = gpu.primitives[slot];
      if ((record.indices.w & VKRAY_PRIMITIVE_KIND_BITS) == VKRAY_PRIMITIVE_SPHERE) {
        const Sphere& sphere = scene.spheres[source.primitive];
        const glm::dvec3 centre = sphere.center - gpu.anchor;
        gpu.vertices[record.indices.x] = encode_point(glm::dvec4(centre, sphere.radius), gpu.precision);
        state.slot_box[slot] = sphere_box(centre, sphere.radius);
        continue;
      }
      // From the stored corners the record names, which the loop above placed: the mesh's triangle
      // and its vertices' indices are a cache miss each (they took a quarter of the refit).
      const CanonicalTriangle triangle = canonical_triangle({record.indices.x, record.indices.y, record.indices.z},
                                                            [&](uint32_t stored) { return state.position[stored]; });
      if (triangle.normal == glm::dvec3(0.0)) {
        fits = false;
        break;
      }
      record.indices = glm::uvec4(triangle.vertex[0], triangle.vertex[1], triangle.vertex[2],
                                  triangle.word(primitive_mask(record.indices.w)));
      write_normal(gpu.normal_texels.data() + slot * texels, triangle.normal, gpu.precision);
      state.slot_box[slot] = triangle.box();
    }
  });
  if (!fits) return false;
  if (one_mesh) {
    for (const uint32_t slot : slots) gpu.rewritten.slots.add(slot);
  } else {
    gpu.rewritten.vertices = {0, gpu.vertices.size()};  // the tree's spheres' too
    gpu.rewritten.slots = {0, gpu.primitives.size()};
    gpu.planes = encode_planes(scene, gpu.anchor, gpu.precision);
    for (size_t k = 0; k < gpu.spheres.size(); ++k) {  // tested apart
      gpu.spheres[k] = {encode_point(glm::dvec4(scene.spheres[k].center - gpu.anchor, scene.spheres[k].radius), gpu.precision)};
    }
  }
  // The nodes above the rewritten slots (all of them, or the paths from the moved mesh's leaves up).
  const Bvh& tree = *gpu.tree;
  std::vector<uint8_t> above(tree.nodes.size(), one_mesh ? 0 : 1);
  if (one_mesh) {
    for (const uint32_t slot : slots) {
      for (uint32_t node = state.slot_node[slot]; node != RefitState::no_node && !above[node]; node = state.parent[node]) {
        above[node] = 1;
      }
    }
  }
  update_child_bounds(tree, state.child_box, [&](uint32_t slot) { return state.slot_box[slot]; },
                      [&](size_t node) { return above[node] != 0; });
  for (size_t node = 0; node < tree.nodes.size(); ++node) {
    if (!above[node]) continue;
    gpu.bvh_nodes[node] = encode_node(state.child_box[node], tree.nodes[node]);
    gpu.rewritten.nodes.add(node);
  }
  gpu.refitted = true;
  return true;
}

}  // namespace vkray
