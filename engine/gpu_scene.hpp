// Conversion of the double-precision scene into the float32 arrays the shader reads.
#pragma once

#include "engine/camera.hpp"
#include "engine/scene.hpp"
#include "shaders/gpu_layout.h"

#include <vector>

namespace vkray {

struct GpuScene {
  // Every position on the GPU is stored relative to this point. float32 has ~7 digits: a scene at
  // x = 1e6 stored as is would lose everything below 0.06 units, while positions relative to a
  // point inside the scene keep their precision (the offset is taken in double, then rounded).
  glm::dvec3 anchor{0.0};
  std::vector<gpu::GpuSphere> spheres;
  std::vector<gpu::GpuPlane> planes;
  // Zero-area triangles left out (no ray can hit them); each mesh padded to whole batches.
  std::vector<gpu::GpuTriangle> triangles;
  std::vector<gpu::GpuMesh> meshes;         // non-empty meshes only, with their float32 bounds
};

// Loop iterations one shader invocation runs in the worst case (every mesh box hit).
uint64_t loop_iterations_per_ray(const GpuScene& scene);

// The anchor is the centre of the bounding box of the finite primitives (spheres, meshes).
GpuScene make_gpu_scene(const Scene& scene);

// Push constants for one tile of rows of a width x height image.
gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count);

}  // namespace vkray
