#include "engine/render/renderer.hpp"

#include "engine/parallel.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/render/ray_order.hpp"
#include "engine/scene/camera.hpp"
#include "engine/stopwatch.hpp"
#include "engine/surface_outputs.hpp"
#include "engine/unit_vector.hpp"
#include "engine/vulkan/acceleration_structures.hpp"
#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/image.hpp"
#include "engine/vulkan/raycast_pipeline.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cstring>
#include <future>
#include <optional>

namespace vkray {
namespace {

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

TexelBuffer make_texel_buffer(VulkanContext& context, const void* data, vk::DeviceSize bytes,
                              vk::BufferUsageFlags extra_usage = {}) {
  TexelBuffer texels{upload_buffer(context, data, bytes, geometry_usage | extra_usage)};
  texels.floats = create_texel_view(context, texels.buffer, vk::Format::eR32G32B32A32Sfloat);
  texels.uints = create_texel_view(context, texels.buffer, vk::Format::eR32G32B32A32Uint);
  return texels;
}

uint32_t checked_count(size_t count, const char* what) {
  if (count > UINT32_MAX) throw InputError(std::string("too many ") + what + " for one scene");
  return static_cast<uint32_t>(count);
}

// Bytes per pixel of each output buffer: depth and normal components are floats, or doubles with
// the float64 shader.
vk::DeviceSize depth_bytes(Precision precision) { return precision == Precision::float64 ? sizeof(double) : sizeof(float); }
vk::DeviceSize normal_bytes(Precision precision) { return 3 * depth_bytes(precision); }
constexpr vk::DeviceSize uv_bytes = 2 * sizeof(float);

// What the shader reads of a given ray: a GpuRay, or a direction from the shared origin (a texel).
vk::DeviceSize given_ray_bytes(RaycastMode mode) {
  return mode == RaycastMode::given_directions ? texel_bytes : sizeof(gpu::GpuRay);
}

// The packet walk's layout of given directions in an order (by direction): rows
// VKRAY_PACKET_GROUP_WIDTH wide, in which a packet is packet_columns columns (lavapipe's 8 lanes;
// wider subgroups take several packets) of VKRAY_PACKET_ROWS rows. The n-th ray of the order takes
// the n % 64-th place of packet n / 64, so that 64 consecutive rays walk the tree together; a block
// of VKRAY_PACKET_ROWS rows holds whole packets.
constexpr uint32_t packet_columns = 8;
constexpr uint32_t packet_rays = packet_columns * VKRAY_PACKET_ROWS;
constexpr uint32_t packets_a_row = VKRAY_PACKET_GROUP_WIDTH / packet_columns;
constexpr uint32_t packet_block_positions = VKRAY_PACKET_GROUP_WIDTH * VKRAY_PACKET_ROWS;
static_assert(VKRAY_PACKET_GROUP_WIDTH % packet_columns == 0);

// The place in the order of the ray at layout position p.
size_t packet_order_index(size_t position) {
  const size_t x = position % VKRAY_PACKET_GROUP_WIDTH, y = position / VKRAY_PACKET_GROUP_WIDTH;
  const size_t packet = (y / VKRAY_PACKET_ROWS) * packets_a_row + x / packet_columns;
  return packet * packet_rays + (y % VKRAY_PACKET_ROWS) * packet_columns + x % packet_columns;
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
  std::optional<OutputBuffer> depth, normal, uv;
  std::optional<OutputBuffer> overflow;  // only where a loop budget applies
  // RaycastMode::given_rays: the tile's rays (GpuRay, written by the host) and what each hit.
  std::optional<TexelBuffer> rays;
  std::optional<OutputBuffer> hits;
};

// A pixel of a storage-image target written by the host: a ray the CPU finished.
struct PixelPatch {
  uint32_t i, j;
  glm::vec4 value;  // as the shader stores it
};

// Loop iterations of raycast.comp outside the tree walk, for each of an invocation's rays the
// planes and spheres tested one by one and the loops over those rays, and a margin for the few
// iterations the compiler may keep where it fails to unroll a constant-trip loop.
uint64_t fixed_loop_iterations(const GpuSceneShape& shape) {
  constexpr uint64_t loop_margin = 16;
  constexpr uint64_t loops_over_rays = 4;
  const uint64_t rays = shape.search == PrimitiveSearch::bvh_packet ? VKRAY_PACKET_ROWS : 1;
  uint64_t iterations = rays * (uint64_t{shape.spheres_apart} + shape.planes + loops_over_rays) + loop_margin;
  iterations += shape.brute_force_triangle_slots / VKRAY_TRIANGLE_BATCH;
  return iterations;
}

// Iterations a tree walk may take on this device (0: no limit): a tree walk has no static bound on
// its iterations; where the device caps them, the walk gets what the other loops leave and rays
// that need more are finished on the CPU. Throws where the other loops alone pass the cap.
uint32_t tree_loop_budget(const GpuSceneShape& shape, const GpuDeviceInfo& device, uint32_t requested) {
  const uint64_t loop_limit = device.max_loop_iterations;
  const uint64_t fixed_iterations = fixed_loop_iterations(shape);
  if (loop_limit > 0 && fixed_iterations >= loop_limit) {
    throw GpuError("this scene needs " + std::to_string(fixed_iterations) + " shader loop iterations per pixel, but " +
                   device.name + " stops a shader after " + std::to_string(loop_limit) +
                   " and would silently drop geometry; use another device (--device)");
  }
  if (shape.search == PrimitiveSearch::brute_force || (loop_limit == 0 && requested == 0)) return 0;
  uint64_t budget = loop_limit > 0 ? loop_limit - fixed_iterations : UINT32_MAX;
  if (requested > 0) budget = std::min<uint64_t>(budget, requested);
  return static_cast<uint32_t>(budget);
}

// VKRAY_SPEC_STACK_REGISTERS for a tree `depth` edges deep: a walk holds at most one stack entry per
// inner node on its path, `depth` of them.
uint32_t stack_registers_for_depth(uint32_t depth) {
  if (depth > VKRAY_STACK_REGISTERS_MAX) return 0;
  return std::max<uint32_t>(4, (depth + 3) / 4 * 4);
}

// The pipelines' specialization for a scene of `shape` whose tree is `depth` deep. The packet walk
// always takes the most registers for its stack, so that its pipeline can be made before the tree
// exists (measured: 16 or 32 registers gave the bunny the same time).
PipelineSpecialization specialization_for(const GpuSceneShape& shape, uint32_t depth, uint32_t loop_budget,
                                          const ShaderVariant& shader) {
  PipelineSpecialization specialization;
  specialization.spheres = shape.spheres_apart;
  specialization.planes = shape.planes;
  specialization.triangle_slots = shape.brute_force_triangle_slots;
  specialization.search_mode = search_info(shape.search).shader_mode;
  specialization.tree_has_triangles = shape.tree_has_triangles;
  specialization.tree_has_spheres = shape.tree_has_spheres;
  specialization.loop_budget = loop_budget;
  const bool stack_in_registers = shader.stack_in_registers && !shader.generic;
  specialization.stack_registers = !stack_in_registers                           ? 0
                                   : shape.search == PrimitiveSearch::bvh_packet ? VKRAY_STACK_REGISTERS_MAX
                                                                                 : stack_registers_for_depth(depth);
  specialization.variant = shader;
  return specialization;
}

// Rows of the next dispatch, from the time the earlier ones took (RendererOptions::dispatch_budget_ms).
class DispatchSizer {
 public:
  // `max_rows`: what the output buffers hold; rows are counted in `width`-wide rows, and taken in
  // whole `row_step`s (the rows of a workgroup) where `max_rows` allows. `known_ms_per_pixel`: the
  // slowest pixels of the renderer's last render, 0 for none.
  DispatchSizer(uint32_t width, uint32_t max_rows, double budget_ms, double known_ms_per_pixel, uint32_t row_step = 1)
      : width_(width), max_rows_(max_rows), budget_ms_(budget_ms), known_ms_per_pixel_(known_ms_per_pixel),
        row_step_(row_step) {}

