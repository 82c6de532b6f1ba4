// The Renderer's state on the device and the steps of a render, shared by the files that each
// hold one concern of it: scene_upload.cpp (the scene's buffers), render_buffers.cpp (a render's
// outputs and bindings), dispatch.cpp (dispatches and their sizes), given_rays.cpp (rays the caller
// gives), unfinished_rays.cpp (rays the CPU finishes), renderer.cpp (the public calls).
#pragma once

#include "engine/reference/reference.hpp"
#include "engine/scene/camera.hpp"
#include "engine/render/renderer.hpp"
#include "engine/vulkan/acceleration_structures.hpp"
#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/direction_order_pass.hpp"
#include "engine/vulkan/host_import.hpp"
#include "engine/vulkan/raycast_pipeline.hpp"

#include <functional>
#include <map>
#include <optional>

namespace vkray {

// Geometry the shader reads as RGBA32 texels (see gpu_layout.h), with a float view and, where the
// texels hold indices, a uint view of the same memory.
struct TexelBuffer {
  GpuBuffer buffer;
  vk::raii::BufferView floats{nullptr};
  vk::raii::BufferView uints{nullptr};
};

constexpr vk::DeviceSize texel_bytes = 16;

// Geometry buffers serve as uniform texel buffers or, for the storage-geometry variant, storage buffers.
constexpr vk::BufferUsageFlags geometry_usage = vk::BufferUsageFlagBits::eUniformTexelBuffer | vk::BufferUsageFlagBits::eStorageBuffer;

// `buffer` with its float and uint views.
TexelBuffer texel_views_of(VulkanContext& context, GpuBuffer buffer);

// What the shader reads of a given ray: a GpuRay, or a direction from the shared origin (a texel);
// of a point, a GpuPoint.
inline vk::DeviceSize given_ray_bytes(RaycastMode mode) {
  if (mode == RaycastMode::points) return sizeof(gpu::GpuPoint);
  return mode == RaycastMode::given_directions ? texel_bytes : sizeof(gpu::GpuRay);
}

// One output of one tile: the buffer the shader writes and, where that buffer is not host-visible,
// the buffer it is copied into for reading. A dispatch of n pixels writes its first
// header_bytes + n * pixel_bytes (planes packed to the dispatch's rows, see raycast.comp): only
// those are copied back (at 8K a whole normal buffer is 400 MB).
struct OutputBuffer {
  GpuBuffer written;
  std::optional<GpuBuffer> readback;
  vk::DeviceSize pixel_bytes = 0;
  vk::DeviceSize header_bytes = 0;
  // For the render under way, in place of readback: the frame's planes of this output, imported
  // (land_in_frame). The device copies each plane of a tile into its place; the host copies nothing.
  struct FramePlanes {
    ImportedHostMemory memory;
    vk::DeviceSize element_bytes = 0;  // a float or a double
    vk::DeviceSize frame_pixels = 0;   // a plane's length in the frame
  };
  std::optional<FramePlanes> frame_planes;
  const void* host() const { return readback ? readback->mapped : written.mapped; }
  vk::DeviceSize bytes_written(vk::DeviceSize pixels) const {
    return std::min(written.size, header_bytes + pixels * pixel_bytes);
  }
};

// Output buffers for tiles of `width` x `rows`, kept between renders of the same shape; with the
// storage-image target (image_id != 0) the outputs go to that image instead.
struct TileOutputs {
  uint32_t width = 0;
  uint32_t rows = 0;
  uint32_t aov_bits = 0;
  uint64_t image_id = 0;  // ImageTarget::id
  RaycastMode mode = RaycastMode::image_buffers;
  // First hits (VKRAY_SPEC_HITS): depth, normal and hits hold each ray's in this many runs of planes.
  uint32_t layers = 1;
  std::optional<OutputBuffer> depth, normal, uv;
  std::optional<OutputBuffer> overflow;  // only where a loop budget applies
  // RaycastMode::given_rays: the tile's rays (GpuRay, written by the host) and what each hit.
  std::optional<TexelBuffer> rays;
  std::optional<OutputBuffer> hits;
  std::optional<OutputBuffer> instance_hits;  // beside `hits` in a scene with instances: the instance each hit
};

// RaycastMode::caller_arrays: a call's rays and hit arrays where the caller holds them, imported
// for the call (Renderer::cast_rays_in_place); an array the caller did not ask for is none.
struct CallerArrays {
  ImportedHostMemory rays;
  vk::raii::BufferView ray_texels{nullptr};  // RGBA32UI, from the first ray on
  std::optional<ImportedHostMemory> t, normal, object, primitive;
  const DirectionOrderPass* order = nullptr;  // the rays ordered by direction, where they walk so
};

// A pixel of a storage-image target written by the host: a ray the CPU finished.
struct PixelPatch {
  uint32_t i, j;
  glm::vec4 value;  // as the shader stores it
};

// scene_upload.cpp: where `scene`'s instances place the ray-query structures' instanced meshes
// (StructureInput::placements), for `gpu_scene` made from it or from it before they moved.
std::vector<StructureInput::Placement> structure_placements(const GpuScene& gpu_scene, const Scene& scene);

struct Renderer::Impl {
  Impl(VulkanContext& vulkan_context, RendererOptions renderer_options)
      : context(vulkan_context), options(renderer_options) {}

