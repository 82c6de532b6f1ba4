#include "engine/render/renderer_impl.hpp"

#include "engine/parallel.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/stopwatch.hpp"
#include "engine/surface_outputs.hpp"
#include "engine/vulkan/image.hpp"

#include <algorithm>
#include <cstring>

namespace vkray {
namespace {

// Bytes per pixel of each output buffer: depth and normal components are floats, or doubles with
// the float64 shader.
vk::DeviceSize depth_bytes(Precision precision) { return precision == Precision::float64 ? sizeof(double) : sizeof(float); }
vk::DeviceSize normal_bytes(Precision precision) { return 3 * depth_bytes(precision); }
constexpr vk::DeviceSize uv_bytes = 2 * sizeof(float);

}  // namespace

TexelBuffer texel_views_of(VulkanContext& context, GpuBuffer buffer) {
  TexelBuffer texels{std::move(buffer)};
  texels.floats = create_texel_view(context, texels.buffer, vk::Format::eR32G32B32A32Sfloat);
  texels.uints = create_texel_view(context, texels.buffer, vk::Format::eR32G32B32A32Uint);
  return texels;
}

vk::Extent2D Renderer::Impl::workgroup_footprint(RaycastMode mode) const {
  if (stats.search == PrimitiveSearch::bvh_packet && mode != RaycastMode::given_rays && mode != RaycastMode::points) {
    return {VKRAY_PACKET_GROUP_WIDTH, VKRAY_PACKET_GROUP_HEIGHT};
  }
  return {options.shader.workgroup_width, options.shader.workgroup_height};
}

vk::DeviceSize Renderer::Impl::binding_limit() const {
  const vk::DeviceSize binding = options.shader.storage_geometry
                                     ? vk::DeviceSize{context.limits.maxStorageBufferRange}
                                     : vk::DeviceSize{context.limits.maxTexelBufferElements} * texel_bytes;
  return std::min<vk::DeviceSize>(binding, context.info.max_allocation_bytes);
}

OutputBuffer Renderer::Impl::make_output(vk::DeviceSize pixels, vk::DeviceSize pixel_bytes,
                                          vk::DeviceSize header_bytes) {
  const vk::DeviceSize bytes = header_bytes + pixels * pixel_bytes;
  OutputBuffer output{create_storage_buffer(context, bytes,
                                            vk::BufferUsageFlagBits::eTransferSrc | vk::BufferUsageFlagBits::eTransferDst),
                      std::nullopt, pixel_bytes, header_bytes, std::nullopt};
  if (!output.written.mapped) output.readback = create_readback_buffer(context, bytes);
  return output;
}

void Renderer::Impl::prepare_tile(uint32_t width, uint32_t rows, AovSet aovs, const ImageTarget* target,
                                  RaycastMode mode, const CallerArrays* caller, uint32_t layers) {
  const uint64_t image_id = target ? target->id() : 0;
  auto fits = [&](const TileOutputs& outputs) {
    return outputs.width == width && outputs.rows == rows && outputs.aov_bits == aovs.bits() &&
           outputs.image_id == image_id && outputs.mode == mode && outputs.layers == layers;
  };
  // A call's imported arrays are bound for that call alone.
  const bool bind_anew = caller || caller_arrays_bound;
  if (fits(tile)) {
    if (!bind_anew) return;
  } else if (fits(parked_tile)) {
    std::swap(tile, parked_tile);
  } else {
    if (is_given(tile.mode) != is_given(mode)) std::swap(tile, parked_tile);  // the other kind's, kept
    tile = TileOutputs{width, rows, aovs.bits(), image_id, mode, layers, {}, {}, {}, {}, {}, {}, {}};
    const vk::DeviceSize pixels = vk::DeviceSize{width} * rows;
    // In place, the shader writes the caller's arrays and lists the rays it leaves to the host.
    const bool in_place = mode == RaycastMode::caller_arrays;
    if (!target && !in_place) {
      if (aovs.has(Aov::depth)) tile.depth = make_output(pixels * layers, depth_bytes(precision()));
      if (aovs.has(Aov::normal)) tile.normal = make_output(pixels * layers, normal_bytes(precision()));
      if (aovs.has(Aov::uv)) tile.uv = make_output(pixels, uv_bytes);
    }
    if (is_given(mode) && !in_place) {
      const vk::DeviceSize bytes = pixels * given_ray_bytes(mode);
      tile.rays = texel_views_of(context, create_upload_buffer(context, bytes, geometry_usage));
    }
    if ((is_given(mode) && !in_place) || (!target && aovs.has(Aov::hit))) tile.hits = make_output(pixels * layers, sizeof(uint32_t));
    if (tile.hits && instances) tile.instance_hits = make_output(pixels * layers, sizeof(uint32_t));
    if ((stats.loop_budget > 0 && (aovs.needs_rays() || is_given(mode))) || in_place) {
      tile.overflow = make_output(pixels, sizeof(uint32_t), sizeof(uint32_t));
    }
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
  resources.texel_views[VKRAY_BINDING_CALLER_RAYS] = caller ? *caller->ray_texels : *placeholder_texels.uints;
  resources.buffers[VKRAY_BINDING_HITS] = output(tile.hits);
  resources.texel_views[VKRAY_BINDING_BVH_BOUNDS] = floats(bvh_nodes);
  resources.texel_views[VKRAY_BINDING_BVH_LINKS] = uints(bvh_nodes);
  resources.texel_views[VKRAY_BINDING_APART_MASKS] = uints(apart_masks);
  resources.texel_views[VKRAY_BINDING_INSTANCES] = geometry(instances);
  resources.buffers[VKRAY_BINDING_INSTANCE_HITS] = output(tile.instance_hits);
  resources.texel_views[VKRAY_BINDING_PLACEMENTS] = geometry(placements);
  resources.texel_views[VKRAY_BINDING_WINDING_CAPS] = uints(winding_caps);
  resources.texel_views[VKRAY_BINDING_CAP_EDGES] = uints(cap_edges);
  // The same buffers whole, for the storage-geometry variant (pipeline->binding_type picks which
  // one a binding takes).
  auto whole = [&](const std::optional<TexelBuffer>& texels) {
    return *(texels ? texels->buffer.buffer : placeholder_texels.buffer.buffer);
  };
  for (const auto& [binding, texels] : {std::pair{VKRAY_BINDING_SPHERES, &spheres}, {VKRAY_BINDING_PLANES, &planes},
                                        {VKRAY_BINDING_PRIMITIVES, &primitives}, {VKRAY_BINDING_VERTICES, &vertices},
                                        {VKRAY_BINDING_NORMALS, &normals}, {VKRAY_BINDING_BVH_BOUNDS, &bvh_nodes},
                                        {VKRAY_BINDING_BVH_LINKS, &bvh_nodes}, {VKRAY_BINDING_RAYS, &tile.rays},
                                        {VKRAY_BINDING_APART_MASKS, &apart_masks}, {VKRAY_BINDING_INSTANCES, &instances},
                                        {VKRAY_BINDING_PLACEMENTS, &placements}, {VKRAY_BINDING_WINDING_CAPS, &winding_caps},
                                        {VKRAY_BINDING_CAP_EDGES, &cap_edges}}) {
    resources.buffers[binding] = whole(*texels);
  }
  resources.buffers[VKRAY_BINDING_DEPTH] = output(tile.depth);
  resources.buffers[VKRAY_BINDING_NORMAL] = output(tile.normal);
  resources.buffers[VKRAY_BINDING_UV] = output(tile.uv);
  resources.buffers[VKRAY_BINDING_OVERFLOW] = output(tile.overflow);
  resources.buffers[VKRAY_BINDING_DEPTH_RANGE] = output(depth_range);
  resources.buffers[VKRAY_BINDING_CALLER_RAYS] = caller ? *caller->rays.buffer.buffer : *placeholder_texels.buffer.buffer;
  resources.offsets[VKRAY_BINDING_CALLER_RAYS] = caller ? caller->rays.offset : 0;
  resources.buffers[VKRAY_BINDING_HIT_SOURCES] = *(hit_source_table ? *hit_source_table : placeholder).buffer;
  resources.buffers[VKRAY_BINDING_RAY_ORDER] = *(caller && caller->order ? caller->order->order() : placeholder).buffer;
  // The caller's arrays in place of the outputs, each bound from its first entry.
  for (const auto& [binding, imported] :
       {std::pair{VKRAY_BINDING_DEPTH, caller ? &caller->t : nullptr}, {VKRAY_BINDING_NORMAL, caller ? &caller->normal : nullptr},
        {VKRAY_BINDING_MESH_IDS, caller ? &caller->object : nullptr},
        {VKRAY_BINDING_PRIMITIVE_IDS, caller ? &caller->primitive : nullptr}}) {
    if (imported && *imported) {
      resources.buffers[binding] = *(*imported)->buffer.buffer;
      resources.offsets[binding] = (*imported)->offset;
    } else if (binding == VKRAY_BINDING_MESH_IDS || binding == VKRAY_BINDING_PRIMITIVE_IDS) {
      resources.buffers[binding] = *placeholder.buffer;
    }
  }
  caller_arrays_bound = caller != nullptr;
  resources.images[VKRAY_BINDING_IMAGE] = *(target ? *target : *placeholder_image).image().view;
  if (structures) resources.top_structure = structures->top();
  pipeline->bind_resources(resources);
}

uint32_t Renderer::Impl::rows_per_tile(uint32_t width, uint32_t height, AovSet buffer_aovs,
                                       RaycastMode mode, uint32_t layers) const {
  vk::DeviceSize largest = is_given(mode) && mode != RaycastMode::caller_arrays ? sizeof(uint32_t) : 0;  // the hits
  if (buffer_aovs.has(Aov::depth)) largest = std::max(largest, depth_bytes(precision()));
  if (buffer_aovs.has(Aov::normal)) largest = std::max(largest, normal_bytes(precision()));
  if (buffer_aovs.has(Aov::uv)) largest = std::max(largest, uv_bytes);
  largest *= layers;  // first hits: depth, normal and hits in a run of planes each (uv is a camera's alone)
  vk::DeviceSize limit = context.limits.maxStorageBufferRange;
  if (options.max_tile_bytes > 0) limit = std::min<vk::DeviceSize>(limit, options.max_tile_bytes);
  vk::DeviceSize by_bytes = largest > 0 ? std::max<vk::DeviceSize>(1, limit / (vk::DeviceSize{width} * largest)) : height;
  if (stats.loop_budget > 0 || mode == RaycastMode::caller_arrays) {  // the overflow list: a count, then 4 bytes a pixel
    by_bytes = std::min(by_bytes, std::max<vk::DeviceSize>(1, (limit - sizeof(uint32_t)) / (vk::DeviceSize{width} * 4)));
  }
  if (is_given(mode) && mode != RaycastMode::caller_arrays) {  // the rays: one texel buffer
    const vk::DeviceSize ray_limit = binding_limit();
    by_bytes = std::min(by_bytes, std::max<vk::DeviceSize>(1, ray_limit / (vk::DeviceSize{width} * given_ray_bytes(mode))));
  }
  const vk::DeviceSize by_groups =
      vk::DeviceSize{context.limits.maxComputeWorkGroupCount[1]} * workgroup_footprint(mode).height;
  return static_cast<uint32_t>(std::min<vk::DeviceSize>({height, by_bytes, by_groups}));
}

void Renderer::Impl::reset_timings() {
  RenderTimings fresh;  // the constructor's figures stay
  fresh.upload_ms = timings.upload_ms;
  fresh.bvh_build_ms = timings.bvh_build_ms;
  fresh.structures_ms = timings.structures_ms;
  fresh.pipeline_beside_upload_ms = timings.pipeline_beside_upload_ms;
  fresh.has_gpu_times = *timestamps != vk::QueryPool();
  timings = fresh;
}

const vk::raii::Pipeline& Renderer::Impl::begin_render(const Camera& camera, uint32_t width, uint32_t height,
                                                       AovSet aovs, const ImageTarget* target, uint32_t& tile_rows) {
  const bool lo_parts = needs_lo_parts(anchor, scene_radius, camera.from);
  const vk::raii::Pipeline& chosen = pipeline->pipeline(
      aovs, lo_parts, target ? RaycastMode::image_target : RaycastMode::image_buffers, timings.pipeline_ms);
  set_planes_above(camera.from);
  tile_rows = rows_per_tile(width, height, target ? AovSet{} : aovs);
  prepare_tile(width, tile_rows, aovs, target);
  return chosen;
}

template <typename Visit>
void Renderer::Impl::for_each_frame_plane(Frame& frame, Visit&& visit) {
  if (precision() == Precision::float64) {
    visit(tile.depth, frame.depth64, 1);
    visit(tile.normal, frame.normal64, 3);
  } else {
    visit(tile.depth, frame.depth, 1);
    visit(tile.normal, frame.normal, 3);
  }
  visit(tile.uv, frame.uv, 2);
}

Renderer::Impl::FrameLanding Renderer::Impl::land_in_frame(Frame& frame) {
  // Part of the readback's cost: a driver pins the pages it imports.
  const auto import_start = Clock::now();
  for_each_frame_plane(frame, [&]<typename T>(std::optional<OutputBuffer>& output, std::vector<T>& target, size_t) {
    if (!output || !output->readback || target.empty()) return;
    if (auto memory = import_host_memory(context, target.data(), target.size() * sizeof(T))) {
      output->frame_planes = OutputBuffer::FramePlanes{std::move(*memory), sizeof(T), frame.pixel_count()};
    }
  });
  timings.readback_ms += elapsed_ms(import_start);
  return FrameLanding{tile};
}

Renderer::Impl::FrameLanding::~FrameLanding() {
  for (std::optional<OutputBuffer>* output : {&tile.depth, &tile.normal, &tile.uv}) {
    if (*output) (*output)->frame_planes.reset();
  }
}

void Renderer::Impl::read_tile(Frame& frame, uint32_t first_row, uint32_t rows) {
  const uint32_t width = frame.width;
  const auto copy_start = Clock::now();
  // The shader packs each plane of this tile to width * rows floats (see raycast.comp); each
  // lands in the same plane of the frame.
  const size_t first_pixel = size_t{first_row} * width;
  const size_t tile_pixels = size_t{rows} * width;
  for_each_frame_plane(frame, [&]<typename T>(std::optional<OutputBuffer>& output, std::vector<T>& target, size_t plane_count) {
    if (!output || output->frame_planes) return;
    const auto* source = static_cast<const T*>(output->host());
    for (size_t plane = 0; plane < plane_count; ++plane) {
      std::memcpy(target.data() + plane * frame.pixel_count() + first_pixel,
                  source + plane * tile_pixels, tile_pixels * sizeof(T));
    }
  });
  if (tile.hits) {  // the device's slots, as the scene numbers them
    const auto* slots = static_cast<const uint32_t*>(tile.hits->host());
    const auto* instance_hits = tile.instance_hits ? static_cast<const uint32_t*>(tile.instance_hits->host()) : nullptr;
    parallel_for_chunks(tile_pixels, [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end; ++k) {
        store_ids(frame, first_pixel + k, hit_sources(slots[k]), instance_hits ? instance_hits[k] : no_object);
      }
    });
  }
  timings.readback_ms += elapsed_ms(copy_start);
}

void Renderer::Impl::set_planes_above(const glm::dvec3& origin) {
  if (!planes) return;
  set_plane_heights(gpu_planes, scene_planes, origin, precision());
  std::memcpy(planes->buffer.mapped, gpu_planes.data(), gpu_planes.size() * sizeof(gpu::GpuPlane));
}

}  // namespace vkray
