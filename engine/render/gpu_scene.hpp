// Conversion of the double-precision scene into the float32 arrays the shader reads.
#pragma once

#include "engine/render/search.hpp"
#include "engine/scene/bvh.hpp"
#include "engine/scene/camera.hpp"
#include "engine/scene/scene.hpp"
#include "engine/vulkan/shader_variant.hpp"
#include "shaders/gpu_layout.h"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace vkray {

struct GpuSceneOptions {
  PrimitiveSearch search = PrimitiveSearch::automatic;
  // automatic takes the packet walk for a tree shallow enough for its stack in registers
  // (VKRAY_STACK_REGISTERS_MAX); the renderer sets this where the device and shader favour it.
  bool packet_walk = false;
  BvhBuildOptions bvh;
};

// The object and primitive behind each value of VKRAY_BINDING_HITS (host memory only).
struct HitSources {
  std::vector<ObjectPrimitive> slots;  // by primitive slot; none for padding
  uint32_t first_sphere_object = 0;    // ObjectPrimitive::object of the first sphere
  uint32_t first_plane_object = 0;     // and of the first plane
  ObjectPrimitive operator()(uint32_t hit) const;
};

// A GpuScene by kind and count: what the shader is specialized on besides the tree's depth. Known
// before anything is built (plan_gpu_scene), so that the pipeline can be made while the tree builds,
// and read off the built scene (GpuScene::shape), which differs from the plan only where building
// shows otherwise: zero-area triangles dropped, a tree too deep for the packet walk.
struct GpuSceneShape {
  PrimitiveSearch search = PrimitiveSearch::brute_force;
  uint32_t spheres_apart = 0;  // spheres tested one by one
  uint32_t planes = 0;
  uint32_t brute_force_triangle_slots = 0;
  // Brute force with instances: the iterations of its loops over their records and their meshes'
  // batches (what a device that stops loops counts; 0 in plan_gpu_scene, which has no meshes).
  uint32_t brute_force_placed_iterations = 0;
  bool tree_has_triangles = false;
  bool tree_has_spheres = false;
  bool masks = false;  // Scene::has_masks (VKRAY_SPEC_MASKS)
  bool instances = false;  // the scene has some (VKRAY_SPEC_INSTANCES)
  bool operator==(const GpuSceneShape&) const = default;
};

struct RefitState;     // gpu_scene.cpp
struct InstanceLevel;  // gpu_scene.cpp

