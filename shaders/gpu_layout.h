// Data layout shared by the host (C++) and the ray-casting compute shader (GLSL).
// Both sides include this one file, so a struct, a binding number or a specialization-constant id
// cannot drift apart. Only vec4/uvec4 members are used: their std430 layout (16-byte size and
// alignment) matches glm's tightly packed vec4 with no padding rules to get wrong.
#ifndef VKRAY_GPU_LAYOUT_H
#define VKRAY_GPU_LAYOUT_H

#ifdef __cplusplus
#include <algorithm>
#include <cmath>
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
// faster. NVIDIA and AMD drivers are usually tuned for storage-buffer loads: the storage-geometry
// variant (VKRAY_STORAGE_GEOMETRY, its own SPIR-V module) binds the same buffers as storage buffers
// of 16-byte texels. Outputs are storage buffers. Bindings the scene or the chosen outputs do not
// need get a 16-byte placeholder and are never read.
#define VKRAY_BINDING_SPHERES 0      // texels, RGBA32F: one per sphere tested without the tree
#define VKRAY_BINDING_PLANES 1       // texels, RGBA32F: one per plane
#define VKRAY_BINDING_PRIMITIVES 2   // texels, RGBA32UI: one per primitive slot (GpuPrimitive)
#define VKRAY_BINDING_DEPTH 3        // storage buffer
#define VKRAY_BINDING_NORMAL 4       // storage buffer
#define VKRAY_BINDING_UV 5           // storage buffer
#define VKRAY_BINDING_BVH_BOUNDS 6   // texels, RGBA32F: four per node (GpuBvhNode), boxes in the first three
#define VKRAY_BINDING_BVH_LINKS 7    // texels, RGBA32UI view of the same buffer: children in the fourth
#define VKRAY_BINDING_OVERFLOW 8     // storage buffer
// The storage-image target (`vkray view`): one output's values in an RGBA32F storage image instead
// of the buffers above, and the range of its finite depths (DepthRangeBits) for the preview's grey.
#define VKRAY_BINDING_IMAGE 9        // storage image, RGBA32F
#define VKRAY_BINDING_DEPTH_RANGE 10 // storage buffer
#define VKRAY_BINDING_VERTICES 11    // texels, RGBA32F: a GpuPoint per vertex (and per sphere in the tree)
#define VKRAY_BINDING_NORMALS 12     // texels, RGBA32F: a triangle's unit normal per primitive slot
// Rays given by the caller instead of a camera (VKRAY_SPEC_RAY_INPUT): two GpuPoints a ray (GpuRay),
// or for rays from one origin their float32 unit directions alone, a texel each; and what each ray
// hit (VKRAY_HIT_*; for camera rays too with VKRAY_SPEC_WRITE_HIT).
#define VKRAY_BINDING_RAYS 13        // texels, RGBA32F
#define VKRAY_BINDING_HITS 14        // storage buffer
// Rays from one origin read and hits written where the caller holds them
// (VKRAY_RAY_INPUT_CALLER_DIRECTIONS; the device imports the caller's memory): the rays as the
// caller gave them, six doubles each (three RGBA32UI texels), and a mesh id and a primitive id a
// ray beside the depth (VKRAY_BINDING_DEPTH: the distance t) and normal (VKRAY_BINDING_NORMAL, x y z
// of a ray together); the shader turns a primitive slot into its ids by the table in
// VKRAY_BINDING_HIT_SOURCES (a uvec2 of mesh id and primitive id a slot, as HitSources holds them).
#define VKRAY_BINDING_CALLER_RAYS 15     // texels, RGBA32UI
#define VKRAY_BINDING_HIT_SOURCES 16     // storage buffer
#define VKRAY_BINDING_MESH_IDS 17        // storage buffer
#define VKRAY_BINDING_PRIMITIVE_IDS 18   // storage buffer
// With VKRAY_CALLER_BY_DIRECTION: the rays' indices ordered by direction (direction_order.comp).
// (Rays gathered into that order there instead, for the walk to read in order, cost lavapipe more:
// the order's scattered writes of 16 bytes a ray took longer than the walk's reads all over the
// caller's rays, 40 ms against 14 of a million rays' 70.)
#define VKRAY_BINDING_RAY_ORDER 19       // storage buffer
// With VKRAY_SPEC_MASKS: the masks of the spheres tested one by one, then of the planes, one a
// texel (x; the tree's primitives carry theirs in GpuPrimitive).
#define VKRAY_BINDING_APART_MASKS 20     // texels, RGBA32UI
// With VKRAY_SPEC_INSTANCES: the instances (VKRAY_TEXELS_PER_INSTANCE_*), and with WRITE_HIT or given rays, the
// instance each ray hit (VKRAY_NO_INSTANCE for none), beside VKRAY_BINDING_HITS.
#define VKRAY_BINDING_INSTANCES 21       // texels, as positions
#define VKRAY_BINDING_INSTANCE_HITS 22   // storage buffer
// Point queries (VKRAY_RAY_INPUT_POINTS), made at a renderer's first: each instance's linear map (its
// rows in three texels' xyz, the least factor it shrinks a length by in the first's w:
// smallest_scale) to measure its mesh's triangles in the world's coordinates; and for the winding
// number, each node's caps (a uvec4: the first edge and count of each child's, VKRAY_NO_CAP for a
// child walked into) and the caps' edges (two vertex indices each, two edges a texel), see
// engine/scene/winding_caps.hpp.
#define VKRAY_BINDING_PLACEMENTS 23      // texels, as positions
#define VKRAY_BINDING_WINDING_CAPS 24    // texels, RGBA32UI
#define VKRAY_BINDING_CAP_EDGES 25       // texels, RGBA32UI
// The ray-query traversal's top-level acceleration structure (VKRAY_SEARCH_RAY_QUERY): in its
// pipelines' descriptor sets alone, the last binding.
#define VKRAY_BINDING_TOP_STRUCTURE 26
#define VKRAY_BINDING_COUNT 27
#define VKRAY_NO_CAP 0xffffffffu

