#include "engine/render/gpu_scene.hpp"

#include "engine/parallel.hpp"
#include "engine/stopwatch.hpp"
#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_access.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>
#include <unordered_map>

namespace vkray {
namespace {

glm::vec4 to_float4(const glm::dvec3& v, double w = 0.0) { return glm::vec4(glm::dvec4(v, w)); }

// GpuPrimitive's w: the primitive's kind, its mask above it.
uint32_t primitive_word(uint32_t kind, Mask mask) { return kind | uint32_t{mask} << VKRAY_PRIMITIVE_MASK_SHIFT; }

// `value` (relative to the anchor) as the shader of `precision` reads it: see GpuPoint.
gpu::GpuPoint encode_point(const glm::dvec4& value, Precision precision) {
  gpu::GpuPoint point;
  if (precision == Precision::float64) {
    static_assert(sizeof(point) == sizeof(value));
    std::memcpy(&point, &value, sizeof(point));
    return point;
  }
  point.first = glm::vec4(value);
  point.second = glm::vec4(value - glm::dvec4(point.first));  // exact in double, then rounded
  return point;
}

struct FloatBox {
  glm::vec3 lower;
  glm::vec3 upper;
};

// At least one float step and VKRAY_BOX_MARGIN outward (see safe_inverse in shaders/intersect.glsl).
float step_down(float value) {
  return float_below(std::min<double>(next_float_down(value), double{value} - VKRAY_BOX_MARGIN));
}
float step_up(float value) {
  return float_above(std::max<double>(next_float_up(value), double{value} + VKRAY_BOX_MARGIN));
}
FloatBox widened(const FloatBox& box) {
  return {{step_down(box.lower.x), step_down(box.lower.y), step_down(box.lower.z)},
          {step_up(box.upper.x), step_up(box.upper.y), step_up(box.upper.z)}};
}

FloatBox outward(const glm::dvec3& lower, const glm::dvec3& upper) {
  return {{float_below(lower.x), float_below(lower.y), float_below(lower.z)},
          {float_above(upper.x), float_above(upper.y), float_above(upper.z)}};
}

// A triangle or sphere as its record (indices into the vertex buffer) and its normal, with its
// float box rounded outward from the exact (double) primitive: it holds both the double and the
// float32 hi/lo primitive up to the one-step widening of every node box (widened).
struct EncodedPrimitive {
  gpu::GpuPrimitive primitive;
  glm::dvec3 normal;  // triangles' unit normal; 0 for spheres
  FloatBox box;
  ObjectPrimitive source;
};

// A triangle relative to the anchor, its corners in a canonical order (lexicographic): the shader's
// normal faces the ray whatever the winding, and the watertight test accepts either orientation,
// so the order is free, and fixing it makes copies of a triangle with another winding or starting
// vertex give bit-identical distances: coincident copies tie exactly (see VKRAY_COINCIDENT_GAP).
struct CanonicalTriangle {
  std::array<glm::dvec3, 3> v;   // the corners relative to the anchor, in canonical order
  std::array<uint32_t, 3> vertex;  // each one's index as given (in the mesh, or in the vertex buffer)
  glm::dvec3 normal{0.0};          // the unit normal; 0 for a triangle of zero area (left out)
  FloatBox box() const { return outward(glm::min(v[0], glm::min(v[1], v[2])), glm::max(v[0], glm::max(v[1], v[2]))); }
};

// The triangle of corners `vertex`, each at position(index) relative to the anchor.
template <typename Position>
CanonicalTriangle canonical_triangle(const std::array<uint32_t, 3>& vertex, Position position) {
  CanonicalTriangle result;
  result.vertex = vertex;
  for (size_t c = 0; c < 3; ++c) result.v[c] = position(vertex[c]);
  // Three compare-and-swaps (a refit makes every triangle again: std::sort of pairs took a tenth of it).
  const auto order = [&](size_t a, size_t b) {
    if (std::tie(result.v[b].x, result.v[b].y, result.v[b].z) < std::tie(result.v[a].x, result.v[a].y, result.v[a].z)) {
      std::swap(result.v[a], result.v[b]);
      std::swap(result.vertex[a], result.vertex[b]);
    }
  };
  order(0, 1), order(1, 2), order(0, 1);
  const glm::dvec3 cross = glm::cross(result.v[1] - result.v[0], result.v[2] - result.v[0]);
  if (cross != glm::dvec3(0.0)) result.normal = unit_vector(cross);
  return result;
}

CanonicalTriangle canonical_triangle(const Mesh& mesh, uint32_t triangle, const glm::dvec3& anchor) {
  return canonical_triangle(mesh.triangles[triangle], [&](uint32_t k) { return mesh.positions[k] - anchor; });
}

// A sphere's box relative to the anchor.
FloatBox sphere_box(const glm::dvec3& centre, double radius) { return outward(centre - radius, centre + radius); }

// The vertex buffer: each distinct position (relative to the anchor, exact in double) once.
class VertexTable {
 public:
  VertexTable(std::vector<gpu::GpuPoint>& vertices, Precision precision) : vertices_(vertices), precision_(precision) {}

