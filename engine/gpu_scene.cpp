#include "engine/gpu_scene.hpp"

#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

#include <chrono>
#include <limits>

namespace vkray {
namespace {

glm::vec4 to_float4(const glm::dvec3& v, double w = 0.0) { return glm::vec4(glm::dvec4(v, w)); }

struct Bounds {
  glm::dvec3 lower{std::numeric_limits<double>::infinity()};
  glm::dvec3 upper{-std::numeric_limits<double>::infinity()};
  void add(const glm::dvec3& p) {
    lower = glm::min(lower, p);
    upper = glm::max(upper, p);
  }
};

struct FloatBox {
  glm::vec3 lower;
  glm::vec3 upper;
};

// Brute force beats the tree up to this many triangles on lavapipe: measured with `vkray render
// --timings` on meshes of n random triangles at 1920x1080 (see README, "Meshes").
constexpr size_t brute_force_max_triangles = 16;

}  // namespace

glm::dvec3 scene_anchor(const Scene& scene) {
  Bounds bounds;
  for (const auto& sphere : scene.spheres) {
    bounds.add(sphere.center - sphere.radius);
    bounds.add(sphere.center + sphere.radius);
  }
  for (const auto& mesh : scene.meshes) {
    for (const auto& position : mesh.positions) bounds.add(position);
  }
  // Only a scene of planes alone has no bounds; its camera is then the natural origin. The camera
  // is otherwise left out, so a Renderer gives the same bits whatever camera it was built with.
  if (bounds.lower.x > bounds.upper.x) bounds.add(scene.camera.from);
  return 0.5 * (bounds.lower + bounds.upper);
}

// Per-ray walks: on lavapipe they beat packets (bunny at 1920x1080: ~165 against ~230 ms), since
// llvmpipe runs subgroup operations as loops over the lanes and a packet visits the union of its
// rays' nodes. No GPU has measured packets faster yet (see README, "Meshes").
TriangleSearch choose_triangle_search(size_t triangle_count) {
  return triangle_count <= brute_force_max_triangles ? TriangleSearch::brute_force : TriangleSearch::bvh_per_ray;
}

GpuScene make_gpu_scene(const Scene& scene, const GpuSceneOptions& options) {
  GpuScene gpu;
  gpu.anchor = scene_anchor(scene);
  for (const auto& sphere : scene.spheres) gpu.spheres.push_back({to_float4(sphere.center - gpu.anchor, sphere.radius)});
  for (const auto& plane : scene.planes) {
    gpu.planes.push_back({to_float4(plane.normal, glm::dot(plane.normal, plane.point - gpu.anchor))});
  }

  // Triangles relative to the anchor, rounded to float once per vertex in double, so triangles
  // sharing a vertex see bit-identical floats: the watertight test needs that.
  std::vector<gpu::GpuTriangle> triangles;
  std::vector<Box> boxes;
  for (const auto& mesh : scene.meshes) {
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3 v0 = mesh.positions[corners[0]] - gpu.anchor;
      const glm::dvec3 v1 = mesh.positions[corners[1]] - gpu.anchor;
      const glm::dvec3 v2 = mesh.positions[corners[2]] - gpu.anchor;
      const glm::dvec3 cross = glm::cross(v1 - v0, v2 - v0);
      if (cross == glm::dvec3(0.0)) continue;
      const glm::dvec3 normal = unit_vector(cross);
      triangles.push_back({to_float4(v0, normal.x), to_float4(v1, normal.y), to_float4(v2, normal.z)});
      boxes.push_back({glm::min(v0, glm::min(v1, v2)), glm::max(v0, glm::max(v1, v2))});
    }
  }
  gpu.triangle_count = static_cast<uint32_t>(triangles.size());
  if (triangles.empty()) {
    gpu.triangle_search = TriangleSearch::brute_force;
    return gpu;
  }
  gpu.triangle_search = options.triangle_search == TriangleSearch::automatic ? choose_triangle_search(triangles.size())
                                                                              : options.triangle_search;
  if (gpu.triangle_search == TriangleSearch::brute_force) {
    gpu.triangles = std::move(triangles);
  } else {
    const auto start = std::chrono::steady_clock::now();
    const Bvh bvh = build_bvh(boxes, options.bvh);
    gpu.triangles.reserve(triangles.size() + VKRAY_TRIANGLE_BATCH);
    for (uint32_t i : bvh.primitive_order) gpu.triangles.push_back(triangles[i]);
    // Boxes of the float32 vertices the shader tests, so each box holds its triangles exactly.
    const auto bounds = child_bounds<FloatBox>(bvh, [&](uint32_t slot) {
      const gpu::GpuTriangle& t = gpu.triangles[slot];
      const glm::vec3 a(t.v0_nx), b(t.v1_ny), c(t.v2_nz);
      return FloatBox{glm::min(a, glm::min(b, c)), glm::max(a, glm::max(b, c))};
    });
    gpu.bvh_nodes.resize(bvh.nodes.size());
    for (size_t n = 0; n < bvh.nodes.size(); ++n) {
      const FloatBox& first = bounds[n][0];
      const FloatBox& second = bounds[n][1];
      gpu.bvh_nodes[n] = {
          glm::vec4(first.lower.x, second.lower.x, first.upper.x, second.upper.x),
          glm::vec4(first.lower.y, second.lower.y, first.upper.y, second.upper.y),
          glm::vec4(first.lower.z, second.lower.z, first.upper.z, second.upper.z),
          glm::uvec4(bvh.nodes[n][0], bvh.nodes[n][1], 0, 0),
      };
    }
    gpu.bvh_depth = bvh.depth;
    gpu.bvh_build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  // Whole batches for brute force, and room for a full leaf after the last one: the packet walk
  // fetches a leaf's four triangle slots whatever its count.
  const size_t spare = VKRAY_BVH_MAX_LEAF_SIZE - 1;
  gpu.triangles.resize((gpu.triangles.size() + spare + VKRAY_TRIANGLE_BATCH - 1) / VKRAY_TRIANGLE_BATCH *
                           VKRAY_TRIANGLE_BATCH,
                       gpu::GpuTriangle{});
  return gpu;
}

gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count) {
  return {to_float4(camera.origin - anchor), to_float4(camera.right), to_float4(camera.up),
          to_float4(-camera.plane_distance * camera.forward), glm::uvec4(width, height, first_row, row_count)};
}

}  // namespace vkray