// How the shader finds the nearest triangle or sphere (VKRAY_SPEC_SEARCH_MODE). Planes are
// infinite: they stay outside the tree, in their own loop.
#define VKRAY_SEARCH_BRUTE_FORCE 0  // every primitive in a loop; no tree (a handful of them)
#define VKRAY_SEARCH_BVH_PER_RAY 1  // each ray walks the tree with its own stack
#define VKRAY_SEARCH_BVH_PACKET 2   // a subgroup's camera rays walk the tree together (packet_walk.glsl)
#define VKRAY_SEARCH_RAY_QUERY 3    // the device's acceleration structures (ray_query_walk.glsl)

// The packet walk's pixels: each invocation traces a column of VKRAY_PACKET_ROWS pixels, and the
// 64 invocations of a workgroup (8x8, in index order) cover VKRAY_PACKET_GROUP_WIDTH columns of
// 4 such rows of columns: invocation i takes column i % 16 of row block i / 16. A subgroup of 8
// consecutive invocations (lavapipe) thus holds an 8x8 block of pixels, one of 32 a 16x16 block.
#define VKRAY_PACKET_ROWS 8
#define VKRAY_PACKET_GROUP_WIDTH 16
#define VKRAY_PACKET_GROUP_HEIGHT 32

// Functions both sides compute alike: GLSL's syntax, with these few names for what differs.
#ifdef __cplusplus
#define VKRAY_SHARED_FUNCTION inline
#define VKRAY_ABS(x) std::fabs(x)
#define VKRAY_CLAMP(x, low, high) std::clamp(x, low, high)
using uint = std::uint32_t;
#else
#define VKRAY_SHARED_FUNCTION
#define VKRAY_ABS(x) abs(x)
#define VKRAY_CLAMP(x, low, high) clamp(x, low, high)
#endif
// Given rays from one origin listed in an order for the packet walk (consecutive rays pointing
// nearly the same way) take their positions in rows VKRAY_PACKET_GROUP_WIDTH wide so that 64
// consecutive ones form one packet of 8 columns (lavapipe's 8 lanes; wider subgroups take several
// packets) by VKRAY_PACKET_ROWS rows: the place in the order of the ray at `position`. A block of
// VKRAY_PACKET_ROWS rows holds the same places as its positions, whole packets.
#define VKRAY_PACKET_COLUMNS 8
VKRAY_SHARED_FUNCTION uint packet_order_index(uint position) {
  uint x = position % VKRAY_PACKET_GROUP_WIDTH, y = position / VKRAY_PACKET_GROUP_WIDTH;
  uint packet = (y / VKRAY_PACKET_ROWS) * (VKRAY_PACKET_GROUP_WIDTH / VKRAY_PACKET_COLUMNS) + x / VKRAY_PACKET_COLUMNS;
  return packet * (VKRAY_PACKET_COLUMNS * VKRAY_PACKET_ROWS) + (y % VKRAY_PACKET_ROWS) * VKRAY_PACKET_COLUMNS +
         x % VKRAY_PACKET_COLUMNS;
}