  uint32_t next_rows() const {
    if (budget_ms_ <= 0.0) return max_rows_;
    uint64_t rows = first_dispatch_pixels / width_;
    // After a render of the same scene, the first dispatch takes what a quarter of the budget holds
    // at its slowest pixels' cost (another camera can cost more): one dispatch a frame where the
    // frame fits, as many views in a row do, where three cost the bunny at 1920x1080 about 5 ms more.
    if (last_rows_ == 0 && known_ms_per_pixel_ > 0.0) {
      rows = static_cast<uint64_t>(0.25 * budget_ms_ / (known_ms_per_pixel_ * width_));
    }
    if (last_rows_ > 0) {
      // Growth bounded, so a jump in cost shows before it costs much; sixteen, since on lavapipe
      // every dispatch beyond three cost the bunny at 1920x1080 about 3 ms (four times: 4
      // dispatches, 160 ms).
      rows = uint64_t{16} * last_rows_;
      if (slowest_ms_per_row_ > 0.0) rows = std::min<uint64_t>(rows, static_cast<uint64_t>(0.5 * budget_ms_ / slowest_ms_per_row_));
    }
    rows = std::max<uint64_t>(rows / row_step_, 1) * row_step_;
    return static_cast<uint32_t>(std::clamp<uint64_t>(rows, 1, max_rows_));
  }

  void measured(uint32_t rows, double ms) {
    last_rows_ = rows;
    slowest_ms_per_row_ = std::max(slowest_ms_per_row_, ms / rows);
  }
  double slowest_ms_per_pixel() const { return slowest_ms_per_row_ / width_; }

 private:
  // The first dispatch: 65536 pixels, a few ms on lavapipe's two cores even where every ray walks a
  // tree, and far less on a GPU.
  static constexpr uint32_t first_dispatch_pixels = 65536;
  uint32_t width_, max_rows_;
  double budget_ms_;
  double known_ms_per_pixel_;
  uint32_t row_step_;
  uint32_t last_rows_ = 0;
  double slowest_ms_per_row_ = 0.0;
};

}  // namespace

const char* given_ray_walk_name(GivenRayWalk walk) {
  switch (walk) {
    case GivenRayWalk::one_by_one: return "one by one";
    case GivenRayWalk::packets_in_place: return "packets in place";
    case GivenRayWalk::packets_by_direction: return "packets by direction";
    default: return "none";
  }
}

struct Renderer::Impl {
  Impl(VulkanContext& vulkan_context, RendererOptions renderer_options)
      : context(vulkan_context), options(renderer_options) {}

  VulkanContext& context;
  RendererOptions options;
  glm::dvec3 anchor{0.0};
  double scene_radius = 0.0;  // GpuScene::radius
  glm::uvec4 counts{0};  // RayGenParams.counts
  // Bound wherever the scene lacks a primitive type or an output is off.
  GpuBuffer placeholder;
  TexelBuffer placeholder_texels;
  std::optional<TexelBuffer> spheres, planes, primitives, vertices, normals, bvh_nodes;
  std::optional<AccelerationStructures> structures;  // the ray-query traversal's
  HitSources hit_sources;
  std::vector<gpu::GpuPlane> gpu_planes;  // what `planes` holds, its heights set per render
  std::vector<Plane> scene_planes;
  SceneStats stats;
  // Where a loop budget applies: the scene, to finish on the CPU the rays that run out of it.
  // The scene on the host: the surface outputs read its meshes, and rays the device leaves unfinished
  // (a loop budget) are traced by a reference made from it.
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
  // dispatch is sized by it (DispatchSizer).
  double camera_ms_per_pixel = 0.0, given_ms_per_ray = 0.0;

  Precision precision() const { return options.shader.precision; }

  // The pixels (or given rays, as rows) one workgroup covers in `mode`: its own invocations', or
  // the packet walk's columns (VKRAY_PACKET_*).
  vk::Extent2D workgroup_footprint(RaycastMode mode) const {
    if (stats.search == PrimitiveSearch::bvh_packet && mode != RaycastMode::given_rays) {
      return {VKRAY_PACKET_GROUP_WIDTH, VKRAY_PACKET_GROUP_HEIGHT};
    }
    return {options.shader.workgroup_width, options.shader.workgroup_height};
  }

  // The most bytes one geometry (or given-ray) buffer may hold: what one texel buffer or, for the
  // storage-geometry variant, one storage buffer binds, and one allocation holds.
  vk::DeviceSize binding_limit() const {
    const vk::DeviceSize binding = options.shader.storage_geometry
                                       ? vk::DeviceSize{context.limits.maxStorageBufferRange}
                                       : vk::DeviceSize{context.limits.maxTexelBufferElements} * texel_bytes;
    return std::min<vk::DeviceSize>(binding, context.info.max_allocation_bytes);
  }

  // An output of `pixels` pixels of `pixel_bytes` each after `header_bytes`.
  OutputBuffer make_output(vk::DeviceSize pixels, vk::DeviceSize pixel_bytes, vk::DeviceSize header_bytes = 0) {
    const vk::DeviceSize bytes = header_bytes + pixels * pixel_bytes;
    OutputBuffer output{create_storage_buffer(context, bytes,
                                              vk::BufferUsageFlagBits::eTransferSrc | vk::BufferUsageFlagBits::eTransferDst),
                        std::nullopt, pixel_bytes, header_bytes};
    if (!output.written.mapped) output.readback = create_readback_buffer(context, bytes);
    return output;
  }

