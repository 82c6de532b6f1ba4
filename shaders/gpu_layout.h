// Data layout shared by the host (C++) and the ray-casting compute shader (GLSL).
// Both sides include this one file, so a struct, a binding number or a specialization-constant id
// cannot drift apart. Only vec4/uvec4 members are used: their std430 layout (16-byte size and
// alignment) matches glm's tightly packed vec4 with no padding rules to get wrong.
#ifndef VKRAY_GPU_LAYOUT_H
#define VKRAY_GPU_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/vec4.hpp>
namespace vkray::gpu {
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
#define VKRAY_CHECK_SIZE(type, bytes) static_assert(sizeof(type) == (bytes), #type " layout")
#else
#define VKRAY_CHECK_SIZE(type, bytes)
#endif

// Workgroup shape: 8x8 keeps a warp/wavefront/subgroup on a compact tile of pixels.
#define VKRAY_WORKGROUP_X 8
#define VKRAY_WORKGROUP_Y 8

// Descriptor bindings, all in set 0. Buffers of primitive types the scene lacks are bound to one
// shared 16-byte placeholder and never read (the specialized count is 0).
#define VKRAY_BINDING_SPHERES 0
#define VKRAY_BINDING_PLANES 1
#define VKRAY_BINDING_TRIANGLES 2
#define VKRAY_BINDING_DEPTH 3
#define VKRAY_BINDING_NORMAL 4
#define VKRAY_BINDING_UV 5
#define VKRAY_BINDING_MESHES 6
#define VKRAY_BINDING_COUNT 7

// Specialization constants: primitive counts (0 removes that loop and its buffer reads) and which
// outputs are written.
#define VKRAY_SPEC_SPHERE_COUNT 0
#define VKRAY_SPEC_PLANE_COUNT 1
#define VKRAY_SPEC_MESH_COUNT 2
#define VKRAY_SPEC_WRITE_DEPTH 3
#define VKRAY_SPEC_WRITE_NORMAL 4
#define VKRAY_SPEC_WRITE_UV 5
#define VKRAY_SPEC_COUNT 6

// All positions on the GPU are relative to the scene's anchor point (see engine/gpu_scene.cpp), so
// float32 keeps its precision for scenes far from the world origin.

// center.xyz relative to the anchor, radius in w.
struct GpuSphere {
  vec4 center_radius;
};
VKRAY_CHECK_SIZE(GpuSphere, 16);

// Unit normal in xyz; w = dot(normal, point - anchor), computed in double on the host.
struct GpuPlane {
  vec4 normal_offset;
};
VKRAY_CHECK_SIZE(GpuPlane, 16);

// Vertices relative to the anchor (w unused) and the unit geometric normal, computed in double on
// the host so needle triangles get an accurate normal. 64 bytes: one cache line per triangle.
struct GpuTriangle {
  vec4 v0;
  vec4 v1;
  vec4 v2;
  vec4 normal;
};
VKRAY_CHECK_SIZE(GpuTriangle, 64);

// Each mesh's triangles are padded with all-zero triangles (never hit: their determinant is 0) to a
// multiple of this batch, which the shader tests in one loop iteration with a constant trip count
// the compiler unrolls. Besides saving loop overhead this matters on lavapipe: llvmpipe ends a
// shader invocation's loops after 65535 iterations in total (its guard against endless loops),
// silently skipping what is left; see GpuDeviceInfo::max_loop_iterations.
#define VKRAY_TRIANGLE_BATCH 8

// A mesh's bounding box (relative to the anchor; w unused) and its range of triangles: rays that
// miss the box skip all of them.
struct GpuMesh {
  vec4 lower;
  vec4 upper;
  uvec4 triangles;  // x: first triangle, y: triangle count (a multiple of VKRAY_TRIANGLE_BATCH)
};
VKRAY_CHECK_SIZE(GpuMesh, 48);

// Per-dispatch camera and image parameters (push constants). The camera basis is computed in
// double on the host; the shader only evaluates direction = x*right + y*up + forward_scaled.
struct RayGenParams {
  vec4 origin;          // camera position relative to the anchor
  vec4 right;           // unit right vector
  vec4 up;              // unit up vector (forward x right)
  vec4 forward_scaled;  // -plane_distance * forward
  uvec4 image;          // width, height, first row of this tile, rows in this tile
};
VKRAY_CHECK_SIZE(RayGenParams, 80);

#ifdef __cplusplus
}  // namespace vkray::gpu
#endif
#undef VKRAY_CHECK_SIZE
#endif  // VKRAY_GPU_LAYOUT_H