  uint32_t index(const glm::dvec3& position) {
    const auto [entry, inserted] = indices_.try_emplace(position, static_cast<uint32_t>(vertices_.size()));
    if (inserted) add(position, 0.0);
    return entry->second;
  }
  // A point of its own (a sphere's centre and radius in w).
  uint32_t add(const glm::dvec3& position, double w) {
    // Encoded into a named value first: pushing encode_point's result straight into the vector, GCC
    // 12 at -O3 stored zeros for the lo parts' x and y whenever the push reallocated
    // (RandomScenes.EightDecadesInOneSceneWithinTheEnvelope caught it).
    const gpu::GpuPoint point = encode_point(glm::dvec4(position, w), precision_);
    vertices_.push_back(point);
    return static_cast<uint32_t>(vertices_.size() - 1);
  }

 private:
  struct BitHash {
    size_t operator()(const glm::dvec3& p) const {
      const auto bits = [](double v) { return std::bit_cast<uint64_t>(v == 0.0 ? 0.0 : v); };  // -0 as +0
      return std::hash<uint64_t>()(bits(p.x) ^ (bits(p.y) * 0x9e3779b97f4a7c15ull) ^ (bits(p.z) * 0xc2b2ae3d27d4eb4full));
    }
  };
  std::vector<gpu::GpuPoint>& vertices_;
  Precision precision_;
  std::unordered_map<glm::dvec3, uint32_t, BitHash> indices_;
};

// A slot's normal written at `at` (texels_per_normal texels).
void write_normal(glm::vec4* at, const glm::dvec3& normal, Precision precision) {
  if (precision == Precision::float64) {
    const gpu::GpuPoint point = encode_point(glm::dvec4(normal, 0.0), precision);
    at[0] = point.first, at[1] = point.second;
  } else {
    at[0] = glm::vec4(glm::dvec4(normal, 0.0));
  }
}
void append_normal(std::vector<glm::vec4>& texels, const glm::dvec3& normal, Precision precision) {
  texels.resize(texels.size() + texels_per_normal(precision));
  write_normal(texels.data() + texels.size() - texels_per_normal(precision), normal, precision);
}

// A tree node as the shader reads it: its two children's boxes, widened (see safe_inverse in
// shaders/intersect.glsl), and their references.
gpu::GpuBvhNode encode_node(const std::array<FloatBox, 2>& children, const std::array<uint32_t, 2>& references) {
  const FloatBox first = widened(children[0]);
  const FloatBox second = widened(children[1]);
  return {
      glm::vec4(first.lower.x, second.lower.x, first.upper.x, second.upper.x),
      glm::vec4(first.lower.y, second.lower.y, first.upper.y, second.upper.y),
      glm::vec4(first.lower.z, second.lower.z, first.upper.z, second.upper.z),
      glm::uvec4(references[0], references[1], 0, 0),
  };
}

// The tree's nodes, from their slots' boxes.
template <typename SlotBox>
std::vector<gpu::GpuBvhNode> encode_nodes(const Bvh& bvh, SlotBox slot_box) {
  const auto bounds = child_bounds<FloatBox>(bvh, slot_box);
  std::vector<gpu::GpuBvhNode> nodes(bvh.nodes.size());
  for (size_t n = 0; n < bvh.nodes.size(); ++n) nodes[n] = encode_node(bounds[n], bvh.nodes[n]);
  return nodes;
}

// The planes (GpuPlane): their offsets from the anchor, and their heights above the scene's camera.
std::vector<gpu::GpuPlane> encode_planes(const Scene& scene, const glm::dvec3& anchor, Precision precision) {
  std::vector<gpu::GpuPlane> planes;
  for (const auto& plane : scene.planes) {
    planes.push_back({{}, encode_point(glm::dvec4(plane.normal, glm::dot(plane.normal, plane.point - anchor)), precision)});
  }
  set_plane_heights(planes, scene.planes, scene.camera.from, precision);
  return planes;
}

// Where a shader's positions are stored from (GpuScene::anchor), and the radius about it.
SceneExtent anchored_extent(const Scene& scene, const ShaderVariant& shader, const SceneExtent& extent) {
  const bool world_origin = shader.precision == Precision::float64 || shader.coordinates == VKRAY_COORDINATES_ABSOLUTE;
  return world_origin ? SceneExtent{glm::dvec3(0.0), scene_radius(scene, glm::dvec3(0.0))} : extent;
}

// Triangle slots of the brute-force loop: whole batches.
uint32_t batched_slots(size_t triangle_count) {
  return static_cast<uint32_t>((triangle_count + VKRAY_TRIANGLE_BATCH - 1) / VKRAY_TRIANGLE_BATCH * VKRAY_TRIANGLE_BATCH);
}

// Slots of zero-area records (no ray meets them) up to `slots`.
void pad_slots(GpuScene& gpu, size_t slots) {
  while (gpu.primitives.size() < slots) {
    gpu.primitives.push_back(gpu::GpuPrimitive{});
    append_normal(gpu.normal_texels, glm::dvec3(0.0), gpu.precision);
    gpu.hit_sources.slots.push_back({});
  }
}

// The order of `centres` along a Morton curve (21 bits an axis over their box).
std::vector<size_t> morton_order(const std::vector<glm::dvec3>& centres) {
  auto spread = [](uint64_t v) {  // 21 bits to every third of 63
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    return (v | v << 2) & 0x1249249249249249ull;
  };
  Bounds bounds;
  for (const auto& centre : centres) bounds.add(centre);
  const glm::dvec3 extent = glm::max(bounds.upper - bounds.lower, glm::dvec3(1e-300));
  auto cell = [](double u) { return static_cast<uint64_t>(std::clamp(u, 0.0, 1.0) * 2097151.0); };
  std::vector<std::pair<uint64_t, size_t>> codes;
  for (size_t k = 0; k < centres.size(); ++k) {
    const glm::dvec3 unit = (centres[k] - bounds.lower) / extent;
    codes.push_back({spread(cell(unit.x)) | spread(cell(unit.y)) << 1 | spread(cell(unit.z)) << 2, k});
  }
  std::stable_sort(codes.begin(), codes.end());
  std::vector<size_t> order;
  for (const auto& [code, k] : codes) order.push_back(k);
  return order;
}

// The slots for ray queries (GpuScene::structure_meshes): the triangles by mesh (an instanced
// mesh's in its own coordinates), each mesh's in Morton order of their boxes' centres; then the
// spheres not tested apart, in Morton order too, with their boxes. lavapipe builds a structure by
// halving its input in order: ordered input makes it a Morton-code tree (the bunny at 1920x1080:
// 0.30 s a frame, 40 s in the OBJ's order).
void lay_out_for_ray_queries(GpuScene& gpu, const Scene& scene, std::vector<EncodedPrimitive> triangles,
                             VertexTable& vertex_table) {
  auto centre = [](const FloatBox& box) { return 0.5 * (glm::dvec3(box.lower) + glm::dvec3(box.upper)); };
  for (size_t begin = 0; begin < triangles.size();) {
    size_t end = begin;
    while (end < triangles.size() && triangles[end].source.object == triangles[begin].source.object) ++end;
    std::vector<glm::dvec3> centres;
    for (size_t k = begin; k < end; ++k) centres.push_back(centre(triangles[k].box));
    const uint32_t mesh = triangles[begin].source.object;
    gpu.structure_meshes.push_back({static_cast<uint32_t>(gpu.primitives.size()), static_cast<uint32_t>(end - begin), mesh,
                                    scene.meshes[mesh].instanced});
    for (size_t k : morton_order(centres)) {
      const EncodedPrimitive& triangle = triangles[begin + k];
      gpu.primitives.push_back(triangle.primitive);
      append_normal(gpu.normal_texels, triangle.normal, gpu.precision);
      gpu.hit_sources.slots.push_back(triangle.source);
    }
    begin = end;
  }
  if (!gpu.tree_has_spheres) {
    for (const auto& sphere : scene.spheres) {
      gpu.spheres.push_back({encode_point(glm::dvec4(sphere.center - gpu.anchor, sphere.radius), gpu.precision)});
    }
    return;
  }
  std::vector<glm::dvec3> centres;
  for (const auto& sphere : scene.spheres) centres.push_back(sphere.center);
  gpu.structure_spheres.first = static_cast<uint32_t>(gpu.primitives.size());
  for (size_t k : morton_order(centres)) {
    const Sphere& sphere = scene.spheres[k];
    const glm::dvec3 centre_offset = sphere.center - gpu.anchor;
    gpu.primitives.push_back(gpu::GpuPrimitive{
        glm::uvec4(vertex_table.add(centre_offset, sphere.radius), 0, 0, primitive_word(VKRAY_PRIMITIVE_SPHERE, sphere.mask))});
    append_normal(gpu.normal_texels, glm::dvec3(0.0), gpu.precision);
    gpu.hit_sources.slots.push_back({gpu.hit_sources.first_sphere_object + static_cast<uint32_t>(k), static_cast<uint32_t>(k)});
    const FloatBox box = widened(sphere_box(centre_offset, sphere.radius));
    gpu.sphere_boxes.push_back({box.lower.x, box.lower.y, box.lower.z, box.upper.x, box.upper.y, box.upper.z});
  }
  gpu.structure_spheres.count = static_cast<uint32_t>(gpu.sphere_boxes.size());
}

// What the scene's counts decide (GpuSceneShape), for plan_gpu_scene before anything is built and
// for make_gpu_scene with the triangles it keeps: one set of decisions, so the two agree.
// With instances, `triangles` counts the world's own and the instanced meshes' once each.
GpuSceneShape shape_for_counts(size_t triangles, size_t spheres, size_t planes, size_t instances, bool masks,
                               const GpuSceneOptions& options) {
  GpuSceneShape shape;
  shape.planes = static_cast<uint32_t>(planes);
  shape.masks = masks;
  // (Instances of meshes without a triangle of non-zero area place nothing.)
  shape.instances = instances > 0 && triangles > 0;
  if (shape.instances) {
    // Instances are walked into per ray, in packets (nearest_primitive_in_tree,
    // nearest_primitives_packet) and by the device's ray queries (its own instances:
    // acceleration_structures.hpp). Per ray unless asked: a packet enters an instance whole
    // wherever one of its rays does. On lavapipe at 1920x1080, a thousand instances of five models,
    // each a few dozen pixels across, took 475 ms a frame per ray against 920 in packets; five of
    // them filling the frame 835 against 208 (`vkray bench SCENE --variants per-ray,packet`).
    const PrimitiveSearch requested = options.search;
    shape.search = requested == PrimitiveSearch::automatic ? PrimitiveSearch::bvh_per_ray : requested;
    if (shape.search == PrimitiveSearch::brute_force) {  // each instance's mesh tested whole (make_gpu_scene)
      shape.spheres_apart = static_cast<uint32_t>(spheres);
      return shape;
    }
    shape.spheres_apart = keeps_spheres_apart(triangles, spheres) ? static_cast<uint32_t>(spheres) : 0;
    shape.tree_has_triangles = true;
    shape.tree_has_spheres = spheres > 0 && shape.spheres_apart == 0;
    return shape;
  }
  shape.search = options.search == PrimitiveSearch::automatic ? choose_search(triangles, spheres, options.packet_walk)
                                                              : options.search;
  if (triangles == 0 && spheres == 0) shape.search = PrimitiveSearch::brute_force;
  if (shape.search == PrimitiveSearch::brute_force) {
    shape.spheres_apart = static_cast<uint32_t>(spheres);
    shape.brute_force_triangle_slots = batched_slots(triangles);
    return shape;
  }
  // The packet walk where it will run, taking the tree shallow enough for it: make_gpu_scene walks
  // a deeper one per ray.
  if (options.search == PrimitiveSearch::automatic && options.packet_walk) shape.search = PrimitiveSearch::bvh_packet;
  const bool apart = keeps_spheres_apart(triangles, spheres);
  shape.spheres_apart = apart ? static_cast<uint32_t>(spheres) : 0;
  shape.tree_has_triangles = triangles > 0;
  shape.tree_has_spheres = spheres > 0 && !apart;
  return shape;
}

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
    const gpu::GpuPrimitive record{glm::uvec4(index[0], index[1], index[2], primitive_word(VKRAY_PRIMITIVE_TRIANGLE, every_mask_bit))};
    triangles.push_back({record, triangle.normal, triangle.box(), {mesh_index, triangle_index}});
  }
  return triangles;
}

}  // namespace

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