// Rays from one origin listed in no such order are ordered by this key of their unit direction
// (x, y, z): the index along a Hilbert curve of the cell it falls in, 2^bits cells a side, on the
// octahedral map of directions onto [-1, 1]^2. Any run of consecutive keys then points into a small
// patch of the sphere (a Hilbert curve never jumps). The map is continuous over the half z >= 0, the
// other half folded over the square's corners (Meyer et al., "On floating-point normal vectors",
// 2010; Cigolle et al., "A survey of efficient representations for independent unit vectors", JCGT
// 2014); only nearness matters here, not exact inversion. The curve's index takes two bits a
// level: the quadrant (x, y) gives the digit (3x) ^ y; in the lower left quadrant x and y swap,
// in the lower right they swap and are complemented (Hilbert, 1891, in the usual xy-to-index loop's
// form). On the host and in shaders/direction_order.comp alike.
VKRAY_SHARED_FUNCTION uint direction_key(float x, float y, float z, uint bits) {
  float sum = VKRAY_ABS(x) + VKRAY_ABS(y) + VKRAY_ABS(z);
  float u = x / sum, v = y / sum;
  if (z < 0.0f) {
    float folded_u = (1.0f - VKRAY_ABS(v)) * (u >= 0.0f ? 1.0f : -1.0f);
    v = (1.0f - VKRAY_ABS(u)) * (v >= 0.0f ? 1.0f : -1.0f);
    u = folded_u;
  }
  uint last = (1u << bits) - 1u;
  float cells = float(1u << bits);
  uint cell_x = uint(VKRAY_CLAMP((u + 1.0f) * 0.5f * cells, 0.0f, cells - 1.0f));
  uint cell_y = uint(VKRAY_CLAMP((v + 1.0f) * 0.5f * cells, 0.0f, cells - 1.0f));
  uint index = 0u;
  for (uint side = 1u << (bits - 1u); side > 0u; side >>= 1u) {
    uint quadrant_x = (cell_x & side) != 0u ? 1u : 0u;
    uint quadrant_y = (cell_y & side) != 0u ? 1u : 0u;
    index += side * side * ((3u * quadrant_x) ^ quadrant_y);
    if (quadrant_y == 0u) {
      if (quadrant_x == 1u) {
        cell_x = last - cell_x;
        cell_y = last - cell_y;
      }
      uint swapped = cell_x;
      cell_x = cell_y;
      cell_y = swapped;
    }
  }
  return index;
}

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
// buffer, and the host finishes that pixel (see engine/render/renderer.cpp): no geometry goes missing.
#define VKRAY_SPEC_LOOP_BUDGET 7
#define VKRAY_SPEC_TREE_HAS_TRIANGLES 8
#define VKRAY_SPEC_TREE_HAS_SPHERES 9
// Variants that trade error or generality for time, so `vkray bench` can show what each choice buys;
// the defaults are what vkray renders with (engine/vulkan/shader_variant.hpp).
#define VKRAY_SPEC_SPHERE_FORMULA 10        // VKRAY_SPHERE_*
#define VKRAY_SPEC_TRIANGLE_TEST 11         // VKRAY_TRIANGLE_*
#define VKRAY_SPEC_WORKGROUP_X 12           // local_size_x
#define VKRAY_SPEC_WORKGROUP_Y 13           // local_size_y
#define VKRAY_SPEC_MORTON_ORDER 14          // invocations in Morton order (square power-of-two groups)
// Every primitive type's code compiled in, with counts and search mode read from the push
// constants (RayGenParams.counts) instead of specialized: what a shader not built for its scene costs.
#define VKRAY_SPEC_GENERIC 15
#define VKRAY_SPEC_COORDINATES 16           // VKRAY_COORDINATES_* (float32 shaders)
// Camera-relative coordinates add the lo parts of positions only while the camera is near the
// scene (engine/render/gpu_scene.cpp, needs_lo_parts): two pipelines, chosen per render, since on lavapipe
// a run-time branch costs as much as the code it skips.
#define VKRAY_SPEC_LO_PARTS 17
// Write the one requested output into the storage image (VKRAY_BINDING_IMAGE) rather than buffers.
#define VKRAY_SPEC_IMAGE_TARGET 18
// Entries of the tree walk's stack held in registers, a multiple of 4 up to
// VKRAY_STACK_REGISTERS_MAX, at least the tree's depth (a walk holds at most one entry per inner
// node on its path); 0 keeps the stack in an array, for deeper trees and the generic variant. On
// llvmpipe a private array indexed per lane costs a memory access with a branch per lane: in
// registers, shifted on every push and pop, the bunny's walk at 1920x1080 took 146 instead of
// 235 ms (16 registers; each 4 more cost about 4 ms).
#define VKRAY_SPEC_STACK_REGISTERS 19
// Trace the rays of VKRAY_BINDING_RAYS rather than a camera's, and write what each hit to
// VKRAY_BINDING_HITS (Python's cast_rays): depth and normal as for pixels. One of:
#define VKRAY_SPEC_RAY_INPUT 20
#define VKRAY_RAY_INPUT_NONE 0        // a camera's pixels
#define VKRAY_RAY_INPUT_RAYS 1        // GpuRays, one an invocation, each from its own origin
// Directions from the origin in RayGenParams.camera, as a camera's: each ray's float32 unit
// direction with w = the end of its range (as GpuRay's), a texel, at its position in an image of
// rows `width` wide, for the packet walk (the host chooses the positions so that neighbours point
// nearly the same way: see Renderer::cast_rays).
#define VKRAY_RAY_INPUT_DIRECTIONS 2
// The caller's own rays from one origin (VKRAY_BINDING_CALLER_RAYS), all of them from the first
// one's origin as far as the shader finds (a ray from elsewhere, or with a zero or non-finite
// direction, is listed in the overflow buffer for the host), each direction normalized in the
// shader as unit_vector does on the host, then rounded to float; hits written to the caller's
// arrays by ray (see VKRAY_CALLER_*). Positions are the rays' indices, or with VKRAY_CALLER_IN_ORDER
// their places in the packet walk's order (packet_order_index), of the rays as listed or, with
// VKRAY_CALLER_BY_DIRECTION, as VKRAY_BINDING_RAY_ORDER orders them.
#define VKRAY_RAY_INPUT_CALLER_DIRECTIONS 3
// Points instead of rays (Renderer::closest_points, winding_numbers): a GpuPoint a point in
// VKRAY_BINDING_RAYS (its w: the query's largest distance, +infinity for none), as many as rays;
// with VKRAY_HIT_QUERY_NEAREST each point's nearest point of the scene written as its distance
// (VKRAY_BINDING_DEPTH), its offset from the point (VKRAY_BINDING_NORMAL's planes) and what it lies
// on (VKRAY_BINDING_HITS, VKRAY_BINDING_INSTANCE_HITS); with VKRAY_HIT_QUERY_WINDING the winding
// number (VKRAY_BINDING_DEPTH). See shaders/point_walk.glsl.
#define VKRAY_RAY_INPUT_POINTS 4
// The device's subgroup size where it is 8, else 0 (see shaders/packet_walk.glsl).
#define VKRAY_SPEC_SUBGROUP_SIZE 21
// Write what each camera ray hit to VKRAY_BINDING_HITS too (the mesh-id and primitive-id outputs).
#define VKRAY_SPEC_WRITE_HIT 22
// What a ray's walk looks for (HitQuery in engine/scene/scene.hpp):
// - the nearest hit;
// - any hit (Renderer::occluded): the walk stops at its first, whichever it is; only whether it hit
//   means anything then, not its depth or normal;
// - every crossing (Renderer::count_intersections): the walk goes to the end of the ray's range
//   and counts each surface it crosses into VKRAY_BINDING_HITS; an edge or vertex a ray passes
//   exactly through counts once (intersect_triangle's claim_edges).
#define VKRAY_SPEC_HIT_QUERY 23
#define VKRAY_HIT_QUERY_NEAREST 0
#define VKRAY_HIT_QUERY_ANY 1
#define VKRAY_HIT_QUERY_COUNT 2
#define VKRAY_HIT_QUERY_WINDING 3  // points alone: the generalized winding number
// The scene gives some mesh, sphere or plane a mask other than every bit (see Mask in
// engine/scene/scene.hpp): a primitive counts only where its mask shares a bit with the call's ray
// mask (RayGenParams.counts.w). Without, no mask is read or tested.
#define VKRAY_SPEC_MASKS 24
// Given rays' first hits (Renderer::cast_rays with hits > 1): the first VKRAY_SPEC_HITS crossings
// along each ray in order of distance (the crossings counting counts, an edge or vertex once),
// each written as a nearest hit is, hit k of a tile's rays in the k-th of VKRAY_SPEC_HITS runs of
// each output's planes. 1: the nearest hit alone.
#define VKRAY_SPEC_HITS 25
#define VKRAY_HITS_MAX 16
// The scene places meshes by instances (Scene::instances): the tree's leaves may hold an instance
// (VKRAY_PRIMITIVE_INSTANCE), whose mesh's own tree the ray then walks in the mesh's coordinates
// (primitives.glsl). Without, no instance is read or tested.
#define VKRAY_SPEC_INSTANCES 26
#define VKRAY_SPEC_COUNT 27
#define VKRAY_STACK_REGISTERS_MAX 32