  VulkanContext& context;
  RendererOptions options;
  GpuSceneOptions scene_options;  // options.scene as the constructor settled them (the packet walk)
  std::optional<Bvh> tree;        // the tree's shape, for set_vertices' refit
  // After a first set_vertices of a tree's scene: its arrays on the host, which the next ones refit
  // in place (refit_in_place) and write into the same buffers. None for a scene that never moves.
  std::optional<GpuScene> moving;
  // A scene with instances: its arrays on the host, whose world level set_transforms builds again
  // (place_instances), and each instanced mesh's box, which bounds where a transform places it.
  std::optional<GpuScene> placing;
  std::vector<Bounds> mesh_boxes;
  glm::dvec3 anchor{0.0};
  double scene_radius = 0.0;  // GpuScene::radius
  glm::uvec4 counts{0};  // RayGenParams.counts, the ray mask in them
  Mask ray_mask = every_mask_bit;  // set_ray_mask's
  // Bound wherever the scene lacks a primitive type or an output is off.
  GpuBuffer placeholder;
  TexelBuffer placeholder_texels;
  std::optional<TexelBuffer> spheres, planes, primitives, vertices, normals, bvh_nodes, apart_masks, instances;
  // What point queries read besides (point_queries.cpp): the slots' records and the nodes' children
  // as uploaded (upload_scene and write_refitted keep them), each instanced mesh's root node, and
  // what the first point query after a change makes of them: each instance's linear map and its
  // mesh's closedness (VKRAY_BINDING_PLACEMENTS), the winding number's caps (made at the first
  // winding number).
  std::vector<glm::uvec4> point_records;
  std::vector<std::array<uint32_t, 2>> point_links;
  std::vector<uint32_t> mesh_roots;
  std::optional<TexelBuffer> placements, winding_caps, cap_edges;
  bool point_data_stale = true;
  std::optional<AccelerationStructures> structures;  // the ray-query traversal's
  HitSources hit_sources;
  // hit_sources.slots as the shader reads them (VKRAY_BINDING_HIT_SOURCES), made by the first
  // cast_rays_in_place; remade when the scene is uploaded again.
  std::optional<GpuBuffer> hit_source_table;
  bool caller_arrays_bound = false;  // the descriptor set holds a call's imported arrays
  std::optional<DirectionOrderPass> direction_order;  // made by the first call that orders rays on the device
  std::vector<gpu::GpuPlane> gpu_planes;  // what `planes` holds, its heights set per render
  std::vector<Plane> scene_planes;
  SceneStats stats;
  // The scene on the host: the surface outputs read its meshes, and rays the device leaves
  // unfinished (a loop budget) are traced by a reference made from it, for rays of `ray_mask`.
  Scene host_scene;
  std::optional<ReferenceScene> reference;
  std::optional<RaycastPipeline> pipeline;
  std::unique_ptr<ImageTarget> placeholder_image;  // 1x1, bound while rendering to buffers
  std::optional<OutputBuffer> depth_range;  // DepthRangeBits, made on the first render to an image
  vk::raii::QueryPool timestamps{nullptr};
  TileOutputs tile;
  // The last tile of the other kind of work (a camera's pixels, or given rays), kept while this kind
  // runs: a Renderer that alternates renders and ray casts makes neither's buffers again (for a
  // million given rays, the fresh memory's page clearing cost about 7 ms a call on lavapipe).
  TileOutputs parked_tile;
  RenderTimings timings;
  // The slowest pixels' (or given rays') cost in the last render, ms each: the next one's first
  // dispatch is sized by it (DispatchSizer). Given rays' by what they look for and how many hits:
  // counting or listing 16 hits costs a ray several times a nearest hit.
  double camera_ms_per_pixel = 0.0;
  std::map<std::pair<HitQuery, uint32_t>, double> given_ms_per_ray;