  // Output buffers and bindings for tiles of `width` x `rows` writing `aovs` to buffers, or to
  // `target` when given; with given rays, their buffer and the hits' too.
  void prepare_tile(uint32_t width, uint32_t rows, AovSet aovs, const ImageTarget* target,
                    RaycastMode mode = RaycastMode::image_buffers) {
    const uint64_t image_id = target ? target->id() : 0;
    auto fits = [&](const TileOutputs& outputs) {
      return outputs.width == width && outputs.rows == rows && outputs.aov_bits == aovs.bits() &&
             outputs.image_id == image_id && outputs.mode == mode;
    };
    if (fits(tile)) return;
    if (fits(parked_tile)) {
      std::swap(tile, parked_tile);
    } else {
      if (is_given(tile.mode) != is_given(mode)) std::swap(tile, parked_tile);  // the other kind's, kept
      tile = TileOutputs{width, rows, aovs.bits(), image_id, mode, {}, {}, {}, {}, {}, {}};
      const vk::DeviceSize pixels = vk::DeviceSize{width} * rows;
      if (!target) {
        if (aovs.has(Aov::depth)) tile.depth = make_output(pixels, depth_bytes(precision()));
        if (aovs.has(Aov::normal)) tile.normal = make_output(pixels, normal_bytes(precision()));
        if (aovs.has(Aov::uv)) tile.uv = make_output(pixels, uv_bytes);
      }
      if (is_given(mode)) {
        const vk::DeviceSize bytes = pixels * given_ray_bytes(mode);
        tile.rays.emplace(TexelBuffer{create_upload_buffer(context, bytes, geometry_usage)});
        tile.rays->floats = create_texel_view(context, tile.rays->buffer, vk::Format::eR32G32B32A32Sfloat);
        tile.rays->uints = create_texel_view(context, tile.rays->buffer, vk::Format::eR32G32B32A32Uint);
      }
      if (is_given(mode) || (!target && aovs.has(Aov::hit))) tile.hits = make_output(pixels, sizeof(uint32_t));
      if (stats.loop_budget > 0 && aovs.needs_rays()) tile.overflow = make_output(pixels, sizeof(uint32_t), sizeof(uint32_t));
    }
    auto floats = [&](const std::optional<TexelBuffer>& texels) {
      return *(texels ? texels->floats : placeholder_texels.floats);
    };
    auto uints = [&](const std::optional<TexelBuffer>& texels) {
      return *(texels ? texels->uints : placeholder_texels.uints);
    };
    // float64 shaders read the geometry's doubles as pairs of 32-bit words (see GpuPoint).
    auto geometry = [&](const std::optional<TexelBuffer>& texels) {
      return precision() == Precision::float64 ? uints(texels) : floats(texels);
    };
    auto output = [&](const std::optional<OutputBuffer>& buffer) {
      return buffer ? *buffer->written.buffer : *placeholder.buffer;
    };
    RaycastPipeline::Resources resources{};
    resources.texel_views[VKRAY_BINDING_SPHERES] = geometry(spheres);
    resources.texel_views[VKRAY_BINDING_PLANES] = geometry(planes);
    resources.texel_views[VKRAY_BINDING_PRIMITIVES] = uints(primitives);
    resources.texel_views[VKRAY_BINDING_VERTICES] = geometry(vertices);
    resources.texel_views[VKRAY_BINDING_NORMALS] = geometry(normals);
    resources.texel_views[VKRAY_BINDING_RAYS] = geometry(tile.rays);
    resources.buffers[VKRAY_BINDING_HITS] = output(tile.hits);
    resources.texel_views[VKRAY_BINDING_BVH_BOUNDS] = floats(bvh_nodes);
    resources.texel_views[VKRAY_BINDING_BVH_LINKS] = uints(bvh_nodes);
    // The same buffers whole, for the storage-geometry variant (pipeline->binding_type picks which
    // one a binding takes).
    auto whole = [&](const std::optional<TexelBuffer>& texels) {
      return *(texels ? texels->buffer.buffer : placeholder_texels.buffer.buffer);
    };
    for (const auto& [binding, texels] : {std::pair{VKRAY_BINDING_SPHERES, &spheres}, {VKRAY_BINDING_PLANES, &planes},
                                          {VKRAY_BINDING_PRIMITIVES, &primitives}, {VKRAY_BINDING_VERTICES, &vertices},
                                          {VKRAY_BINDING_NORMALS, &normals}, {VKRAY_BINDING_BVH_BOUNDS, &bvh_nodes},
                                          {VKRAY_BINDING_BVH_LINKS, &bvh_nodes}, {VKRAY_BINDING_RAYS, &tile.rays}}) {
      resources.buffers[binding] = whole(*texels);
    }
    resources.buffers[VKRAY_BINDING_DEPTH] = output(tile.depth);
    resources.buffers[VKRAY_BINDING_NORMAL] = output(tile.normal);
    resources.buffers[VKRAY_BINDING_UV] = output(tile.uv);
    resources.buffers[VKRAY_BINDING_OVERFLOW] = output(tile.overflow);
    resources.buffers[VKRAY_BINDING_DEPTH_RANGE] = output(depth_range);
    resources.images[VKRAY_BINDING_IMAGE] = *(target ? *target : *placeholder_image).image().view;
    if (structures) resources.top_structure = structures->top();
    pipeline->bind_resources(resources);
  }

  // Rays listed in the overflow buffer ran out of the loop budget with part of the tree not yet
  // visited: they are traced again, exactly, by the double-precision reference. Rare: a primary ray
  // visits tens to hundreds of nodes, the budget is ~65000 on lavapipe.
  // `finish` receives each such ray's index within the tile (row-major).
  template <typename Finish>
  void finish_unfinished(Finish&& finish) {
    const auto* overflow = static_cast<const uint32_t*>(tile.overflow->host());
    const uint32_t count = overflow[0];
    if (count == 0) return;
    const auto start = Clock::now();
    if (!reference) reference.emplace(host_scene);
    for (uint32_t k = 0; k < count; ++k) finish(overflow[1 + k]);
    timings.unfinished_rays += count;
    timings.cpu_finish_ms += elapsed_ms(start);
  }

  // The same for a camera's pixels: `finish` receives each pixel (i, j) and its hit.
  template <typename Finish>
  void finish_unfinished_rays(const CameraBasis& basis, uint32_t width, uint32_t height, uint32_t first_row,
                              Finish&& finish) {
    finish_unfinished([&](uint32_t index) {
      const uint32_t i = index % width;
      const uint32_t j = first_row + index / width;
      finish(i, j, reference->trace(basis.origin, basis.direction(pixel_uv(i, j, width, height))));
    });
  }