namespace {

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

}  // namespace

GpuSceneShape plan_gpu_scene(const Scene& scene, const GpuSceneOptions& options) {
  return shape_for_counts(scene.drawn_triangle_count(), scene.spheres.size(), scene.planes.size(), scene.instances.size(),
                          scene.has_masks(), options);
}

GpuScene make_gpu_scene(const Scene& scene, const GpuSceneOptions& options, const ShaderVariant& shader,
                        const std::optional<SceneExtent>& extent, const std::optional<RefitSource>& refit) {
  GpuScene gpu;
  gpu.precision = shader.precision;
  const SceneExtent anchored = anchored_extent(scene, shader, extent ? *extent : scene_extent(scene));
  gpu.anchor = anchored.anchor;
  gpu.hit_sources.first_sphere_object = static_cast<uint32_t>(scene.meshes.size());
  gpu.hit_sources.first_plane_object = static_cast<uint32_t>(scene.meshes.size() + scene.spheres.size());
  auto encode = [&](const glm::dvec3& position, double w) { return encode_point(glm::dvec4(position, w), gpu.precision); };
  gpu.radius = anchored.radius;
  gpu.planes = encode_planes(scene, gpu.anchor, gpu.precision);

  // Triangles relative to the anchor; each vertex position is stored once and indexed by every
  // triangle that shares it, so they see bit-identical values: the watertight test needs that.
  VertexTable vertex_table(gpu.vertices, gpu.precision);
  std::vector<EncodedPrimitive> triangles;
  gpu.stored_vertex.resize(scene.meshes.size());
  // An instanced mesh's triangles in its own coordinates (encode_instances), the others' here.
  std::vector<std::vector<EncodedPrimitive>> instanced_triangles(scene.meshes.size());
  std::vector<uint8_t> placed(scene.meshes.size(), 0);
  for (const Instance& instance : scene.instances) placed[instance.mesh] = 1;
  for (uint32_t mesh_index = 0; mesh_index < scene.meshes.size(); ++mesh_index) {
    const Mesh& mesh = scene.meshes[mesh_index];
    std::vector<uint32_t>& stored = gpu.stored_vertex[mesh_index];
    stored.assign(mesh.positions.size(), GpuScene::no_vertex);
    if (mesh.instanced) {  // (one no instance places is drawn nowhere: nothing to store)
      if (placed[mesh_index]) instanced_triangles[mesh_index] = encode_instanced_mesh(gpu, scene, mesh_index);
      continue;
    }
    for (uint32_t triangle_index = 0; triangle_index < mesh.triangles.size(); ++triangle_index) {
      const CanonicalTriangle triangle = canonical_triangle(mesh, triangle_index, gpu.anchor);
      if (triangle.normal == glm::dvec3(0.0)) {
        gpu.left_out.push_back({mesh_index, triangle_index});
        continue;
      }
      std::array<uint32_t, 3> index;
      for (size_t c = 0; c < 3; ++c) stored[triangle.vertex[c]] = index[c] = vertex_table.index(triangle.v[c]);
      const gpu::GpuPrimitive record{glm::uvec4(index[0], index[1], index[2], primitive_word(VKRAY_PRIMITIVE_TRIANGLE, mesh.mask))};
      triangles.push_back({record, triangle.normal, triangle.box(), {mesh_index, triangle_index}});
    }
  }
  size_t instanced_count = 0;
  for (const auto& mesh_triangles : instanced_triangles) instanced_count += mesh_triangles.size();
  gpu.triangle_count = static_cast<uint32_t>(triangles.size() + instanced_count);
  // Slots stay below the bits a list of first hits tags its entries with (VKRAY_HIT_FAR_ROOT).
  const size_t slot_count = gpu.triangle_count + scene.spheres.size() + scene.instances.size();
  if (slot_count >= VKRAY_HIT_FAR_ROOT) {
    throw InputError("the scene has " + std::to_string(slot_count) +
                     " triangles, spheres and instances; vkray numbers fewer than " + std::to_string(VKRAY_HIT_FAR_ROOT));
  }
  const GpuSceneShape shape = shape_for_counts(gpu.triangle_count, scene.spheres.size(), scene.planes.size(),
                                               scene.instances.size(), scene.has_masks(), options);
  gpu.search = shape.search;
  gpu.tree_has_triangles = shape.tree_has_triangles;
  gpu.tree_has_spheres = shape.tree_has_spheres;
  gpu.masks = shape.masks;
  if (gpu.masks) {
    for (uint32_t k = 0; k < shape.spheres_apart; ++k) gpu.apart_masks.emplace_back(scene.spheres[k].mask, 0, 0, 0);
    for (const Plane& plane : scene.planes) gpu.apart_masks.emplace_back(plane.mask, 0, 0, 0);
  }

  if (gpu.search == PrimitiveSearch::brute_force) {
    for (const auto& sphere : scene.spheres) gpu.spheres.push_back({encode(sphere.center - gpu.anchor, sphere.radius)});
    for (const auto& triangle : triangles) {
      gpu.primitives.push_back(triangle.primitive);
      append_normal(gpu.normal_texels, triangle.normal, gpu.precision);
      gpu.hit_sources.slots.push_back(triangle.source);
    }
    pad_slots(gpu, batched_slots(triangles.size()));
    gpu.world_triangle_slots = static_cast<uint32_t>(gpu.primitives.size());
    if (shape.instances) lay_out_brute_force_instances(gpu, scene, instanced_triangles);
    return gpu;
  }

  if (gpu.search == PrimitiveSearch::ray_query) {
    for (const auto& mesh_triangles : instanced_triangles) triangles.insert(triangles.end(), mesh_triangles.begin(), mesh_triangles.end());
    lay_out_for_ray_queries(gpu, scene, std::move(triangles), vertex_table);
    if (shape.instances) {
      gpu.instance_level = make_instance_level(gpu, scene, instanced_triangles);
      place_instances(gpu, scene);
    }
    return gpu;
  }

  const auto start = Clock::now();
  std::vector<EncodedPrimitive> unordered = std::move(triangles);
  const bool spheres_apart = !shape.tree_has_spheres;
  for (uint32_t k = 0; k < (spheres_apart ? 0 : scene.spheres.size()); ++k) {
    const Sphere& sphere = scene.spheres[k];
    const glm::dvec3 centre = sphere.center - gpu.anchor;
    const gpu::GpuPrimitive record{glm::uvec4(vertex_table.add(centre, sphere.radius), 0, 0, primitive_word(VKRAY_PRIMITIVE_SPHERE, sphere.mask))};
    unordered.push_back({record, glm::dvec3(0.0), sphere_box(centre, sphere.radius), {gpu.hit_sources.first_sphere_object + k, k}});
  }
  if (spheres_apart) {
    for (const auto& sphere : scene.spheres) gpu.spheres.push_back({encode(sphere.center - gpu.anchor, sphere.radius)});
  }
  if (shape.instances) {
    lay_out_instances(gpu, scene, std::move(unordered), instanced_triangles, options.bvh);
    gpu.bvh_build_ms = elapsed_ms(start);
    return gpu;
  }
  std::vector<Box> boxes;
  boxes.reserve(unordered.size());
  for (const auto& primitive : unordered) boxes.push_back({glm::dvec3(primitive.box.lower), glm::dvec3(primitive.box.upper)});
  // A refit keeps the tree's shape where each leaf slot still holds the primitive it held: the same
  // triangles kept (none became or stopped being of zero area) and spheres, in the same order.
  const auto same_primitives = [&] {
    const std::vector<uint32_t>& order = refit->tree.primitive_order;
    if (order.size() != unordered.size() || refit->slots.slots.size() != order.size()) return false;
    for (size_t slot = 0; slot < order.size(); ++slot) {
      if (refit->slots.slots[slot] != unordered[order[slot]].source) return false;
    }
    return true;
  };
  gpu.refitted = refit && same_primitives();
  const Bvh bvh = gpu.refitted ? refit->tree : build_bvh(boxes, options.bvh);
  gpu.primitives.reserve(unordered.size() + VKRAY_BVH_MAX_LEAF_SIZE);
  for (uint32_t i : bvh.primitive_order) {
    gpu.primitives.push_back(unordered[i].primitive);
    append_normal(gpu.normal_texels, unordered[i].normal, gpu.precision);
    gpu.hit_sources.slots.push_back(unordered[i].source);
  }
  gpu.bvh_nodes = encode_nodes(bvh, [&](uint32_t slot) { return unordered[bvh.primitive_order[slot]].box; });
  gpu.bvh_depth = bvh.depth;
  gpu.tree = bvh;
  if (options.search == PrimitiveSearch::automatic && gpu.search == PrimitiveSearch::bvh_packet &&
      !packet_walk_fits(bvh.depth)) {
    gpu.search = PrimitiveSearch::bvh_per_ray;
  }
  gpu.bvh_build_ms = elapsed_ms(start);
  return gpu;
}

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