struct GpuScene {
  // Every position on the GPU is stored relative to this point (see GpuPoint in gpu_layout.h):
  // scene_anchor, the centre of the scene's box on a grid, so that the split into hi and lo float
  // parts covers the scene with about the fewest bits; the world origin for float64 shaders and the
  // absolute-coordinates variant.
  glm::dvec3 anchor{0.0};
  Precision precision = Precision::float32;
  // The largest distance from the anchor of a sphere's surface or a mesh vertex (0 without either).
  double radius = 0.0;
  std::vector<gpu::GpuPlane> planes;
  // Spheres tested one by one: all of them without the tree; with it, a handful beside triangles
  // (the tree then holds the triangles alone).
  std::vector<gpu::GpuSphere> spheres;
  // With the tree: every triangle and sphere in leaf order. Without: the triangles, padded to whole
  // VKRAY_TRIANGLE_BATCHes with all-zero ones (vertex 0 three times: never hit). Zero-area
  // triangles are left out (no ray can hit them). See GpuPrimitive in gpu_layout.h.
  std::vector<gpu::GpuPrimitive> primitives;
  // What the primitives index: each distinct vertex position once, and the tree's spheres.
  std::vector<gpu::GpuPoint> vertices;
  // The triangles' unit normals by primitive slot, VKRAY_TEXELS_PER_NORMAL_* texels each (zero for
  // spheres and padding).
  std::vector<glm::vec4> normal_texels;
  std::vector<gpu::GpuBvhNode> bvh_nodes;  // empty without the tree
  // Where the scene has masks (Scene::has_masks): the masks of `spheres`, then of `planes`, a texel
  // each (VKRAY_BINDING_APART_MASKS); the primitives carry theirs. Empty without.
  bool masks = false;
  std::vector<glm::uvec4> apart_masks;
  // The instances (VKRAY_TEXELS_PER_INSTANCE_* texels each; see gpu_layout.h), their meshes' triangles
  // (slots after the world's tree's) and trees (nodes after it). Empty without.
  std::vector<glm::vec4> instance_texels;
  // With instances, what place_instances builds the world's tree again from: the world's own
  // primitives, each instanced mesh's box and root, and the slots and nodes the world's tree may take.
  std::shared_ptr<const InstanceLevel> instance_level;
  // Ray queries: each mesh's triangles are the consecutive slots [first, first + count), in Morton
  // order of their centroids (lavapipe's builder makes far better structures from ordered input:
  // the bunny at 1920x1080 traced 0.65 s a frame so against 72-86 s in the OBJ's order); the
  // spheres, where not tested apart, follow the triangles, with their float boxes (min x, y, z,
  // max x, y, z, rounded outward) for the device's procedural geometry. An instanced mesh's range
  // (`placed`) holds it in its own coordinates, for the top-level structure to place.
  struct SlotRange {
    uint32_t first = 0, count = 0;
    uint32_t mesh = 0;  // the scene's
    bool placed = false;
  };
  std::vector<SlotRange> structure_meshes;
  SlotRange structure_spheres;
  std::vector<std::array<float, 6>> sphere_boxes;
  HitSources hit_sources;
  // Edges on the tree's longest root-to-leaf path; with instances, the most entries the walk's stack
  // may hold: the world's depth, three for an instance entered (see nearest_primitive_in_tree), and
  // the deepest mesh tree's.
  uint32_t bvh_depth = 0;
  PrimitiveSearch search = PrimitiveSearch::brute_force;  // never automatic here
  bool tree_has_triangles = false;
  bool tree_has_spheres = false;
  uint32_t triangle_count = 0;  // kept triangles
  double bvh_build_ms = 0.0;
  // The tree's shape (its nodes and which primitive each leaf slot holds), kept for a refit: a scene
  // whose vertices moved gets the same tree with its boxes recomputed (make_gpu_scene's `refit`).
  std::optional<Bvh> tree;
  bool refitted = false;  // the tree is `refit`'s, its boxes recomputed; not built
  // For a refit in place (refit_in_place): each mesh vertex's index in `vertices` (no_vertex where
  // no kept triangle uses it), and the triangles of zero area left out.
  static constexpr uint32_t no_vertex = UINT32_MAX;
  std::vector<std::vector<uint32_t>> stored_vertex;
  std::vector<ObjectPrimitive> left_out;
  // What refit_in_place keeps from one call to the next (made at its first): the double positions,
  // the slots' and nodes' boxes, which slots each mesh's triangles hold, and the tree's parents, so
  // that a later call redoes only a moved mesh's part. A copy of the scene starts without it (its
  // first refit then redoes everything): two scenes never share it.
  class RefitStateHandle {
   public:
    RefitStateHandle();
    RefitStateHandle(const RefitStateHandle&);
    RefitStateHandle& operator=(const RefitStateHandle&);
    RefitStateHandle(RefitStateHandle&&) noexcept;
    RefitStateHandle& operator=(RefitStateHandle&&) noexcept;
    ~RefitStateHandle();  // these where RefitState is complete (gpu_scene.cpp)
    std::unique_ptr<RefitState> state;
  };
  RefitStateHandle refit_state;
  // The items of each array the last refit_in_place rewrote, [first, end): from the first to the
  // last, what an upload writes (other meshes' items may lie between them).
  struct ItemRange {
    size_t first = SIZE_MAX, end = 0;
    void add(size_t item) { first = std::min(first, item), end = std::max(end, item + 1); }
    bool empty() const { return end <= first; }
  };
  struct Rewritten {
    ItemRange vertices, slots, nodes;
    bool mesh_alone = false;  // only one mesh's part: the spheres and planes left as they were
    bool instances = false;   // the instances' texels (place_instances)
  };
  Rewritten rewritten;

  // A tree or the device's structures find the primitives: no brute-force loop.
  bool has_tree() const { return search != PrimitiveSearch::brute_force; }
  GpuSceneShape shape() const;
  // Triangle slots the brute-force loop walks (0 with the tree): the world's own, whole batches;
  // with instances, their records follow (make_gpu_scene), and the iterations walking them.
  uint32_t brute_force_triangle_slots() const { return has_tree() ? 0 : world_triangle_slots; }
  uint32_t world_triangle_slots = 0;
  uint32_t brute_force_placed_iterations = 0;
  // Bytes of device memory the triangles, spheres and their tree take.
  size_t geometry_bytes() const {
    return spheres.size() * sizeof(gpu::GpuSphere) + primitives.size() * sizeof(gpu::GpuPrimitive) +
           vertices.size() * sizeof(gpu::GpuPoint) + normal_texels.size() * sizeof(glm::vec4) +
           bvh_nodes.size() * sizeof(gpu::GpuBvhNode) + instance_texels.size() * sizeof(glm::vec4);
  }
};

// Device bytes of each kind of geometry record (`vkray info`): a mesh of n vertices and about 2n
// triangles takes slot + normal + vertex / 2 bytes a triangle, plus its share of the tree's nodes.
struct GeometryLayout {
  size_t primitive_slot = sizeof(gpu::GpuPrimitive);
  size_t normal_float32 = VKRAY_TEXELS_PER_NORMAL_FLOAT32 * sizeof(glm::vec4);
  size_t normal_float64 = VKRAY_TEXELS_PER_NORMAL_FLOAT64 * sizeof(glm::vec4);
  size_t vertex = sizeof(gpu::GpuPoint);
  size_t tree_node = sizeof(gpu::GpuBvhNode);
};

