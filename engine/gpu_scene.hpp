// Conversion of the double-precision scene into the float32 arrays the shader reads.
#pragma once

#include "engine/bvh.hpp"
#include "engine/camera.hpp"
#include "engine/scene.hpp"
#include "shaders/gpu_layout.h"

#include <vector>

namespace vkray {

// How the shader finds the nearest triangle; automatic picks brute force for tiny meshes and the
// BVH otherwise (see choose_triangle_search).
enum class TriangleSearch : uint32_t {
  automatic,
  brute_force = VKRAY_TRIANGLES_BRUTE_FORCE,
  bvh_per_ray = VKRAY_TRIANGLES_BVH_PER_RAY,
  bvh_packet = VKRAY_TRIANGLES_BVH_PACKET,
};

struct GpuSceneOptions {
  TriangleSearch triangle_search = TriangleSearch::automatic;
  BvhBuildOptions bvh;
};

struct GpuScene {
  // Every position on the GPU is stored relative to this point. float32 has ~7 digits: a scene at
  // x = 1e6 stored as is would lose everything below 0.06 units, while positions relative to a
  // point inside the scene keep their precision (the offset is taken in double, then rounded).
  glm::dvec3 anchor{0.0};
  std::vector<gpu::GpuSphere> spheres;
  std::vector<gpu::GpuPlane> planes;
  // Triangles of every mesh, zero-area ones left out (no ray can hit them), in the BVH's leaf
  // order, padded to whole VKRAY_TRIANGLE_BATCHes with all-zero triangles: see gpu_layout.h.
  std::vector<gpu::GpuTriangle> triangles;
  uint32_t triangle_count = 0;           // real triangles, without the padding
  std::vector<gpu::GpuBvhNode> bvh_nodes;  // empty unless the search uses the tree
  uint32_t bvh_depth = 0;
  TriangleSearch triangle_search = TriangleSearch::brute_force;  // never automatic here
  double bvh_build_ms = 0.0;

  uint32_t triangle_slots() const { return static_cast<uint32_t>(triangles.size()); }
  // Bytes of device memory the triangles and their tree take.
  size_t triangle_bytes() const {
    return triangles.size() * sizeof(gpu::GpuTriangle) + bvh_nodes.size() * sizeof(gpu::GpuBvhNode);
  }
};

// The centre of the bounding box of the finite primitives (spheres, meshes); the camera for a
// scene of planes alone.
glm::dvec3 scene_anchor(const Scene& scene);

// Brute force for meshes of at most this many triangles, the tree beyond: see gpu_scene.cpp.
TriangleSearch choose_triangle_search(size_t triangle_count);

GpuScene make_gpu_scene(const Scene& scene, const GpuSceneOptions& options = {});

// Push constants for one tile of rows of a width x height image.
gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count);

}  // namespace vkray