GpuScene::RefitStateHandle::RefitStateHandle() = default;
GpuScene::RefitStateHandle::RefitStateHandle(const RefitStateHandle&) {}
GpuScene::RefitStateHandle& GpuScene::RefitStateHandle::operator=(const RefitStateHandle&) {
  state.reset();
  return *this;
}
GpuScene::RefitStateHandle::RefitStateHandle(RefitStateHandle&&) noexcept = default;
GpuScene::RefitStateHandle& GpuScene::RefitStateHandle::operator=(RefitStateHandle&&) noexcept = default;
GpuScene::RefitStateHandle::~RefitStateHandle() = default;

size_t texels_per_normal(Precision precision) {
  return precision == Precision::float64 ? VKRAY_TEXELS_PER_NORMAL_FLOAT64 : VKRAY_TEXELS_PER_NORMAL_FLOAT32;
}

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
      record.indices = glm::uvec4(triangle.vertex[0], triangle.vertex[1], triangle.vertex[2], record.indices.w);
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

ObjectPrimitive HitSources::operator()(uint32_t hit) const {
  if (hit == VKRAY_HIT_NONE) return {};
  const uint32_t index = hit & VKRAY_HIT_INDEX_MASK;
  if (hit & VKRAY_HIT_PLANE) return {first_plane_object + index, index};
  if (hit & VKRAY_HIT_SPHERE_APART) return {first_sphere_object + index, index};
  return slots[index];
}