#define VKRAY_SPHERE_STABLE 0               // Ray Tracing Gems ch. 7 (intersect.glsl)
#define VKRAY_SPHERE_NAIVE 1                // the textbook b^2 - c
#define VKRAY_TRIANGLE_WATERTIGHT 0         // Woop, Benthin and Wald 2013
#define VKRAY_TRIANGLE_MOLLER_TRUMBORE 1    // Moeller and Trumbore 1997
#define VKRAY_COORDINATES_CAMERA_RELATIVE 0 // hi and lo parts (GpuPoint): float32 relative to the camera
#define VKRAY_COORDINATES_SCENE_ANCHOR 1    // hi parts alone: float32 relative to the scene's centre
#define VKRAY_COORDINATES_ABSOLUTE 2        // hi parts alone, anchor at the world origin: plain float32

// Positions. Every position on the GPU is stored relative to the scene's anchor (the centre of its
// box; see engine/render/gpu_scene.cpp) as a GpuPoint: the position and one more number in two texels. How
// the shader reads them depends on its precision:
// - float32 shaders: `first` is the position (xyz, w) rounded to float ("hi"), `second` what that
//   rounding left out, rounded to float ("lo"): together ~48 significant bits. The camera comes in
//   the same split, and the shader subtracts hi from hi and lo from lo before adding: the difference
//   is then accurate to float32 relative to the distance from the camera, not to the distance from
//   the anchor (relative-to-eye rendering, as planet renderers do it; Cozzi and Ring, "3D Engine
//   Design for Virtual Globes", 2011, ch. 5). Precision follows the camera without re-uploading
//   anything when it moves.
// - float64 shaders (`--precision double`): the anchor is the world origin, and `first` holds x and y,
//   `second` z and w, each double as two 32-bit words (read through the RGBA32UI view).
struct GpuPoint {
  vec4 first;
  vec4 second;
};
VKRAY_CHECK_SIZE(GpuPoint, 32);