  // Given rays in dispatches of at most `tile_rows` rows of `width` positions. Position p holds ray
  // p, or with an `order` (by direction) the ray at its place packet_order_index(p) in it; places
  // past its end are padding, which trace its last ray again and keep nothing. `origin`: the rays'
  // one origin (given_directions), sent as a camera's.
  void cast_given(std::span<const GivenRay> rays, RaycastMode mode, uint32_t width, uint32_t tile_rows, size_t positions,
                  const glm::dvec3* origin, const std::vector<uint32_t>* order, RayHits& hits) {
    auto ray_at = [&](size_t position) {  // rays.size() for padding
      if (!order) return position;
      const size_t n = packet_order_index(position);
      return n < order->size() ? size_t{(*order)[n]} : rays.size();
    };
    const AovSet aovs{Aov::depth, Aov::normal};
    // The lo parts of positions as for a camera (needs_lo_parts), wherever any of the rays starts.
    const bool lo_parts = origin ? needs_lo_parts(anchor, scene_radius, *origin)
                                 : std::any_of(rays.begin(), rays.end(), [&](const GivenRay& ray) {
                                     return needs_lo_parts(anchor, scene_radius, {ray[0], ray[1], ray[2]});
                                   });
    const vk::raii::Pipeline& chosen = pipeline->pipeline(aovs, lo_parts, mode, timings.pipeline_ms);
    // The planes' heights above the one origin; rays from their own origins subtract it themselves.
    if (planes) {
      if (origin) set_plane_heights(gpu_planes, scene_planes, *origin, precision());
      std::memcpy(planes->buffer.mapped, gpu_planes.data(), gpu_planes.size() * sizeof(gpu::GpuPlane));
    }
    prepare_tile(width, tile_rows, aovs, nullptr, mode);
    double& ms_per_ray = origin ? camera_ms_per_pixel : given_ms_per_ray;  // packets cost as pixels do
    DispatchSizer sizer(width, tile_rows, options.dispatch_budget_ms, ms_per_ray, workgroup_footprint(mode).height);
    gpu::RayGenParams params{};
    if (origin) params = make_ray_gen_params(CameraBasis{*origin, {}, {}, {}, 0.0}, anchor, precision(), 0, 0, 0, 0, counts);
    params.counts = counts;
    for (size_t first = 0, count = 0; first < positions; first += count) {
      count = std::min(size_t{width} * sizer.next_rows(), positions - first);
      const auto encode_start = Clock::now();
      parallel_for_chunks(count, [&](size_t begin, size_t end) {
        for (size_t p = begin; p < end; ++p) {
          const size_t k = ray_at(first + p);
          const GivenRay& ray = rays[k < rays.size() ? k : order->back()];
          const glm::dvec3 direction(ray[3], ray[4], ray[5]);
          if (origin) {  // float32 alone: the packet walk's
            static_cast<glm::vec4*>(tile.rays->buffer.mapped)[p] = glm::vec4(glm::vec3(unit_vector(direction)), 0.0f);
          } else {
            static_cast<gpu::GpuRay*>(tile.rays->buffer.mapped)[p] = encode_ray({ray[0], ray[1], ray[2]}, direction, anchor, precision());
          }
        }
      });
      timings.rays_ms += elapsed_ms(encode_start);
      params.image = glm::uvec4(width, static_cast<uint32_t>(count), 0, static_cast<uint32_t>((count + width - 1) / width));
      sizer.measured(params.image.w, dispatch_tile(chosen, params));
      ms_per_ray = sizer.slowest_ms_per_pixel();

      const auto copy_start = Clock::now();
      const auto* slots = static_cast<const uint32_t*>(tile.hits->host());
      const size_t plane_size = size_t{width} * params.image.w;  // the shader's planes span whole rows
      auto copy = [&]<typename T>(const T* depths, const T* unit_normals) {
        parallel_for_chunks(count, [&](size_t begin, size_t end) {
          for (size_t p = begin; p < end; ++p) {
            const size_t k = ray_at(first + p);
            if (k >= rays.size()) continue;
            const glm::dvec3 normal(unit_normals[p], unit_normals[plane_size + p], unit_normals[2 * plane_size + p]);
            hits.store(k, depths[p], normal, hit_sources(slots[p]));
          }
        });
      };
      if (!order && precision() == Precision::float32) {  // in place: the planes as they are, the ids named
        const auto* unit_normals = static_cast<const float*>(tile.normal->host());
        std::memcpy(hits.t.data() + first, tile.depth->host(), count * sizeof(float));
        for (size_t c = 0; c < 3; ++c) {
          std::memcpy(hits.normal.data() + c * hits.count + first, unit_normals + c * plane_size, count * sizeof(float));
        }
        parallel_for_chunks(count, [&](size_t begin, size_t end) {
          for (size_t k = begin; k < end; ++k) {
            const ObjectPrimitive source = hit_sources(slots[k]);
            hits.object[first + k] = source.object;
            hits.primitive[first + k] = source.primitive;
          }
        });
      } else if (precision() == Precision::float64) {
        copy(static_cast<const double*>(tile.depth->host()), static_cast<const double*>(tile.normal->host()));
      } else {
        copy(static_cast<const float*>(tile.depth->host()), static_cast<const float*>(tile.normal->host()));
      }
      timings.readback_ms += elapsed_ms(copy_start);
      if (tile.overflow) {
        finish_unfinished([&](uint32_t position) {
          const size_t k = ray_at(first + position);
          if (k >= rays.size()) return;
          const GivenRay& ray = rays[k];
          const ReferenceHit hit = reference->trace(glm::dvec3(ray[0], ray[1], ray[2]), unit_vector(glm::dvec3(ray[3], ray[4], ray[5])));
          hits.store(k, hit.t, hit.normal, reference->source(hit));
        });
      }
    }
  }

  // A camera's rows in dispatches, each sized by what the earlier ones took (DispatchSizer);
  // `tile_done(first_row, rows)` reads each back before the next runs.
  template <typename TileDone>
  void dispatch_camera_rows(const vk::raii::Pipeline& camera_pipeline, const CameraBasis& basis, uint32_t width, uint32_t height,
                            uint32_t tile_rows, RaycastMode mode, TileDone&& tile_done) {
    DispatchSizer sizer(width, tile_rows, options.dispatch_budget_ms, camera_ms_per_pixel, workgroup_footprint(mode).height);
    for (uint32_t first_row = 0, rows = 0; first_row < height; first_row += rows) {
      rows = std::min(sizer.next_rows(), height - first_row);
      sizer.measured(rows, dispatch_tile(camera_pipeline, make_ray_gen_params(basis, anchor, precision(), width, height,
                                                                              first_row, rows, counts)));
      camera_ms_per_pixel = sizer.slowest_ms_per_pixel();
      tile_done(first_row, rows);
    }
  }

  // Rows per dispatch: every output buffer within the device's storage-buffer range (and the
  // caller's cap), and the workgroup count within the device's limit.
  // `buffer_aovs`: the outputs written to buffers (none with the storage-image target).
  uint32_t rows_per_tile(uint32_t width, uint32_t height, AovSet buffer_aovs, RaycastMode mode = RaycastMode::image_buffers) const {
    vk::DeviceSize largest = is_given(mode) ? sizeof(uint32_t) : 0;  // the hits
    if (buffer_aovs.has(Aov::depth)) largest = std::max(largest, depth_bytes(precision()));
    if (buffer_aovs.has(Aov::normal)) largest = std::max(largest, normal_bytes(precision()));
    if (buffer_aovs.has(Aov::uv)) largest = std::max(largest, uv_bytes);
    vk::DeviceSize limit = context.limits.maxStorageBufferRange;
    if (options.max_tile_bytes > 0) limit = std::min<vk::DeviceSize>(limit, options.max_tile_bytes);
    vk::DeviceSize by_bytes = largest > 0 ? std::max<vk::DeviceSize>(1, limit / (vk::DeviceSize{width} * largest)) : height;
    if (stats.loop_budget > 0) {  // the overflow list: a count, then 4 bytes a pixel
      by_bytes = std::min(by_bytes, std::max<vk::DeviceSize>(1, (limit - sizeof(uint32_t)) / (vk::DeviceSize{width} * 4)));
    }
    if (is_given(mode)) {  // the rays: one texel buffer
      const vk::DeviceSize ray_limit = binding_limit();
      by_bytes = std::min(by_bytes, std::max<vk::DeviceSize>(1, ray_limit / (vk::DeviceSize{width} * given_ray_bytes(mode))));
    }
    const vk::DeviceSize by_groups =
        vk::DeviceSize{context.limits.maxComputeWorkGroupCount[1]} * workgroup_footprint(mode).height;
    return static_cast<uint32_t>(std::min<vk::DeviceSize>({height, by_bytes, by_groups}));
  }