// What make_gpu_scene will build for `scene`, as far as it can be known without building it (see
// GpuSceneShape): every triangle counted as kept, the tree shallow enough for the packet walk.
GpuSceneShape plan_gpu_scene(const Scene& scene, const GpuSceneOptions& options);

// A scene built before, whose tree make_gpu_scene refits where the scene it is given keeps the same
// primitives (the same triangles of non-zero area, the same spheres): only vertices moved.
struct RefitSource {
  const Bvh& tree;
  const HitSources& slots;  // what each slot of the tree's leaves held
};

// Positions encoded for `shader`'s precision and coordinates; `extent` is scene_extent(scene), found
// here where not given. With `refit`, its tree's shape where it fits (GpuScene::refitted), else a new tree.
GpuScene make_gpu_scene(const Scene& scene, const GpuSceneOptions& options = {}, const ShaderVariant& shader = {},
                        const std::optional<SceneExtent>& extent = std::nullopt, const std::optional<RefitSource>& refit = std::nullopt);

// `gpu`, a tree's scene that make_gpu_scene made for `scene` before its vertices moved (the same
// meshes, triangles and spheres), brought up to `scene` where it lies: every stored position, triangle
// record, normal and box found again from `extent` (scene_extent(scene)) on every core, the tree's
// shape kept and its boxes refitted; the same arrays as make_gpu_scene's with that tree would hold,
// their vertices in their former order. With `moved_mesh`, the only mesh that moved since the last
// call: where the anchor stayed and the mesh shares no stored vertex with another, only its vertices,
// its triangles' slots and the nodes above them (GpuScene::rewritten says which). False, `gpu` then
// unusable, where it cannot be: a triangle's area became or stopped being zero, or vertices that
// shared a stored position no longer coincide.
bool refit_in_place(GpuScene& gpu, const Scene& scene, const ShaderVariant& shader, const SceneExtent& extent,
                    std::optional<uint32_t> moved_mesh = std::nullopt);

// `gpu`, made by make_gpu_scene for a scene with instances, brought up to where `scene`'s instances
// now stand (the same instances of the same meshes; nothing else moved): the world's tree built
// anew over its own primitives and the instances' placed boxes, in the slots and nodes it held
// (GpuScene::rewritten says which), and the instances' texels rewritten. The meshes' trees stay as
// they are: the top level alone is rebuilt, as Vulkan's and Embree's instances are. For ray queries
// the texels alone: the device's top-level structure is the renderer's to build.
void place_instances(GpuScene& gpu, const Scene& scene);

// By mesh, the root node of an instanced mesh's tree (empty without instances): where the point
// queries' winding caps of each mesh start.
std::span<const uint32_t> instanced_mesh_roots(const GpuScene& gpu);

// Texels a slot's normal takes in GpuScene::normal_texels (VKRAY_TEXELS_PER_NORMAL_*).
size_t texels_per_normal(Precision precision);

// Every plane's normal_height for a camera at `origin` (see GpuPlane): `scene_planes` are the
// scene's, in the same order as `planes`.
void set_plane_heights(std::vector<gpu::GpuPlane>& planes, const std::vector<Plane>& scene_planes,
                       const glm::dvec3& origin, Precision precision);

// A given ray as the shader reads it (GpuRay): the origin relative to `anchor`, the direction
// normalized in double, the end of its range (+infinity for none).
gpu::GpuRay encode_ray(const glm::dvec3& origin, const glm::dvec3& direction, double range_end,
                       const glm::dvec3& anchor, Precision precision);
// RayGenParams.counts: what the generic shader variant reads instead of specialization constants,
// and the rays' mask.
glm::uvec4 run_time_counts(const GpuScene& scene, Mask ray_mask);

// Whether a float32 camera-relative shader must add the lo parts of positions for a camera at
// `origin`: only while the camera is within 2 radii of the anchor. Farther, everything is at least
// half the camera's distance from the anchor away from it, and hi parts alone are within 1.5 eps of
// that distance: below what the ray's own rounding moves a hit, for half the texel fetches
// (VKRAY_SPEC_LO_PARTS).
bool needs_lo_parts(const glm::dvec3& anchor, double radius, const glm::dvec3& origin);

// Push constants for one tile of rows of a width x height image.
gpu::RayGenParams make_ray_gen_params(const CameraBasis& camera, const glm::dvec3& anchor, Precision precision,
                                      uint32_t width,
                                      uint32_t height, uint32_t first_row, uint32_t row_count,
                                      const glm::uvec4& counts);

}  // namespace vkray