// A ray given by the caller: its origin relative to the anchor, then its unit direction with w =
// the end of its range (hits count at t < w; +infinity for none), each split as positions are, so
// float32 shaders keep the origin's ~48 bits and float64 shaders read both exactly. float32 shaders
// read the end rounded to float, as they read the direction (a hit within float32's distance error
// of it may fall either side).
struct GpuRay {
  GpuPoint origin;
  GpuPoint direction;
};
VKRAY_CHECK_SIZE(GpuRay, 64);

// What a ray hit, as VKRAY_BINDING_HITS holds it: a primitive slot (the host knows each slot's
// mesh and triangle, or sphere), or one of these tagged indices.
#define VKRAY_HIT_NONE 0xffffffffu
#define VKRAY_HIT_SPHERE_APART 0x40000000u  // | index of a sphere tested one by one (VKRAY_BINDING_SPHERES)
#define VKRAY_HIT_PLANE 0x80000000u         // | index of the plane
#define VKRAY_HIT_INDEX_MASK 0x3fffffffu
// In a shader's list of first hits alone, never written: the far root of a sphere whose near root is
// listed too (its normal is the far root's). Slots stay below it.
#define VKRAY_HIT_FAR_ROOT 0x20000000u

// A sphere tested one by one: centre, radius in w.
struct GpuSphere {
  GpuPoint center_radius;
};
VKRAY_CHECK_SIZE(GpuSphere, 32);