  void reset_timings() {
    RenderTimings fresh;  // the constructor's figures stay
    fresh.upload_ms = timings.upload_ms;
    fresh.bvh_build_ms = timings.bvh_build_ms;
    fresh.structures_ms = timings.structures_ms;
    fresh.pipeline_beside_upload_ms = timings.pipeline_beside_upload_ms;
    fresh.has_gpu_times = *timestamps != vk::QueryPool();
    timings = fresh;
  }

  // What a render needs before its tiles: the pipeline (returned), the planes' heights above this
  // camera, the tile's outputs and bindings; `tile_rows` receives the rows per tile.
  const vk::raii::Pipeline& begin_render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs,
                                         const ImageTarget* target, uint32_t& tile_rows) {
    const bool lo_parts = needs_lo_parts(anchor, scene_radius, camera.from);
    const vk::raii::Pipeline& chosen = pipeline->pipeline(
        aovs, lo_parts, target ? RaycastMode::image_target : RaycastMode::image_buffers, timings.pipeline_ms);
    if (planes) {  // no submission is in flight: every render waits for its own
      set_plane_heights(gpu_planes, scene_planes, camera.from, precision());
      std::memcpy(planes->buffer.mapped, gpu_planes.data(), gpu_planes.size() * sizeof(gpu::GpuPlane));
    }
    tile_rows = rows_per_tile(width, height, target ? AovSet{} : aovs);
    prepare_tile(width, tile_rows, aovs, target);
    return chosen;
  }

  // Casts the rays of one tile: resets the overflow list (and the depth range, for an image),
  // dispatches, and copies what the host reads into host-visible memory; waits for it.
  // Returns the dispatch's GPU time (its wall time, submission included, where there are no
  // timestamps).
  double dispatch_tile(const vk::raii::Pipeline& chosen, const gpu::RayGenParams& params) {
    const auto submitted = Clock::now();
    const bool to_image = tile.image_id != 0;
    context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      if (*timestamps) {
        commands.resetQueryPool(*timestamps, 0, 3);
        commands.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *timestamps, 0);
      }
      if (tile.overflow || to_image) {
        if (tile.overflow) commands.fillBuffer(*tile.overflow->written.buffer, 0, sizeof(uint32_t), 0u);
        if (to_image) {  // (+infinity, 0): see DepthRangeBits
          commands.fillBuffer(*depth_range->written.buffer, 0, sizeof(uint32_t), std::bit_cast<uint32_t>(INFINITY));
          commands.fillBuffer(*depth_range->written.buffer, sizeof(uint32_t), VK_WHOLE_SIZE, 0u);
        }
        const vk::MemoryBarrier cleared(vk::AccessFlagBits::eTransferWrite,
                                        vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
        commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {},
                                 cleared, {}, {});
      }
      pipeline->bind(commands, chosen, params);
      const vk::Extent2D group = workgroup_footprint(tile.mode);
      commands.dispatch((tile.width + group.width - 1) / group.width, (params.image.w + group.height - 1) / group.height, 1);
      if (*timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eComputeShader, *timestamps, 1);
      // Make the shader's writes visible to the copy into host-visible memory, and to the host.
      const vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                                      vk::AccessFlagBits::eTransferRead | vk::AccessFlagBits::eHostRead);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                               vk::PipelineStageFlagBits::eTransfer | vk::PipelineStageFlagBits::eHost, {}, barrier, {},
                               {});
      bool copied = false;
      for (const auto* output :
           {&tile.depth, &tile.normal, &tile.uv, &tile.overflow, &tile.hits, to_image ? &depth_range : nullptr}) {
        if (output && *output && (*output)->readback) {
          const vk::DeviceSize bytes = (*output)->bytes_written(vk::DeviceSize{tile.width} * params.image.w);
          commands.copyBuffer(*(*output)->written.buffer, *(*output)->readback->buffer, vk::BufferCopy(0, 0, bytes));
          timings.readback_bytes += bytes;
          copied = true;
        }
      }
      if (copied) {  // a fence wait alone does not make device writes visible to the host
        const vk::MemoryBarrier to_host(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
        commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, to_host,
                                 {}, {});
      }
      if (*timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *timestamps, 2);
    });

    double dispatch_ms = elapsed_ms(submitted);
    if (*timestamps) {
      const auto [result, ticks] = timestamps.getResults<uint64_t>(
          0, 3, 3 * sizeof(uint64_t), sizeof(uint64_t), vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
      const double period_ms = context.info.timestamp_period_ns * 1e-6;
      dispatch_ms = static_cast<double>(ticks[1] - ticks[0]) * period_ms;
      timings.dispatch_gpu_ms += dispatch_ms;
      timings.readback_ms += static_cast<double>(ticks[2] - ticks[1]) * period_ms;
    }
    ++timings.tiles;
    timings.longest_dispatch_ms = std::max(timings.longest_dispatch_ms, dispatch_ms);
    return dispatch_ms;
  }

  // The GPU time of `repeats` passes over a camera's whole image in one submission, back to back,
  // with nothing read back: see Renderer::sustained_dispatch_ms.
  double sustained_dispatch_ms(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs, uint32_t repeats) {
    uint32_t tile_rows = 0;
    const vk::raii::Pipeline& chosen = begin_render(camera, width, height, aovs, nullptr, tile_rows);
    const CameraBasis basis = make_camera_basis(camera, width, height);
    std::vector<gpu::RayGenParams> tiles;
    for (uint32_t first_row = 0; first_row < height; first_row += tile_rows) {
      tiles.push_back(make_ray_gen_params(basis, anchor, precision(), width, height, first_row,
                                          std::min(tile_rows, height - first_row), counts));
    }
    const vk::Extent2D group = workgroup_footprint(RaycastMode::image_buffers);
    const auto submitted = Clock::now();
    context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      if (*timestamps) {
        commands.resetQueryPool(*timestamps, 0, 2);
        commands.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *timestamps, 0);
      }
      // Each pass writes the outputs the last one wrote, and starts the list of unfinished rays
      // anew (its count would otherwise run past the list's end).
      const vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eTransferWrite,
                                      vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eShaderRead |
                                          vk::AccessFlagBits::eTransferWrite);
      const auto stages = vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer;
      for (uint32_t pass = 0; pass < repeats; ++pass) {
        for (const gpu::RayGenParams& params : tiles) {
          if (tile.overflow) {
            commands.fillBuffer(*tile.overflow->written.buffer, 0, sizeof(uint32_t), 0u);
            commands.pipelineBarrier(stages, stages, {}, written, {}, {});
          }
          pipeline->bind(commands, chosen, params);
          commands.dispatch((width + group.width - 1) / group.width, (params.image.w + group.height - 1) / group.height, 1);
          commands.pipelineBarrier(stages, stages, {}, written, {}, {});
        }
      }
      if (*timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *timestamps, 1);
    });
    double total_ms = elapsed_ms(submitted);
    if (*timestamps) {
      const auto [result, ticks] = timestamps.getResults<uint64_t>(
          0, 2, 2 * sizeof(uint64_t), sizeof(uint64_t), vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
      total_ms = static_cast<double>(ticks[1] - ticks[0]) * context.info.timestamp_period_ns * 1e-6;
    }
    return total_ms / repeats;
  }

  // Writes the pixels the CPU finished into `target`, after the shader's writes.
  void write_patches(const std::vector<PixelPatch>& patches, ImageTarget& target) {
    GpuBuffer staging = create_upload_buffer(context, patches.size() * sizeof(glm::vec4));
    std::vector<vk::BufferImageCopy> regions;
    regions.reserve(patches.size());
    auto* values = static_cast<glm::vec4*>(staging.mapped);
    for (size_t k = 0; k < patches.size(); ++k) {
      values[k] = patches[k].value;
      regions.emplace_back(k * sizeof(glm::vec4), 0, 0, color_layer,
                           vk::Offset3D(int32_t(patches[k].i), int32_t(patches[k].j), 0), vk::Extent3D(1, 1, 1));
    }
    const vk::Image image = *target.image().image;
    context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      transition_image(commands, image, vk::PipelineStageFlagBits::eComputeShader, vk::AccessFlagBits::eShaderWrite,
                       vk::ImageLayout::eGeneral, vk::PipelineStageFlagBits::eTransfer, vk::AccessFlagBits::eTransferWrite,
                       vk::ImageLayout::eTransferDstOptimal);
      commands.copyBufferToImage(*staging.buffer, image, vk::ImageLayout::eTransferDstOptimal, regions);
      transition_image(commands, image, vk::PipelineStageFlagBits::eTransfer, vk::AccessFlagBits::eTransferWrite,
                       vk::ImageLayout::eTransferDstOptimal, vk::PipelineStageFlagBits::eComputeShader,
                       vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite, vk::ImageLayout::eGeneral);
    });
  }
};