gpu::GpuRay encode_ray(const glm::dvec3& origin, const glm::dvec3& direction, double range_end,
                       const glm::dvec3& anchor, Precision precision) {
  gpu::GpuRay ray{encode_point(glm::dvec4(origin - anchor, 0.0), precision),
                  encode_point(glm::dvec4(unit_vector(direction), range_end), precision)};
  if (precision == Precision::float32) ray.direction.second.w = 0.0f;  // unread; inf - inf would leave NaN there
  return ray;
}

GpuSceneShape GpuScene::shape() const {
  return {search,
          static_cast<uint32_t>(spheres.size()),
          static_cast<uint32_t>(planes.size()),
          brute_force_triangle_slots(),
          brute_force_placed_iterations,
          tree_has_triangles,
          tree_has_spheres,
          masks,
          !instance_texels.empty()};
}

void set_plane_heights(std::vector<gpu::GpuPlane>& planes, const std::vector<Plane>& scene_planes,
                       const glm::dvec3& origin, Precision precision) {
  for (size_t k = 0; k < planes.size(); ++k) {
    const Plane& plane = scene_planes[k];
    planes[k].normal_height = encode_point(glm::dvec4(plane.normal, glm::dot(plane.normal, plane.point - origin)), precision);
  }
}

glm::uvec4 run_time_counts(const GpuScene& scene, Mask ray_mask) {
  return {static_cast<uint32_t>(scene.spheres.size()), static_cast<uint32_t>(scene.planes.size()),
          scene.brute_force_triangle_slots(),
          search_info(scene.search).shader_mode | uint32_t{ray_mask} << VKRAY_RAY_MASK_SHIFT};
}

