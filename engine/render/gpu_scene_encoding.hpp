// What the files that build a GpuScene share (gpu_scene.cpp, gpu_scene_instances.cpp,
// gpu_scene_refit.cpp): how positions, primitives, normals and tree nodes are encoded for the shader,
// each written once. Not part of the engine's interface: gpu_scene.hpp is.
#pragma once

#include "engine/render/gpu_scene.hpp"
#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <memory>
#include <tuple>
#include <unordered_map>
#include <vector>

namespace vkray::scene_encoding {

inline glm::vec4 to_float4(const glm::dvec3& v, double w = 0.0) { return glm::vec4(glm::dvec4(v, w)); }

// GpuPrimitive's w: the primitive's kind, its mask above it.
inline uint32_t primitive_word(uint32_t kind, Mask mask) { return kind | uint32_t{mask} << VKRAY_PRIMITIVE_MASK_SHIFT; }
// The mask a record's w holds (the flags above it, VKRAY_PRIMITIVE_FLIPPED, left out).
inline Mask primitive_mask(uint32_t word) { return static_cast<Mask>(word >> VKRAY_PRIMITIVE_MASK_SHIFT); }

// `value` (relative to the anchor) as the shader of `precision` reads it: see GpuPoint.
inline gpu::GpuPoint encode_point(const glm::dvec4& value, Precision precision) {
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
inline float step_down(float value) {
  return float_below(std::min<double>(next_float_down(value), double{value} - VKRAY_BOX_MARGIN));
}
inline float step_up(float value) {
  return float_above(std::max<double>(next_float_up(value), double{value} + VKRAY_BOX_MARGIN));
}
inline FloatBox widened(const FloatBox& box) {
  return {{step_down(box.lower.x), step_down(box.lower.y), step_down(box.lower.z)},
          {step_up(box.upper.x), step_up(box.upper.y), step_up(box.upper.z)}};
}

inline FloatBox outward(const glm::dvec3& lower, const glm::dvec3& upper) {
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
  bool flipped = false;            // the canonical order runs against the winding (VKRAY_PRIMITIVE_FLIPPED)
  // Its record's w: a triangle with `mask`, flipped where it is.
  uint32_t word(Mask mask) const {
    return primitive_word(VKRAY_PRIMITIVE_TRIANGLE, mask) | (flipped ? VKRAY_PRIMITIVE_FLIPPED : 0u);
  }
  FloatBox box() const { return outward(glm::min(v[0], glm::min(v[1], v[2])), glm::max(v[0], glm::max(v[1], v[2]))); }
};

// The triangle of corners `vertex`, each at position(index) relative to the anchor.
template <typename Position>
inline CanonicalTriangle canonical_triangle(const std::array<uint32_t, 3>& vertex, Position position) {
  CanonicalTriangle result;
  result.vertex = vertex;
  for (size_t c = 0; c < 3; ++c) result.v[c] = position(vertex[c]);
  // Three compare-and-swaps (a refit makes every triangle again: std::sort of pairs took a tenth of it).
  const auto order = [&](size_t a, size_t b) {
    if (std::tie(result.v[b].x, result.v[b].y, result.v[b].z) < std::tie(result.v[a].x, result.v[a].y, result.v[a].z)) {
      std::swap(result.v[a], result.v[b]);
      std::swap(result.vertex[a], result.vertex[b]);
      result.flipped = !result.flipped;  // each swap turns the order's winding over
    }
  };
  order(0, 1), order(1, 2), order(0, 1);
  const glm::dvec3 cross = glm::cross(result.v[1] - result.v[0], result.v[2] - result.v[0]);
  if (cross != glm::dvec3(0.0)) result.normal = unit_vector(cross);
  return result;
}

inline CanonicalTriangle canonical_triangle(const Mesh& mesh, uint32_t triangle, const glm::dvec3& anchor) {
  return canonical_triangle(mesh.triangles[triangle], [&](uint32_t k) { return mesh.positions[k] - anchor; });
}

// A sphere's box relative to the anchor.
inline FloatBox sphere_box(const glm::dvec3& centre, double radius) { return outward(centre - radius, centre + radius); }

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
inline void write_normal(glm::vec4* at, const glm::dvec3& normal, Precision precision) {
  if (precision == Precision::float64) {
    const gpu::GpuPoint point = encode_point(glm::dvec4(normal, 0.0), precision);
    at[0] = point.first, at[1] = point.second;
  } else {
    at[0] = glm::vec4(glm::dvec4(normal, 0.0));
  }
}
inline void append_normal(std::vector<glm::vec4>& texels, const glm::dvec3& normal, Precision precision) {
  texels.resize(texels.size() + texels_per_normal(precision));
  write_normal(texels.data() + texels.size() - texels_per_normal(precision), normal, precision);
}

// A tree node as the shader reads it: its two children's boxes, widened (see safe_inverse in
// shaders/intersect.glsl), and their references.
inline gpu::GpuBvhNode encode_node(const std::array<FloatBox, 2>& children, const std::array<uint32_t, 2>& references) {
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
inline std::vector<gpu::GpuPlane> encode_planes(const Scene& scene, const glm::dvec3& anchor, Precision precision) {
  std::vector<gpu::GpuPlane> planes;
  for (const auto& plane : scene.planes) {
    planes.push_back({{}, encode_point(glm::dvec4(plane.normal, glm::dot(plane.normal, plane.point - anchor)), precision)});
  }
  set_plane_heights(planes, scene.planes, scene.camera.from, precision);
  return planes;
}

// Where a shader's positions are stored from (GpuScene::anchor), and the radius about it.
inline SceneExtent anchored_extent(const Scene& scene, const ShaderVariant& shader, const SceneExtent& extent) {
  const bool world_origin = shader.precision == Precision::float64 || shader.coordinates == VKRAY_COORDINATES_ABSOLUTE;
  return world_origin ? SceneExtent{glm::dvec3(0.0), scene_radius(scene, glm::dvec3(0.0))} : extent;
}

// Triangle slots of the brute-force loop: whole batches.
inline uint32_t batched_slots(size_t triangle_count) {
  return static_cast<uint32_t>((triangle_count + VKRAY_TRIANGLE_BATCH - 1) / VKRAY_TRIANGLE_BATCH * VKRAY_TRIANGLE_BATCH);
}

// Slots of zero-area records (no ray meets them) up to `slots`.
inline void pad_slots(GpuScene& gpu, size_t slots) {
  while (gpu.primitives.size() < slots) {
    gpu.primitives.push_back(gpu::GpuPrimitive{});
    append_normal(gpu.normal_texels, glm::dvec3(0.0), gpu.precision);
    gpu.hit_sources.slots.push_back({});
  }
}

// Instanced mesh `mesh_index`'s triangles in its own coordinates (gpu_scene_instances.cpp).
std::vector<EncodedPrimitive> encode_instanced_mesh(GpuScene& gpu, const Scene& scene, uint32_t mesh_index);
// An instanced scene's layout for the tree walks, and for brute force (gpu_scene_instances.cpp).
void lay_out_instances(GpuScene& gpu, const Scene& scene, std::vector<EncodedPrimitive> world,
                       const std::vector<std::vector<EncodedPrimitive>>& instanced_triangles, const BvhBuildOptions& options);
void lay_out_brute_force_instances(GpuScene& gpu, const Scene& scene,
                                   const std::vector<std::vector<EncodedPrimitive>>& instanced_triangles);
// What place_instances needs for the ray-query layout (gpu_scene_instances.cpp).
std::shared_ptr<InstanceLevel> make_instance_level(const GpuScene& gpu, const Scene& scene,
                                                   const std::vector<std::vector<EncodedPrimitive>>& instanced_triangles);

}  // namespace vkray::scene_encoding