// A plane: its unit normal with its height above the camera, dot(normal, point - camera), written
// by the host in double before every render (a handful of planes: rewriting them costs nothing, and
// the height is then exact to its own rounding at any distance from the scene's centre); then the
// normal with w = dot(normal, point - anchor), which only the plain float coordinate variants read
// (they subtract dot(normal, camera) in float, as a textbook shader does).
struct GpuPlane {
  GpuPoint normal_height;
  GpuPoint normal_offset;
};
VKRAY_CHECK_SIZE(GpuPlane, 64);

// A primitive the tree holds (or a triangle tested by brute force), 16 bytes: indices into the
// vertex buffer (VKRAY_BINDING_VERTICES), where each distinct position of the scene is stored
// once, so a mesh of n vertices and about 2n triangles takes 16 + 32 / 2 bytes a triangle for
// both, 59.5 for the bunny with its tree and normals, where three GpuPoints a triangle took 107.6.
// Every triangle that shares a vertex reads the same texels: bit-identical values, as the
// watertight test needs.
// - Triangle: its three vertices (in lexicographic order of position: copies of a triangle with
//   another winding or first vertex then test the same arithmetic), w = VKRAY_PRIMITIVE_TRIANGLE.
//   Its unit geometric normal is in the normal buffer at the same slot, computed in double on the
//   host so that needle triangles get an accurate one; the shader reads it only for the winner.
// - Sphere: x = the vertex holding (centre, radius), w = VKRAY_PRIMITIVE_SPHERE.
// Above the kind, w holds the primitive's mask (its mesh's, or the sphere's) from bit
// VKRAY_PRIMITIVE_MASK_SHIFT: in the texel a walk reads for the primitive anyway.
// Primitives are stored in the order of the BVH's leaves, so a leaf is a contiguous range of slots.
struct GpuPrimitive {
  uvec4 indices;
};
VKRAY_CHECK_SIZE(GpuPrimitive, 16);
#define VKRAY_PRIMITIVE_TRIANGLE 0u
#define VKRAY_PRIMITIVE_SPHERE 1u
// x = the instance's index (VKRAY_BINDING_INSTANCES), y = its mesh's root node; only in the world's tree.
#define VKRAY_PRIMITIVE_INSTANCE 2u
#define VKRAY_PRIMITIVE_KIND_BITS 0xffu
#define VKRAY_PRIMITIVE_MASK_SHIFT 8
// A triangle whose stored (canonical) order of vertices runs against its winding: its solid angle's
// sign is turned (the winding number alone reads it; rays take either side alike). Above the mask.
#define VKRAY_PRIMITIVE_FLIPPED 0x10000u
#define VKRAY_TEXELS_PER_POINT 2
// A triangle's normal: (x, y, z, 0) in float32 shaders; in float64 shaders a GpuPoint holding the
// doubles (x, y, z, 0), two texels.
#define VKRAY_TEXELS_PER_NORMAL_FLOAT32 1
#define VKRAY_TEXELS_PER_NORMAL_FLOAT64 2

// The brute-force path tests triangles in batches of this many, padded with all-zero triangles
// (never hit: their determinant is 0), in one loop iteration with a constant trip count the
// compiler unrolls. This matters on lavapipe, whose loop cap counts iterations.
#define VKRAY_TRIANGLE_BATCH 8