void RayHits::allocate(size_t ray_count, bool doubles) {
  count = ray_count;
  t.resize(count);
  normal.resize(3 * count);
  object.resize(count);
  primitive.resize(count);
  t64.resize(doubles ? count : 0);
  normal64.resize(doubles ? 3 * count : 0);
}

void RayHits::store(size_t ray, double distance, const glm::dvec3& unit_normal, ObjectPrimitive source) {
  t[ray] = static_cast<float>(distance);
  for (int c = 0; c < 3; ++c) normal[c * count + ray] = static_cast<float>(unit_normal[c]);
  if (!t64.empty()) {
    t64[ray] = distance;
    for (int c = 0; c < 3; ++c) normal64[c * count + ray] = unit_normal[c];
  }
  object[ray] = source.object;
  primitive[ray] = source.primitive;
}

Renderer::Renderer(GpuDevice& device, const Scene& scene, RendererOptions options)
    : impl_(std::make_unique<Impl>(device.vulkan(), options)) {
  with_vulkan_errors("uploading the scene", [&] {
    const auto start = Clock::now();
    Impl& r = *impl_;
    r.context.check_usable();
    // A search asked for by name is refused before anything is built or uploaded (a ray-query
    // upload asks for device features a device without them never enabled).
    if (const std::string obstacle = search_obstacle(options.scene.search, r.context.info, options.shader); !obstacle.empty()) {
      throw GpuError("traversal '" + std::string(traversal_name(options.scene.search)) + "' cannot run on " +
                     r.context.info.name + ": " + obstacle);
    }
    const std::string packet_obstacle = search_obstacle(PrimitiveSearch::bvh_packet, r.context.info, options.shader);
    GpuSceneOptions scene_options = options.scene;
    scene_options.packet_walk = r.context.info.favours_packet_walk && packet_obstacle.empty();
    // The packet walk's pipeline does not depend on the tree: the first one is made on a second
    // thread while the tree builds and the scene uploads, and kept if the built scene is as planned.
    const GpuSceneShape planned = plan_gpu_scene(scene, scene_options);
    std::optional<RaycastPipeline> early_pipeline;
    std::future<double> early_creation;
    if (!options.first_aovs.empty() && planned.search == PrimitiveSearch::bvh_packet && packet_obstacle.empty()) {
      early_pipeline.emplace(r.context, specialization_for(planned, 0, tree_loop_budget(planned, r.context.info, options.loop_budget),
                                                           options.shader));
      const bool lo_parts = needs_lo_parts(scene_anchor(scene), scene_radius(scene, scene_anchor(scene)), scene.camera.from);
      early_creation = std::async(std::launch::async, [&early_pipeline, &options, lo_parts] {
        double created_ms = 0.0;
        early_pipeline->pipeline(options.first_aovs.on_device(), lo_parts, RaycastMode::image_buffers, created_ms);
        return created_ms;
      });
    }
    // Joins the second thread however the constructor ends: it uses the pipeline above.
    const auto join_early = [&] {
      return early_creation.valid() ? early_creation.get() : 0.0;
    };
    struct Joiner {
      std::future<double>& creation;
      ~Joiner() {
        if (creation.valid()) creation.wait();
      }
    } joiner{early_creation};
    const GpuScene gpu_scene = make_gpu_scene(scene, scene_options, options.shader);
    if (gpu_scene.search == PrimitiveSearch::bvh_packet && !packet_walk_fits(gpu_scene.bvh_depth)) {
      throw GpuError("the packet walk keeps its stack in registers, for trees up to " +
                     std::to_string(VKRAY_STACK_REGISTERS_MAX) + " deep; this one is " + std::to_string(gpu_scene.bvh_depth));
    }
    const vk::DeviceSize buffer_limit = r.binding_limit();
    auto upload = [&]<typename T>(const std::vector<T>& items, const char* what,
                                  vk::BufferUsageFlags extra_usage = {}) -> std::optional<TexelBuffer> {
      static_assert(sizeof(T) % texel_bytes == 0);
      if (items.empty()) return std::nullopt;
      const vk::DeviceSize bytes = items.size() * sizeof(T);
      if (bytes > buffer_limit) {
        throw GpuError("the scene's " + std::string(what) + " take " + std::to_string(bytes >> 20) + " MiB, more than " +
                       r.context.info.name + " can bind as one buffer (" + std::to_string(buffer_limit >> 20) +
                       " MiB)");
      }
      return make_texel_buffer(r.context, items.data(), bytes, extra_usage);
    };
    r.spheres = upload(gpu_scene.spheres, "spheres");
    if (!gpu_scene.planes.empty()) {  // host-visible: their heights above the camera change every render
      const vk::DeviceSize bytes = gpu_scene.planes.size() * sizeof(gpu::GpuPlane);
      r.planes.emplace(TexelBuffer{create_upload_buffer(r.context, bytes, geometry_usage)});
      r.planes->floats = create_texel_view(r.context, r.planes->buffer, vk::Format::eR32G32B32A32Sfloat);
      r.planes->uints = create_texel_view(r.context, r.planes->buffer, vk::Format::eR32G32B32A32Uint);
      r.gpu_planes = gpu_scene.planes;
      r.scene_planes = scene.planes;
    }
    r.primitives = upload(gpu_scene.primitives, "triangles and spheres");
    const bool ray_query = gpu_scene.search == PrimitiveSearch::ray_query;
    // The ray-query traversal's structures are built from the vertex buffer itself.
    r.vertices = upload(gpu_scene.vertices, "vertices",
                        ray_query ? vk::BufferUsageFlagBits::eAccelerationStructureBuildInputReadOnlyKHR |
                                        vk::BufferUsageFlagBits::eShaderDeviceAddress
                                  : vk::BufferUsageFlags{});
    r.normals = upload(gpu_scene.normal_texels, "triangle normals");
    r.bvh_nodes = upload(gpu_scene.bvh_nodes, "BVH nodes");
    r.hit_sources = gpu_scene.hit_sources;
    r.stats = SceneStats{gpu_scene.triangle_count, static_cast<uint32_t>(scene.spheres.size()),
                         gpu_scene.geometry_bytes(), static_cast<uint32_t>(gpu_scene.bvh_nodes.size()),
                         gpu_scene.bvh_depth, gpu_scene.search, 0};
    double structures_ms = 0.0;
    if (ray_query) {
      StructureInput input;
      input.vertices = &r.vertices->buffer;
      input.vertex_count = static_cast<uint32_t>(gpu_scene.vertices.size());
      input.vertex_stride = sizeof(gpu::GpuPoint);
      for (const auto& mesh : gpu_scene.structure_meshes) {
        input.meshes.push_back({mesh.first, mesh.count});
        for (uint32_t slot = mesh.first; slot < mesh.first + mesh.count; ++slot) {
          const glm::uvec4& record = gpu_scene.primitives[slot].indices;
          input.triangles.push_back({record.x, record.y, record.z});
        }
      }
      input.sphere_boxes = gpu_scene.sphere_boxes;
      input.first_sphere_slot = gpu_scene.structure_spheres.first;
      r.structures.emplace(r.context, input);
      r.stats.geometry_bytes += r.structures->bytes();
      structures_ms = r.structures->build_ms();
    }

    r.stats.loop_budget = tree_loop_budget(gpu_scene.shape(), r.context.info, options.loop_budget);
    r.host_scene = scene;

    const ShaderVariant& shader = options.shader;
    const uint32_t group_size = shader.workgroup_width * shader.workgroup_height;
    if (group_size == 0 || group_size > r.context.limits.maxComputeWorkGroupInvocations ||
        shader.workgroup_width > r.context.limits.maxComputeWorkGroupSize[0] ||
        shader.workgroup_height > r.context.limits.maxComputeWorkGroupSize[1]) {
      throw GpuError(r.context.info.name + " has no " + std::to_string(shader.workgroup_width) + "x" +
                     std::to_string(shader.workgroup_height) + " compute workgroups");
    }
    const bool square_power_of_two = shader.workgroup_width == shader.workgroup_height && (group_size & (group_size - 1)) == 0;
    if (shader.morton_order && !(square_power_of_two && shader.workgroup_width <= 16)) {
      throw std::invalid_argument("Morton order needs a square power-of-two workgroup of at most 16x16");
    }

    r.anchor = gpu_scene.anchor;
    r.scene_radius = gpu_scene.radius;
    r.placeholder = create_storage_buffer(r.context, texel_bytes);
    r.placeholder_image = std::make_unique<ImageTarget>(device, 1, 1);
    const std::array<uint32_t, 4> zero_texel{};
    r.placeholder_texels = make_texel_buffer(r.context, zero_texel.data(), texel_bytes);
    checked_count(gpu_scene.spheres.size(), "spheres");
    checked_count(gpu_scene.planes.size(), "planes");
    const PipelineSpecialization specialization =
        specialization_for(gpu_scene.shape(), gpu_scene.bvh_depth, r.stats.loop_budget, options.shader);
    r.counts = run_time_counts(gpu_scene);
    const double early_ms = join_early();
    if (early_pipeline && early_pipeline->specialization() == specialization) {
      r.pipeline.emplace(std::move(*early_pipeline));
      r.timings.pipeline_beside_upload_ms = early_ms;
    } else {
      r.pipeline.emplace(r.context, specialization);
    }
    if (r.context.info.timestamp_period_ns > 0.0) {
      r.timestamps = vk::raii::QueryPool(r.context.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 3));
    }
    r.timings.bvh_build_ms = gpu_scene.bvh_build_ms;
    r.timings.structures_ms = structures_ms;
    r.timings.upload_ms = elapsed_ms(start);
  });
}

