#include "engine/render/gpu_scene_encoding.hpp"

#include "engine/stopwatch.hpp"

#include <glm/matrix.hpp>

#include <cmath>
#include <limits>

namespace vkray {
using namespace scene_encoding;
namespace {

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
      const gpu::GpuPrimitive record{glm::uvec4(index[0], index[1], index[2], triangle.word(mesh.mask))};
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

size_t texels_per_normal(Precision precision) {
  return precision == Precision::float64 ? VKRAY_TEXELS_PER_NORMAL_FLOAT64 : VKRAY_TEXELS_PER_NORMAL_FLOAT32;
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
