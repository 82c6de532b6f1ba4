#include "engine/gpu_scene.hpp"

#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

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

}  // namespace

GpuScene make_gpu_scene(const Scene& scene) {
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
  GpuScene gpu;
  gpu.anchor = 0.5 * (bounds.lower + bounds.upper);

  for (const auto& sphere : scene.spheres) gpu.spheres.push_back({to_float4(sphere.center - gpu.anchor, sphere.radius)});
  for (const auto& plane : scene.planes) {
    gpu.planes.push_back({to_float4(plane.normal, glm::dot(plane.normal, plane.point - gpu.anchor))});
  }
  for (const auto& mesh : scene.meshes) {
    const size_t first = gpu.triangles.size();
    glm::vec4 lower(std::numeric_limits<float>::infinity()), upper(-std::numeric_limits<float>::infinity());
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3 v0 = mesh.positions[corners[0]] - gpu.anchor;
      const glm::dvec3 v1 = mesh.positions[corners[1]] - gpu.anchor;
      const glm::dvec3 v2 = mesh.positions[corners[2]] - gpu.anchor;
      const glm::dvec3 cross = glm::cross(v1 - v0, v2 - v0);
      if (cross == glm::dvec3(0.0)) continue;
      const gpu::GpuTriangle triangle{to_float4(v0), to_float4(v1), to_float4(v2), to_float4(unit_vector(cross))};
      // Bounds of the float32 vertices the shader tests, so the box holds them exactly.
      for (const auto& v : {triangle.v0, triangle.v1, triangle.v2}) lower = glm::min(lower, v), upper = glm::max(upper, v);
      gpu.triangles.push_back(triangle);
    }
    if (gpu.triangles.size() > first) {
      while ((gpu.triangles.size() - first) % VKRAY_TRIANGLE_BATCH != 0) gpu.triangles.push_back({});
      gpu.meshes.push_back({lower, upper, glm::uvec4(first, gpu.triangles.size() - first, 0, 0)});
    }
  }
  return gpu;
}

uint64_t loop_iterations_per_ray(const GpuScene& scene) {
  uint64_t iterations = scene.spheres.size() + scene.planes.size() + scene.meshes.size();
  for (const auto& mesh : scene.meshes) iterations += mesh.triangles.y / VKRAY_TRIANGLE_BATCH;
  return iterations;
}

gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count) {
  return {to_float4(camera.origin - anchor), to_float4(camera.right), to_float4(camera.up),
          to_float4(-camera.plane_distance * camera.forward), glm::uvec4(width, height, first_row, row_count)};
}

}  // namespace vkray
