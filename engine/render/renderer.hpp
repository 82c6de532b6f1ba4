// The render core: built once per scene (geometry uploaded once, pipelines made on first use), then
// rendered any number of times with a new camera, image size or set of outputs.
#pragma once

#include "engine/frame.hpp"
#include "engine/host_memory.hpp"
#include "engine/point_outputs.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/vulkan/image_target.hpp"
#include "engine/scene/scene.hpp"
#include "engine/vulkan/shader_variant.hpp"

#include <glm/mat4x4.hpp>

#include <array>
#include <memory>
#include <span>
#include <vector>

namespace vkray {

// How cast_rays traced the rays it was given (see Renderer::cast_rays).
enum class GivenRayWalk {
  none,                  // no rays given
  one_by_one,            // each ray walked the tree on its own
  packets_in_place,      // rays from one origin listed as an image's rows: packets of its 8x8 blocks
  packets_in_order,      // rays from one origin whose list keeps neighbours together: packets of 64 consecutive ones
  packets_by_direction,  // rays from one origin in another order: packets of 64 ordered by direction
};

// "one by one", "packets in place", "packets in order", "packets by direction" ("none" for none).
const char* given_ray_walk_name(GivenRayWalk walk);

struct RenderTimings {
  double upload_ms = 0.0;          // scene conversion and upload (once, in the constructor), BVH build included
  double bvh_build_ms = 0.0;       // of which building the BVH
  double structures_ms = 0.0;      // of which the device building its acceleration structures (ray queries)
  double pipeline_ms = 0.0;        // pipeline creation (first render with a given set of outputs)
  // The pipeline made on a second thread while the tree was built and the scene uploaded
  // (RendererOptions::first_aovs), in the constructor: its creation time; 0 where none was.
  double pipeline_beside_upload_ms = 0.0;
  bool has_gpu_times = false;      // the device has timestamps; else dispatch_gpu_ms is not measured
  double dispatch_gpu_ms = 0.0;    // GPU time of the ray-casting dispatches (timestamp queries)
  double readback_ms = 0.0;        // copying results back into the Frame (or the few the host reads)
  uint64_t readback_bytes = 0;     // copied on the device into host-visible memory (staging), all dispatches
  uint64_t readback_in_place_bytes = 0;  // of those, copied straight into the frame's planes: no host copy
  double rays_ms = 0.0;            // cast_rays: ordering the rays and writing them for the device
  GivenRayWalk given_walk = GivenRayWalk::none;  // how cast_rays walked the tree
  bool rays_in_place = false;      // cast_rays_in_place: the device read the rays and wrote the hits in the caller's memory
  double order_gpu_ms = 0.0;       // of dispatch_gpu_ms, ordering the rays by direction on the device
  uint32_t tiles = 0;              // dispatches the image was split into
  double longest_dispatch_ms = 0.0;  // GPU time of the longest (wall time where no timestamps)
  uint64_t unfinished_rays = 0;    // rays that ran out of the device's loop budget, finished on the CPU
  double cpu_finish_ms = 0.0;      // time spent finishing them
  // set_vertices: its whole time (the scene converted, its tree refitted or built, the upload),
  // whether the tree kept its shape (refitted) or was built anew, and whether only the moved mesh's
  // part of it was redone (refit_in_place's mesh_alone).
  double scene_update_ms = 0.0;
  bool tree_refitted = false;
  bool refit_mesh_alone = false;
  // A later engine call's times and counts added, for a call made of several (the walk and the
  // constructor's figures stay this one's).
  void add(const RenderTimings& later);
};

// What the constructor put on the device.
struct SceneStats {
  uint32_t triangles = 0;          // kept (non-degenerate) triangles
  uint32_t spheres = 0;
  size_t geometry_bytes = 0;       // device memory of the triangles, spheres and their BVH
  uint32_t bvh_nodes = 0;
  uint32_t bvh_depth = 0;
  PrimitiveSearch search = PrimitiveSearch::brute_force;
  uint32_t loop_budget = 0;        // iterations a tree walk may take on this device; 0: no limit
};

// What each of a batch of given rays hit, in the rays' order.
// With first hits (Renderer::cast_rays' `hits` above 1), entry ray * hits_per_ray + k holds ray's
// k-th hit, nearest first: count is the rays' count times hits_per_ray.
struct RayHits {
  size_t count = 0;
  uint32_t hits_per_ray = 1;
  UninitializedVector<float> t;         // distance along the unit direction to the nearest hit; +inf on a miss
  UninitializedVector<float> normal;    // 3 planes (all x, then y, then z): unit normal facing the ray, 0 on a miss
  UninitializedVector<uint32_t> object;     // ObjectPrimitive::object, no_object on a miss
  UninitializedVector<uint32_t> primitive;  // ObjectPrimitive::primitive, no_object on a miss
  // In a scene with instances, the instance placing the mesh hit (no_object for none); empty without.
  UninitializedVector<uint32_t> instance;
  // The float64 shader's distances and normals as it computed them, before t and normal round them;
  // empty for the float32 shader.
  UninitializedVector<double> t64, normal64;
  // HitQuery::count alone: how many surfaces each ray crosses (Renderer::count_intersections); the
  // arrays above are then empty. HitQuery::any writes `object` alone (but for rays the host
  // finished: Renderer::occluded reads no more).
  UninitializedVector<uint32_t> crossings;
  // Room for `ray_count` rays, their values unset: cast_rays stores every one.
  void allocate(size_t ray_count, bool doubles = false, bool instances = false);
  void store(size_t ray, double distance, const glm::dvec3& unit_normal, ObjectPrimitive source,
             uint32_t placing_instance = no_object);
};

// A caller's arrays for cast_rays_in_place, one entry a ray in the rays' order (x, y, z together
// for the normal); a null array is not written.
struct HitArrays {
  float* t = nullptr;              // along the unit direction; +inf on a miss
  float* normal = nullptr;         // the unit normal facing the ray; 0 on a miss
  uint32_t* object = nullptr;      // ObjectPrimitive::object; no_object on a miss
  uint32_t* primitive = nullptr;   // ObjectPrimitive::primitive; no_object on a miss
};

// The longest a dispatch may run, by default. A display-attached GPU is reset when one runs for
// about 2 s (Windows' TDR; Linux desktops have similar watchdogs): a tenth of that leaves room for
// the estimate's error and slower devices, and costs a submission or two a frame.
inline constexpr double default_dispatch_budget_ms = 200.0;

struct RendererOptions {
  // Upper bound on the bytes of one output buffer; the image is split into tiles of rows to stay
  // under it and under the device's maxStorageBufferRange (a tile has at least one row, whatever
  // the bound). 0: the device limit alone.
  uint64_t max_tile_bytes = 0;
  // Dispatches are sized so that none runs longer than this, measured as they run: the first
  // covers a small part of the image, each later one as many rows as the slowest rows so far let
  // fit in half the budget (at most sixteen times its predecessor's). 0: tiles by size alone.
  double dispatch_budget_ms = default_dispatch_budget_ms;
  GpuSceneOptions scene;
  // Iterations one ray's tree walk may take before the CPU finishes it; 0: as many as the device
  // allows. Tests lower it to force that path.
  uint32_t loop_budget = 0;
  ShaderVariant shader;
  // The outputs the first render will ask for, of the scene's camera into buffers: where known before
  // the tree is built (the packet walk, whose pipeline the tree's depth does not change), that
  // pipeline is made on a second thread while the tree builds and the scene uploads. Empty: every
  // pipeline is made on first use.
  AovSet first_aovs;
};

class Renderer {
 public:
  Renderer(GpuDevice& device, const Scene& scene, RendererOptions options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders `camera` at width x height; only the outputs in `aovs` are computed and read back
  // (every output with the generic shader variant).
  Frame render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs);