// BVH: binary, with both children's boxes stored in their parent, so one node fetch gives a ray
// both slab tests and the nearer child. 64 bytes, one cache line. Per axis: (lower of child 0,
// lower of child 1, upper of child 0, upper of child 1). Boxes are float32, relative to the anchor,
// rounded outward from the primitives in double.
struct GpuBvhNode {
  vec4 bounds_x;
  vec4 bounds_y;
  vec4 bounds_z;
  uvec4 children;  // x, y: child references; z, w: 0
};
VKRAY_CHECK_SIZE(GpuBvhNode, 64);

// An instance (VKRAY_TEXELS_PER_INSTANCE_* texels): what takes a ray into its mesh's coordinates, where the mesh's triangles (their
// vertices relative to the mesh's own origin) and tree (nodes after the world's, boxes in the mesh's
// coordinates) are stored once for all its instances. A ray (o, d) becomes (A (o - T), A d), A the
// inverse of the instance's linear map and T its translation relative to the anchor: the same t in
// both, so one bound serves both walks; o - T is formed first, from hi and lo parts as positions
// are, so it is accurate to float32 relative to the ray's distance from the instance however far
// both lie from the anchor.
// - float32 shaders: rows k = 0, 1, 2 of A in texel k's xyz, T's hi part in their w, T's lo part in
//   texel 3's xyz. 64 bytes.
// - float64 shaders: the rows of A, each with T's component in w, as three GpuPoints. 96 bytes.
// The world tree's record of an instance holds its index and its mesh's root node
// (VKRAY_PRIMITIVE_INSTANCE).
#define VKRAY_TEXELS_PER_INSTANCE_FLOAT32 4
#define VKRAY_TEXELS_PER_INSTANCE_FLOAT64 6
// What an instance hit reads for no instance: the world's own triangles and spheres.
#define VKRAY_NO_INSTANCE 0xffffffffu

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

// Coincident surfaces. A sphere or triangle wins over the nearest plane only where its hit point
// lies off the plane by more than VKRAY_COINCIDENT_GAP of its own distance: where a triangle lies in
// a plane or a sphere touches one, the two distances differ only by rounding, and without this
// rule whichever rounding favours would win, pixel by pixel. The shader and the reference
// (engine/reference/reference.cpp) both apply it, so the plane wins on every pixel in both. The rounding of
// either hit point off the plane is within a few float32 ulps of the distance at any angle (the
// error of n.d scales t, not the height), so 2^-20 (16 ulps) separates rounding from real gaps.
// VKRAY_PRIMITIVE_T_MAX is then the bound for spheres and triangles behind a plane hit at t with
// slope |n.d|: (t - t_primitive) * slope <= gap * t_primitive.
#define VKRAY_COINCIDENT_GAP (1.0 / 1048576.0)
#define VKRAY_PRIMITIVE_T_MAX(t, slope) ((t) * (slope) / ((slope) + VKRAY_COINCIDENT_GAP))

// Per-dispatch camera and image parameters (push constants; 128 bytes, the least every Vulkan
// device offers). The camera basis is computed in double on the host; the shader only evaluates
// direction = x*right + y*up + forward_scaled. `camera` holds 32-bit words:
// - float32 shaders: origin hi, origin lo (relative to the anchor, split as in GpuPoint), right,
//   up, forward_scaled (= -plane_distance * forward) as floats; the sixth is unused.
// - float64 shaders: the twelve doubles origin.xyz, right.xyz, up.xyz, forward_scaled.xyz.
#define VKRAY_CAMERA_WORDS 6
struct RayGenParams {
  uvec4 camera[VKRAY_CAMERA_WORDS];
  // Width, height, first row of this tile, rows in this tile. With RAY_INPUT the rays are laid out
  // as rows of `width` and `height` is the number of rays.
  uvec4 image;
  // Spheres, planes, triangle slots and (w's low byte) the search mode, read by the generic variant
  // only; in w above them, from bit VKRAY_RAY_MASK_SHIFT, the call's ray mask (VKRAY_SPEC_MASKS).
  uvec4 counts;
};
VKRAY_CHECK_SIZE(RayGenParams, 128);
#define VKRAY_SEARCH_MODE_BITS 0xffu
#define VKRAY_RAY_MASK_SHIFT 8
// VKRAY_RAY_INPUT_CALLER_DIRECTIONS: camera[5] holds the VKRAY_CALLER_* bits (x), and the mesh ids
// of the first sphere tested one by one (z) and of the first plane (w), as HitSources has them.
#define VKRAY_CALLER_WRITE_T 1u
#define VKRAY_CALLER_WRITE_NORMAL 2u
#define VKRAY_CALLER_WRITE_MESH_ID 4u
#define VKRAY_CALLER_WRITE_PRIMITIVE_ID 8u
#define VKRAY_CALLER_IN_ORDER 16u
#define VKRAY_CALLER_BY_DIRECTION 32u