  Precision precision() const { return options.shader.precision; }
  // renderer.cpp: keeps a scene with instances for set_transforms.
  void keep_for_placing(GpuScene&& gpu_scene);

  // scene_upload.cpp: the scene's geometry (and the ray-query traversal's structures) on the device,
  // replacing what was there (set_vertices); `scene` is what gpu_scene was made from.
  void upload_scene(const GpuScene& gpu_scene, const Scene& scene);
  // A refitted scene's arrays into the buffers that hold them (the same sizes), and its anchor.
  void write_refitted(const GpuScene& gpu_scene);
  // What the constructor makes once besides: the placeholders bound for what a scene lacks, timestamps.
  void make_placeholders();
  // The pipeline for `gpu_scene`: `early` where it was made for the same specialization, the current
  // one where it is, else a new one (its pipelines made on first use).
  void choose_pipeline(const GpuScene& gpu_scene, std::optional<RaycastPipeline>& early);
  // Throws where the device has no such workgroup, or Morton order cannot walk it.
  void check_workgroup() const;

  // render_buffers.cpp
  // The pixels (or given rays, as rows) one workgroup covers in `mode`: its own invocations', or
  // the packet walk's columns (VKRAY_PACKET_*).
  vk::Extent2D workgroup_footprint(RaycastMode mode) const;
  // The most bytes one geometry (or given-ray) buffer may hold: what one texel buffer or, for the
  // storage-geometry variant, one storage buffer binds, and one allocation holds.
  vk::DeviceSize binding_limit() const;
  // An output of `pixels` pixels of `pixel_bytes` each after `header_bytes`.
  OutputBuffer make_output(vk::DeviceSize pixels, vk::DeviceSize pixel_bytes, vk::DeviceSize header_bytes = 0);
  // Output buffers and bindings for tiles of `width` x `rows` writing `aovs` to buffers, or to
  // `target` when given; with given rays, their buffer and the hits' too.
  // RaycastMode::caller_arrays binds `caller`'s arrays in place of the tile's outputs. `layers`:
  // each given ray's first hits (TileOutputs::layers).
  void prepare_tile(uint32_t width, uint32_t rows, AovSet aovs, const ImageTarget* target,
                    RaycastMode mode = RaycastMode::image_buffers, const CallerArrays* caller = nullptr,
                    uint32_t layers = 1);
  // Rows per dispatch: every output buffer within the device's storage-buffer range (and the
  // caller's cap), and the workgroup count within the device's limit.
  // `buffer_aovs`: the outputs written to buffers (none with the storage-image target).
  uint32_t rows_per_tile(uint32_t width, uint32_t height, AovSet buffer_aovs,
                         RaycastMode mode = RaycastMode::image_buffers, uint32_t layers = 1) const;
  void reset_timings();
  // What a render needs before its tiles: the pipeline (returned), the planes' heights above this
  // camera, the tile's outputs and bindings; `tile_rows` receives the rows per tile.
  const vk::raii::Pipeline& begin_render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs,
                                         const ImageTarget* target, uint32_t& tile_rows);
  // Each output of the tile with its planes in `frame` (float or double, as the precision has them),
  // `planes` of them.
  template <typename Visit>
  void for_each_frame_plane(Frame& frame, Visit&& visit);
  // With staging, the frame's planes imported where the device allows (OutputBuffer::frame_planes),
  // so that the device copies each tile straight into them; the returned guard forgets them again.
  struct FrameLanding {
    TileOutputs& tile;
    ~FrameLanding();
  };
  [[nodiscard]] FrameLanding land_in_frame(Frame& frame);
  // The outputs of the tile of `rows` rows from `first_row` into their places in `frame`, where the
  // device did not copy them there.
  void read_tile(Frame& frame, uint32_t first_row, uint32_t rows);
  // The planes' heights above `origin` into their buffer (no submission is in flight: every render
  // waits for its own).
  void set_planes_above(const glm::dvec3& origin);

  // renderer.cpp: a perspective camera's `device_aovs` into `frame`, in dispatches of rows.
  void render_camera_rows(const Camera& camera, AovSet device_aovs, Frame& frame);