  // Renders `aov` of `camera` into the storage-image target, at its size: the same values render()
  // returns, left on the device (rays past the loop budget are finished on the CPU and written in).
  // Returns the range of finite depths when `aov` is depth. Takes a float32 shader specialized on
  // its outputs (not the generic or float64 variants).
  DepthRange render(const Camera& camera, Aov aov, ImageTarget& target);

  // The GPU time one pass over `camera`'s whole image takes, averaged over `repeats` passes back to
  // back in one submission with nothing read back (wall time where the device has no timestamps):
  // the device's throughput with its clocks up. Frames rendered one at a time, each waited for and
  // read back, leave a GPU idle most of the time, and it slows down (an H100 ran identical pipelines
  // at 0.68 and 3.8 ms, its clock at 1980 and 345 MHz). The outputs are left unread.
  double sustained_dispatch_ms(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs, uint32_t repeats);

  // Traces each ray (checked first: check_given_rays, check_ray_ranges) to its nearest hit within
  // its range, with the precision contract of images: the origin relative to the scene's anchor, the
  // direction normalized in double, then rounded as a camera's are. With `hits` above 1 (at most
  // VKRAY_HITS_MAX), its first `hits` hits in order of distance (RayHits::hits_per_ray): the first
  // of the crossings count_intersections counts, each sphere's far root too, an edge passed
  // exactly through once; misses past the last. They walk one by one, in one pass along the ray.
  RayHits cast_rays(std::span<const GivenRay> rays, const RayRanges& ranges = {}, uint32_t hits = 1);

  // cast_rays for rays from one origin with no ranges, their hits written straight into the
  // caller's arrays: the device reads `rays` and writes `into` where they lie (host memory it
  // imports: VK_EXT_external_memory_host), and the shader normalizes the directions and turns
  // primitive slots into ids, so that the host touches no ray. Rays the shader finds from another
  // origin or with a bad direction, or leaves unfinished, are cast again by cast_rays (which checks
  // them: InputError names the first bad one). Returns false, having written nothing, where this way
  // does not apply (a device without the import or fast doubles, the float64 shader, ray queries,
  // rays from several origins, arrays the device cannot bind); cast_rays then does the work.
  bool cast_rays_in_place(std::span<const GivenRay> rays, const HitArrays& into);
  // Whether cast_rays_in_place takes rays here at all: the device imports host memory, and the
  // float32 shader takes double edge functions (where doubles are fast: lavapipe, the H100 and H200),
  // the variant that reads the caller's doubles.
  bool casts_in_place() const;