// direction_order.comp: its bindings, passes (VKRAY_SPEC 0) and push constants (count, bits a side
// of direction_key's cells, the keys 4^bits).
#define VKRAY_ORDER_BINDING_RAYS 0    // texels, RGBA32UI: the caller's rays (as VKRAY_BINDING_CALLER_RAYS)
#define VKRAY_ORDER_BINDING_CELLS 1   // storage buffer: a count, then a first place, a key
#define VKRAY_ORDER_BINDING_RANKS 2   // storage buffer: a ray's key and rank among that key's rays
#define VKRAY_ORDER_BINDING_ORDER 3   // storage buffer: the rays' indices in order (VKRAY_BINDING_RAY_ORDER)
#define VKRAY_ORDER_PASS_COUNT 0
#define VKRAY_ORDER_PASS_SCAN 1
#define VKRAY_ORDER_PASS_PLACE 2
#define VKRAY_ORDER_GROUP_SIZE 256
#define VKRAY_ORDER_MAX_BITS 9
struct DirectionOrderParams {
  uvec4 sizes;
};
VKRAY_CHECK_SIZE(DirectionOrderParams, 16);

// The nearest and farthest finite depth of an image as the bits of positive floats, which order
// as unsigned integers do: the shader folds its hits in with atomicMin/atomicMax. Reset to
// (+infinity, 0) before a dispatch; far_bits stays 0 when nothing was hit.
struct DepthRangeBits {
  uvec4 near_far;  // x: nearest, y: farthest; z, w: 0
};
VKRAY_CHECK_SIZE(DepthRangeBits, 16);

// The 8-bit preview of an output (engine/io/preview.hpp), as shaders/preview.comp applies it. A ramp
// maps a float to a byte: the byte of v is the largest k with thresholds[k] <= v (thresholds[0] is
// -infinity, thresholds ascend), found by a binary search of 8 comparisons. Comparisons are exact,
// so the GPU picks the same byte as the host for the same float, whatever its arithmetic.
#define VKRAY_RAMP_LEVELS 256
#define VKRAY_PREVIEW_BINDING_VALUES 0   // storage image, RGBA32F: what the render wrote
#define VKRAY_PREVIEW_BINDING_PICTURE 1  // storage image, RGBA8UI: the 8-bit picture
#define VKRAY_PREVIEW_BINDING_RAMPS 2    // uniform buffer: GpuPreviewRamps
#define VKRAY_PREVIEW_DEPTH 0            // grey from ramp 0 on -depth; misses black
#define VKRAY_PREVIEW_NORMAL 1           // each component through ramp 0; misses (zero normal) black
#define VKRAY_PREVIEW_UV 2               // u, v and 0 through ramp 0 inside the unit disk, ramp 1 outside
// Two ramps of VKRAY_RAMP_LEVELS thresholds, four to a vec4 (std140 arrays have a 16-byte stride).
struct GpuPreviewRamps {
  vec4 thresholds[2 * VKRAY_RAMP_LEVELS / 4];
};
VKRAY_CHECK_SIZE(GpuPreviewRamps, 2048);
// Push constants of preview.comp.
struct PreviewParams {
  uvec4 image;  // width, height, VKRAY_PREVIEW_*, 1 to store blue first (BGRA swapchains)
};
VKRAY_CHECK_SIZE(PreviewParams, 16);

#ifdef __cplusplus
}  // namespace vkray::gpu
#endif
#undef VKRAY_CHECK_SIZE
#endif  // VKRAY_GPU_LAYOUT_H