bool needs_lo_parts(const glm::dvec3& anchor, double radius, const glm::dvec3& origin) {
  return glm::length(origin - anchor) < 2.0 * radius;
}

gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, Precision precision,
                                      uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count,
                                      const glm::uvec4& counts) {
  gpu::RayGenParams params{};
  const glm::dvec3 origin = camera.origin - anchor;
  const glm::dvec3 right = camera.right_step(), up = camera.up_step(), forward_scaled = camera.centre_direction();
  if (precision == Precision::float64) {
    const std::array<double, 12> values{origin.x, origin.y, origin.z, right.x,          right.y,          right.z,
                                        up.x,     up.y,     up.z,     forward_scaled.x, forward_scaled.y, forward_scaled.z};
    static_assert(sizeof(values) == sizeof(params.camera));
    std::memcpy(params.camera, values.data(), sizeof(values));
  } else {
    const gpu::GpuPoint split = encode_point(glm::dvec4(origin, 0.0), Precision::float32);
    const glm::vec4 words[] = {split.first, split.second, to_float4(right), to_float4(up), to_float4(forward_scaled)};
    for (size_t k = 0; k < std::size(words); ++k) params.camera[k] = std::bit_cast<glm::uvec4>(words[k]);
  }
  params.image = glm::uvec4(width, height, first_row, row_count);
  params.counts = counts;
  return params;
}

}  // namespace vkray