  // Whether each ray hits anything within its range (1) or not (0): an occlusion query, whose walk
  // stops at the first hit it meets. The same rays, ranges and precision contract as cast_rays.
  std::vector<uint8_t> occluded(std::span<const GivenRay> rays, const RayRanges& ranges = {});

  // How many times each ray crosses a surface within its range: every triangle, sphere root and
  // plane it meets, as ReferenceScene::count_crossings counts them (an edge or vertex passed exactly
  // through counts once), so that the count is odd where the ray starts inside a closed mesh. The
  // walk runs one by one to the end of each range. The same rays, ranges and mask as cast_rays; the
  // first call makes its pipeline.
  std::vector<uint32_t> count_intersections(std::span<const GivenRay> rays, const RayRanges& ranges = {});

  // Point queries, each point's position in world coordinates (checked: finite and within
  // max_coordinate), with the precision contract of rays: positions relative to the point from their
  // hi and lo parts. The nearest point of what rays of the ray mask can meet, within
  // `max_distances` (none: no bound; one value for every point, or one a point; +inf: none), as
  // PointHits: its distance, its offset from the point and what it lies on (an instance's
  // triangles measured in the world's coordinates: an unevenly scaled placement's nearest point is
  // the world's). Walks the tree nearest box first (or every primitive, with brute force); a
  // renderer of ray queries has no tree of its own and refuses (InputError).
  PointHits closest_points(std::span<const glm::dvec3> points, std::span<const double> max_distances = {});
  // The generalized winding number at each point (see ReferenceScene::winding_number), in
  // PointHits::distance: the tree's caps (made at the first call) answer exactly.
  PointHits winding_numbers(std::span<const glm::dvec3> points);

  // Makes, side by side, every pipeline that render of `camera` at width x height with depth and
  // normal, cast_rays and occluded can take (one by one and, where the packet walk runs, in packets
  // from one origin; with and without the lo parts of positions), and runs each once (the render at
  // its size, so its buffers are made too; the rays a few), so that no later call pays for a first
  // use: lavapipe makes each in 0.2 to 0.6 s and compiles it at its first dispatch. Its time goes to
  // timings().pipeline_ms; the call timings its runs left are cleared.
  void prepare_pipelines(const Camera& camera, uint32_t width, uint32_t height);

  // The mask of every later call's rays (see Mask): a ray hits only the meshes, spheres and planes
  // whose mask shares a bit with it; every bit by default. Where no object of the scene has a mask
  // the shaders test none, and any mask sees everything. Throws InputError for 0, which would see
  // nothing.
  void set_ray_mask(Mask mask);

  // Moves the vertices of mesh `mesh` (the scene's meshes[mesh], its mesh_id) to `positions`, one a
  // vertex in its order (a deforming mesh: a skinned arm, cloth): the next call renders the moved
  // scene, exactly as a Renderer made from it would. Its tree keeps its shape and only its boxes are
  // recomputed (a refit) while the same triangles keep a non-zero area; else it is built anew. From
  // the third call on, only this mesh's vertices, slots and the nodes above them are redone (and the
  // span of each array from the first to the last of them uploaded) where the anchor stays (the
  // centre of the scene's box, which an object moving inside a room's walls keeps; the world origin
  // in double precision) and the mesh shares no vertex position with another mesh (refit_mesh_alone).
  // timings() then says which (tree_refitted) and what it took (scene_update_ms). Throws InputError
  // for a mesh out of range, a count other than the mesh's or a coordinate not finite or beyond
  // max_coordinate, the scene unchanged.
  void set_vertices(uint32_t mesh, std::span<const glm::dvec3> positions);

  // The scene as the renderer holds it (with the vertices set_vertices moved).
  // New placements for some of the scene's instances (Scene::instances): instance instances[k]
  // takes transforms[k], an affine map of its mesh's positions (its last row 0 0 0 1). The world's
  // tree is built again over the instances where they now stand, the meshes' trees kept, and the
  // next call renders the moved scene. Throws InputError, changing nothing, for an instance out of
  // range, or a transform not affine, not finite, not invertible, or placing its mesh's box beyond
  // 1e15; RenderTimings::scene_update_ms is the call's time.
  void set_transforms(std::span<const uint32_t> instances, std::span<const glm::dmat4> transforms);

  const Scene& scene() const;

  // Timings of the last render (upload_ms and bvh_build_ms are the constructor's).
  const RenderTimings& timings() const;
  const SceneStats& scene_stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vkray
