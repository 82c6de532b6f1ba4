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

// Default workgroup shape: 8x8 in Morton order keeps a warp/wavefront/subgroup on a compact tile
// of pixels (see raycast.comp). Other shapes exist for `vkray bench` (VKRAY_SPEC_WORKGROUP_*).
#define VKRAY_WORKGROUP_X 8
#define VKRAY_WORKGROUP_Y 8

// Descriptor bindings, all in set 0. Geometry is read through uniform texel buffers (RGBA32 texels):
// llvmpipe (lavapipe) turns a storage-buffer load into a loop over the 8 lanes with a branch and a
// bounds check per lane and component, but a texel fetch into one vectorized gather, several times
// faster; real GPUs read either at the same speed. Outputs are storage buffers. Bindings the scene
// or the chosen outputs do not need get a 16-byte placeholder and are never read.
#define VKRAY_BINDING_SPHERES 0      // texels, RGBA32F: one per sphere tested without the tree
#define VKRAY_BINDING_PLANES 1       // texels, RGBA32F: one per plane
#define VKRAY_BINDING_PRIMITIVES 2   // texels, RGBA32F: three per primitive slot (GpuPrimitive)
#define VKRAY_BINDING_DEPTH 3        // storage buffer
#define VKRAY_BINDING_NORMAL 4       // storage buffer
#define VKRAY_BINDING_UV 5           // storage buffer
#define VKRAY_BINDING_BVH_BOUNDS 6   // texels, RGBA32F: four per node (GpuBvhNode), boxes in the first three
#define VKRAY_BINDING_BVH_LINKS 7    // texels, RGBA32UI view of the same buffer: children in the fourth
#define VKRAY_BINDING_OVERFLOW 8     // storage buffer
#define VKRAY_BINDING_COUNT 9

// How the shader finds the nearest triangle or sphere (VKRAY_SPEC_SEARCH_MODE). Planes are
// infinite: they stay outside the tree, in their own loop.
#define VKRAY_SEARCH_BRUTE_FORCE 0  // every primitive in a loop; no tree (a handful of them)
#define VKRAY_SEARCH_BVH_PER_RAY 1  // each ray walks the tree with its own stack
#define VKRAY_SEARCH_BVH_PACKET 2   // a subgroup's rays walk the tree together, one shared stack

// Specialization constants: counts (0 removes that loop and its reads), how primitives are found,
// what the tree holds, which outputs are written, and the loop budget.
#define VKRAY_SPEC_SPHERE_COUNT 0           // spheres tested one by one, outside the tree
#define VKRAY_SPEC_PLANE_COUNT 1
#define VKRAY_SPEC_TRIANGLE_SLOTS 2         // triangles tested by brute force, a multiple of VKRAY_TRIANGLE_BATCH
#define VKRAY_SPEC_WRITE_DEPTH 3
#define VKRAY_SPEC_WRITE_NORMAL 4
#define VKRAY_SPEC_WRITE_UV 5
#define VKRAY_SPEC_SEARCH_MODE 6
// Iterations the tree walk of one ray may take; 0: unlimited. llvmpipe (lavapipe) silently ends
// every loop of a shader invocation after 65535 iterations in total (LP_MAX_TGSI_LOOP_ITERATIONS);
// a ray that would need more stops at this budget instead, lists its pixel in the overflow
// buffer, and the host finishes that pixel (see engine/renderer.cpp): no geometry goes missing.
#define VKRAY_SPEC_LOOP_BUDGET 7
#define VKRAY_SPEC_TREE_HAS_TRIANGLES 8
#define VKRAY_SPEC_TREE_HAS_SPHERES 9
// Variants that trade error or generality for time, so `vkray bench` can show what each choice buys;
// the defaults are what vkray renders with (engine/shader_variant.hpp).
#define VKRAY_SPEC_SPHERE_FORMULA 10        // VKRAY_SPHERE_*
#define VKRAY_SPEC_TRIANGLE_TEST 11         // VKRAY_TRIANGLE_*
#define VKRAY_SPEC_WORKGROUP_X 12           // local_size_x
#define VKRAY_SPEC_WORKGROUP_Y 13           // local_size_y
#define VKRAY_SPEC_MORTON_ORDER 14          // invocations in Morton order (square power-of-two groups)
// Every primitive type's code compiled in, with counts and search mode read from the push
// constants (RayGenParams.counts) instead of specialized: what a shader not built for its scene costs.
#define VKRAY_SPEC_GENERIC 15
#define VKRAY_SPEC_COUNT 16