Renderer::~Renderer() = default;

const RenderTimings& Renderer::timings() const { return impl_->timings; }

const SceneStats& Renderer::scene_stats() const { return impl_->stats; }

Frame Renderer::render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs) {
  check_image_size(width, height);
  Impl& r = *impl_;
  if (r.options.shader.generic) {  // it writes them all
    for (const Aov written : {Aov::depth, Aov::normal, Aov::uv}) aovs.add(written);
  }
  Frame frame(width, height, aovs);
  frame.camera = camera;
  frame.allocate(r.precision() == Precision::float64);
  r.reset_timings();
  if (aovs.empty()) return frame;
  const AovSet device_aovs = aovs.on_device();
  if (camera.projection != Projection::perspective) {
    // Rays that do not leave one point through an image plane's pixels: the pixels' rays in double
    // (pixel_ray), cast as given rays. cast_rays picks their walk: an equirectangular image's from
    // its one origin in packets of its rows, an orthographic image's one by one.
    if (device_aovs.needs_rays() || device_aovs.has(Aov::hit)) {
      const CameraBasis basis = make_camera_basis(camera, width, height);
      std::vector<GivenRay> rays(frame.pixel_count());
      parallel_for_chunks(height, [&](size_t first_row, size_t end_row) {
        for (auto j = static_cast<uint32_t>(first_row); j < end_row; ++j) {
          for (uint32_t i = 0; i < width; ++i) {
            const PixelRay ray = pixel_ray(camera, basis, i, j, width, height);
            rays[size_t{j} * width + i] = {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z};
          }
        }
      }, 16);
      const RayHits hits = cast_rays(rays);
      const size_t pixels = frame.pixel_count();
      parallel_for_chunks(pixels, [&](size_t begin, size_t end) {
        for (size_t p = begin; p < end; ++p) {
          if (!frame.depth.empty()) frame.depth[p] = hits.t[p];
          if (!frame.depth64.empty()) frame.depth64[p] = hits.t64[p];
          for (size_t c = 0; c < 3; ++c) {
            if (!frame.normal.empty()) frame.normal[c * pixels + p] = hits.normal[c * pixels + p];
            if (!frame.normal64.empty()) frame.normal64[c * pixels + p] = hits.normal64[c * pixels + p];
          }
          store_ids(frame, p, {hits.object[p], hits.primitive[p]});
        }
      });
    }
    if (!frame.uv.empty()) fill_pixel_uv(frame);
    frame.round_doubles();
    add_camera_outputs(frame);
    add_surface_outputs(frame, r.host_scene);
    return frame;
  }

  with_vulkan_errors("rendering", [&] {
    const CameraBasis basis = make_camera_basis(camera, width, height);
    uint32_t tile_rows = 0;
    const vk::raii::Pipeline& pipeline = r.begin_render(camera, width, height, device_aovs, nullptr, tile_rows);
    r.dispatch_camera_rows(pipeline, basis, width, height, tile_rows, RaycastMode::image_buffers, [&](uint32_t first_row, uint32_t rows) {
      const auto copy_start = Clock::now();
      // The shader packs each plane of this tile to width * rows floats (see raycast.comp); each
      // lands in the same plane of the frame.
      const size_t first_pixel = size_t{first_row} * width;
      const size_t tile_pixels = size_t{rows} * width;
      auto copy_planes = [&]<typename T>(const std::optional<OutputBuffer>& output, std::vector<T>& target, size_t planes) {
        if (!output) return;
        const auto* source = static_cast<const T*>(output->host());
        for (size_t plane = 0; plane < planes; ++plane) {
          std::memcpy(target.data() + plane * frame.pixel_count() + first_pixel,
                      source + plane * tile_pixels, tile_pixels * sizeof(T));
        }
      };
      if (r.precision() == Precision::float64) {
        copy_planes(r.tile.depth, frame.depth64, 1);
        copy_planes(r.tile.normal, frame.normal64, 3);
      } else {
        copy_planes(r.tile.depth, frame.depth, 1);
        copy_planes(r.tile.normal, frame.normal, 3);
      }
      copy_planes(r.tile.uv, frame.uv, 2);
      if (r.tile.hits) {  // the device's slots, as the scene numbers them
        const auto* slots = static_cast<const uint32_t*>(r.tile.hits->host());
        parallel_for_chunks(tile_pixels, [&](size_t begin, size_t end) {
          for (size_t k = begin; k < end; ++k) store_ids(frame, first_pixel + k, r.hit_sources(slots[k]));
        });
      }
      r.timings.readback_ms += elapsed_ms(copy_start);
      if (r.tile.overflow) {
        r.finish_unfinished_rays(basis, width, height, first_row, [&](uint32_t i, uint32_t j, const ReferenceHit& hit) {
          store_reference_hit(frame, size_t{j} * width + i, hit);
          store_ids(frame, size_t{j} * width + i, r.reference->source(hit));
        });
      }
    });
  });
  frame.round_doubles();
  add_camera_outputs(frame);
  add_surface_outputs(frame, r.host_scene);
  return frame;
}

