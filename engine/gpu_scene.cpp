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

// A triangle kept for the GPU: its vertices' indices into GpuScene::positions and its unit normal.
struct IndexedTriangle {
  std::array<uint32_t, 3> corners;
  glm::dvec3 normal;
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

TriangleSearch choose_triangle_search(size_t triangle_count) {
  return triangle_count <= brute_force_max_triangles ? TriangleSearch::brute_force : TriangleSearch::bvh_packet;
}

GpuScene make_gpu_scene(const Scene& scene, const GpuSceneOptions& options) {
  GpuScene gpu;
  gpu.anchor = scene_anchor(scene);
  for (const auto& sphere : scene.spheres) gpu.spheres.push_back({to_float4(sphere.center - gpu.anchor, sphere.radius)});
  for (const auto& plane : scene.planes) {
    gpu.planes.push_back({to_float4(plane.normal, glm::dot(plane.normal, plane.point - gpu.anchor))});
  }

  // Vertices referenced by a kept triangle, relative to the anchor (rounded once, so triangles
  // sharing a vertex see bit-identical floats: the watertight test needs that).
  std::vector<IndexedTriangle> triangles;
  std::vector<Box> boxes;
  for (const auto& mesh : scene.meshes) {
    std::vector<uint32_t> vertex_index(mesh.positions.size(), UINT32_MAX);
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3 v0 = mesh.positions[corners[0]] - gpu.anchor;
      const glm::dvec3 v1 = mesh.positions[corners[1]] - gpu.anchor;
      const glm::dvec3 v2 = mesh.positions[corners[2]] - gpu.anchor;
      const glm::dvec3 cross = glm::cross(v1 - v0, v2 - v0);
      if (cross == glm::dvec3(0.0)) continue;
      IndexedTriangle triangle{{}, unit_vector(cross)};
      for (int k = 0; k < 3; ++k) {
        uint32_t& index = vertex_index[corners[k]];
        if (index == UINT32_MAX) {
          index = static_cast<uint32_t>(gpu.positions.size() / 3);
          const glm::vec3 p(mesh.positions[corners[k]] - gpu.anchor);
          gpu.positions.insert(gpu.positions.end(), {p.x, p.y, p.z});
        }
        triangle.corners[k] = index;
      }
      triangles.push_back(triangle);
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

  std::vector<uint32_t> order(triangles.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  if (gpu.triangle_search != TriangleSearch::brute_force) {
    const auto start = std::chrono::steady_clock::now();
    Bvh bvh = build_bvh(boxes, options.bvh);
    order = std::move(bvh.primitive_order);
    bvh.primitive_order.clear();
    // Boxes of the float32 vertices the shader tests, so each box holds its triangles exactly.
    auto vertex = [&](uint32_t index) {
      return glm::vec3(gpu.positions[3 * index], gpu.positions[3 * index + 1], gpu.positions[3 * index + 2]);
    };
    const auto bounds = child_bounds<FloatBox>(bvh, [&](uint32_t slot) {
      const auto& corners = triangles[order[slot]].corners;
      const glm::vec3 a = vertex(corners[0]), b = vertex(corners[1]), c = vertex(corners[2]);
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

  const size_t slots = (triangles.size() + VKRAY_TRIANGLE_BATCH - 1) / VKRAY_TRIANGLE_BATCH * VKRAY_TRIANGLE_BATCH;
  gpu.triangle_indices.assign(3 * slots, 0u);
  gpu.triangle_normals.assign(3 * slots, 0.0f);
  for (size_t slot = 0; slot < order.size(); ++slot) {
    const IndexedTriangle& triangle = triangles[order[slot]];
    const glm::vec3 normal(triangle.normal);
    for (int k = 0; k < 3; ++k) {
      gpu.triangle_indices[3 * slot + k] = triangle.corners[k];
      gpu.triangle_normals[3 * slot + k] = normal[k];
    }
  }
  return gpu;
}

gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count) {
  return {to_float4(camera.origin - anchor), to_float4(camera.right), to_float4(camera.up),
          to_float4(-camera.plane_distance * camera.forward), glm::uvec4(width, height, first_row, row_count)};
}

}  // namespace vkray