#define VKRAY_SPHERE_STABLE 0               // Ray Tracing Gems ch. 7 (intersect.glsl)
#define VKRAY_SPHERE_NAIVE 1                // the textbook b^2 - c
#define VKRAY_TRIANGLE_WATERTIGHT 0         // Woop, Benthin and Wald 2013
#define VKRAY_TRIANGLE_MOLLER_TRUMBORE 1    // Moeller and Trumbore 1997

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

// A primitive the tree holds (or a triangle tested by brute force): three texels.
// - Triangle: its vertices relative to the anchor in xyz, and its unit geometric normal spread over
//   the three w components. The normal is computed in double on the host, so needle triangles get an
//   accurate one; the shader reads it only for the winning triangle.
// - Sphere: (centre relative to the anchor, radius), then (centre, VKRAY_SPHERE_MARK) and (centre,
//   0). The mark tells it from a triangle (normal components are within [-1, 1]); read as a
//   triangle, its three equal vertices have a zero determinant and are never hit.
// Primitives are stored in the order of the BVH's leaves, so a leaf is a contiguous range, and
// triangles pre-gathered rather than indexed: three fetches a triangle instead of four dependent ones.
struct GpuPrimitive {
  vec4 a;
  vec4 b;
  vec4 c;
};
VKRAY_CHECK_SIZE(GpuPrimitive, 48);
#define VKRAY_SPHERE_MARK 4.0

// The brute-force path tests triangles in batches of this many, padded with all-zero triangles
// (never hit: their determinant is 0), in one loop iteration with a constant trip count the
// compiler unrolls. This matters on lavapipe, whose loop cap counts iterations.
#define VKRAY_TRIANGLE_BATCH 8

// BVH: binary, with both children's boxes stored in their parent, so one node fetch gives a ray
// both slab tests and the nearer child. 64 bytes, one cache line. Per axis: (lower of child 0,
// lower of child 1, upper of child 0, upper of child 1). Boxes are float32, relative to the anchor,
// and hold the float32 primitives exactly.
struct GpuBvhNode {
  vec4 bounds_x;
  vec4 bounds_y;
  vec4 bounds_z;
  uvec4 children;  // x, y: child references; z, w: 0
};
VKRAY_CHECK_SIZE(GpuBvhNode, 64);

// Node boxes are widened by at least this much beyond what they hold (see safe_inverse in
// shaders/intersect.glsl); relative to a scene's size that is nothing for any scene float32 can hold.
#define VKRAY_BOX_MARGIN 1e-20

// A child reference is an inner node's index, or, with VKRAY_BVH_LEAF_BIT set, a leaf: its first
// primitive slot in the low bits above VKRAY_BVH_LEAF_COUNT_BITS and its count minus one below.
#define VKRAY_BVH_LEAF_BIT 0x80000000u
#define VKRAY_BVH_LEAF_COUNT_BITS 3
#define VKRAY_BVH_MAX_LEAF_SIZE 8                 // 1 << VKRAY_BVH_LEAF_COUNT_BITS
#define VKRAY_BVH_MAX_PRIMITIVES 0x0fffffffu      // what the 28 bits of a leaf's first slot hold
// The builder's depth limit; it bounds the traversal stack. SAH trees of real meshes are far
// shallower (the bunny's is 16 deep, a 4M-triangle sphere's 24), but a chain of nested clusters
// across many scales drove Embree's builder into its depth limit at 64 (tests/bvh_test.cpp).
#define VKRAY_BVH_MAX_DEPTH 128

// Per-dispatch camera and image parameters (push constants). The camera basis is computed in
// double on the host; the shader only evaluates direction = x*right + y*up + forward_scaled.
struct RayGenParams {
  vec4 origin;          // camera position relative to the anchor
  vec4 right;           // unit right vector
  vec4 up;              // unit up vector (forward x right)
  vec4 forward_scaled;  // -plane_distance * forward
  uvec4 image;          // width, height, first row of this tile, rows in this tile
  uvec4 counts;         // read by the generic variant only: spheres, planes, triangle slots, search mode
};
VKRAY_CHECK_SIZE(RayGenParams, 96);

#ifdef __cplusplus
}  // namespace vkray::gpu
#endif
#undef VKRAY_CHECK_SIZE
#endif  // VKRAY_GPU_LAYOUT_H