double Renderer::sustained_dispatch_ms(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs,
                                       uint32_t repeats) {
  check_image_size(width, height);
  if (camera.projection != Projection::perspective) {
    throw InputError("sustained dispatches are timed for perspective cameras, whose rays the device makes");
  }
  Impl& r = *impl_;
  r.reset_timings();
  double ms = 0.0;
  with_vulkan_errors("rendering", [&] { ms = r.sustained_dispatch_ms(camera, width, height, aovs.on_device(), std::max(repeats, 1u)); });
  return ms;
}

RayHits Renderer::cast_rays(std::span<const GivenRay> rays) {
  check_given_rays(rays);
  Impl& r = *impl_;
  RayHits hits;
  hits.allocate(rays.size(), r.precision() == Precision::float64);
  r.reset_timings();
  if (rays.empty()) return hits;

  with_vulkan_errors("casting rays", [&] {
    const AovSet aovs{Aov::depth, Aov::normal};
    // Rows of `width` holding `positions`, at most as many as the device's buffers hold.
    auto tile_rows = [&](uint32_t width, size_t positions, RaycastMode mode) {
      return r.rows_per_tile(width, static_cast<uint32_t>(std::min<size_t>((positions + width - 1) / width, UINT32_MAX)), aovs, mode);
    };
    // Rays from one origin (a camera's, a LiDAR's) walk the tree in packets as a camera's pixels
    // do, where the camera's rays would (the float32 packet walk): one by one they take five times
    // as long (README, "Python"). A packet's rays must point nearly the same way: rays listed as an
    // image's rows keep their places, as a camera's pixels; others are ordered by direction, 64
    // consecutive ones a packet, in tiles of whole packets (where the device's buffers hold one).
    const std::optional<glm::dvec3> origin =
        r.stats.search == PrimitiveSearch::bvh_packet && r.precision() == Precision::float32 ? shared_origin(rays)
                                                                                             : std::nullopt;
    if (const std::optional<uint32_t> rows_width = origin ? scan_width(rays) : std::nullopt) {
      r.timings.given_walk = GivenRayWalk::packets_in_place;
      r.cast_given(rays, RaycastMode::given_directions, *rows_width,
                   tile_rows(*rows_width, rays.size(), RaycastMode::given_directions), rays.size(), &*origin, nullptr, hits);
      return;
    }
    if (origin) {
      const size_t positions = (rays.size() + packet_block_positions - 1) / packet_block_positions * packet_block_positions;
      const uint32_t rows = tile_rows(VKRAY_PACKET_GROUP_WIDTH, positions, RaycastMode::given_directions) /
                            VKRAY_PACKET_ROWS * VKRAY_PACKET_ROWS;
      if (rows > 0) {
        r.timings.given_walk = GivenRayWalk::packets_by_direction;
        const auto order_start = Clock::now();
        const std::vector<uint32_t> order = order_by_direction(rays);
        r.timings.rays_ms += elapsed_ms(order_start);
        r.cast_given(rays, RaycastMode::given_directions, VKRAY_PACKET_GROUP_WIDTH, rows, positions, &*origin, &order, hits);
        return;
      }
    }
    // Rows of one workgroup's width: a workgroup then holds consecutive rays, which callers
    // usually order as they lie in space (a scan line, an image's rows).
    r.timings.given_walk = GivenRayWalk::one_by_one;
    const uint32_t width = r.options.shader.workgroup_width;
    r.cast_given(rays, RaycastMode::given_rays, width, tile_rows(width, rays.size(), RaycastMode::given_rays), rays.size(),
                 nullptr, nullptr, hits);
  });
  return hits;
}

DepthRange Renderer::render(const Camera& camera, Aov aov, ImageTarget& target) {
  const uint32_t width = target.width(), height = target.height();
  check_image_size(width, height);
  if (camera.projection != Projection::perspective) {
    throw InputError(std::string("the viewer draws perspective cameras; `vkray render` writes ") +
                     projection_name(camera.projection) + " ones");
  }
  Impl& r = *impl_;
  if (r.options.shader.generic || r.precision() != Precision::float32) {
    throw std::logic_error("the storage-image target takes a float32 shader specialized on its output");
  }
  r.reset_timings();
  DepthRange depths;
  with_vulkan_errors("rendering", [&] {
    const CameraBasis basis = make_camera_basis(camera, width, height);
    if (!r.depth_range) r.depth_range = r.make_output(0, 0, sizeof(gpu::DepthRangeBits));
    uint32_t tile_rows = 0;
    const vk::raii::Pipeline& pipeline = r.begin_render(camera, width, height, AovSet{aov}, &target, tile_rows);
    std::vector<PixelPatch> patches;
    r.dispatch_camera_rows(pipeline, basis, width, height, tile_rows, RaycastMode::image_target, [&](uint32_t first_row, uint32_t) {
      if (aov == Aov::depth) {
        const auto& bits = static_cast<const gpu::DepthRangeBits*>(r.depth_range->host())->near_far;
        if (bits.y != 0) depths.add(std::bit_cast<float>(bits.x)), depths.add(std::bit_cast<float>(bits.y));
      }
      if (r.tile.overflow) {
        // The values store_reference_hit puts in a Frame, as the shader stores them.
        r.finish_unfinished_rays(basis, width, height, first_row, [&](uint32_t i, uint32_t j, const ReferenceHit& hit) {
          const float depth = static_cast<float>(hit.t);
          patches.push_back({i, j, aov == Aov::depth ? glm::vec4(depth, 0.0f, 0.0f, 0.0f) : glm::vec4(glm::vec3(hit.normal), 0.0f)});
          if (aov == Aov::depth && std::isfinite(depth)) depths.add(depth);
        });
      }
    });
    if (!patches.empty()) r.write_patches(patches, target);
  });
  return depths;
}

}  // namespace vkray