  // dispatch.cpp
  // Casts the rays of one tile: resets the overflow list (and the depth range, for an image),
  // dispatches, and copies what the host reads into host-visible memory; waits for it.
  // Returns the dispatch's GPU time (its wall time, submission included, where there are no
  // timestamps). A pipeline's first dispatch is run small first, untimed (its compilation).
  double dispatch_tile(const vk::raii::Pipeline& chosen, const gpu::RayGenParams& params);
  double submit_tile(const vk::raii::Pipeline& chosen, const gpu::RayGenParams& params);
  // A camera's rows in dispatches, each sized by what the earlier ones took (DispatchSizer);
  // `tile_done(first_row, rows)` reads each back before the next runs.
  void dispatch_camera_rows(const vk::raii::Pipeline& camera_pipeline, const CameraBasis& basis, uint32_t width,
                            uint32_t height, uint32_t tile_rows, RaycastMode mode,
                            const std::function<void(uint32_t first_row, uint32_t rows)>& tile_done);
  // The GPU time of `repeats` passes over a camera's whole image in one submission, back to back,
  // with nothing read back: see Renderer::sustained_dispatch_ms.
  double sustained_dispatch_ms(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs, uint32_t repeats);

  // given_rays.cpp
  // What Renderer::cast_rays or Renderer::occluded traces: the rays, their ranges, what they look
  // for, and for the nearest hits how many of the first hits (VKRAY_SPEC_HITS).
  struct GivenRays {
    std::span<const GivenRay> rays;
    RayRanges ranges;
    HitQuery query = HitQuery::nearest;
    uint32_t hits = 1;
  };
  RayHits cast_rays(const GivenRays& given);
  // Given rays in dispatches of at most `tile_rows` rows of `width` positions. Position p holds ray
  // p, or with an `order` (by direction) the ray at its place packet_order_index(p) in it; places
  // past its end are padding, which trace its last ray again and keep nothing. `origin`: the rays'
  // one origin (given_directions), sent as a camera's.
  void cast_given(const GivenRays& given, RaycastMode mode, uint32_t width, uint32_t tile_rows, size_t positions,
                  const glm::dvec3* origin, const std::vector<uint32_t>* order, RayHits& hits);
  bool cast_rays_in_place(std::span<const GivenRay> rays, const HitArrays& into);
  // Whether this device and shader can (the lists themselves aside).
  bool casts_in_place() const;
  // `rays` and the arrays of `into` imported and bound as the shader reads them (the rays as texels
  // too where `ray_texels`), or none where the device refuses any or cannot bind it whole.
  std::optional<CallerArrays> import_caller_arrays(std::span<const GivenRay> rays, const HitArrays& into, bool ray_texels);
  // The rays at `listed` (indices into `rays`; sorted here) cast by cast_rays and written into `into`:
  // those cast_rays_in_place's shader left to the host. InputError names the first bad one.
  void cast_listed_again(std::span<const GivenRay> rays, std::vector<uint32_t>& listed, const HitArrays& into);
  // The depth, normal and ids of a camera whose rays do not leave one point through an image
  // plane's pixels, into `frame`: its pixels' rays cast as given rays.
  void render_by_given_rays(const Camera& camera, Frame& frame);

  // point_queries.cpp: `points`' nearest points within `max_distances` (one a point, one for all, or
  // none: no bound), or winding numbers (`query`).
  PointHits query_points(std::span<const glm::dvec3> points, std::span<const double> max_distances, HitQuery query);
  // The point queries' buffers for the scene as it now is (the caps where `winding`).
  void make_point_data(bool winding);
  // The point queries' source from `gpu_scene`: all of it, or what its refit rewrote.
  void keep_point_source(const GpuScene& gpu_scene, bool rewritten_alone);

  // unfinished_rays.cpp
  // Rays listed in the overflow buffer ran out of the loop budget with part of the tree not yet
  // visited: they are traced again, exactly, by the double-precision reference. Rare: a primary ray
  // visits tens to hundreds of nodes, the budget is ~65000 on lavapipe.
  // `finish` receives each such ray's index within the tile (row-major).
  void finish_unfinished(const std::function<void(uint32_t index)>& finish);
  // What the last dispatch listed in the overflow buffer (fetched from the device first under
  // staging): indices within the tile, or of the caller's rays (RaycastMode::caller_arrays).
  std::span<const uint32_t> listed_rays();
  // The same for a camera's pixels: `finish` receives each pixel (i, j) and its hit.
  void finish_unfinished_rays(const CameraBasis& basis, uint32_t width, uint32_t height, uint32_t first_row,
                              const std::function<void(uint32_t i, uint32_t j, const ReferenceHit& hit)>& finish);
  // Writes the pixels the CPU finished into `target`, after the shader's writes.
  void write_patches(const std::vector<PixelPatch>& patches, ImageTarget& target);
};

}  // namespace vkray
