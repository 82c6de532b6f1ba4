#include "engine/parallel.hpp"
#include "engine/render/dispatch_sizer.hpp"
#include "engine/render/ray_order.hpp"
#include "engine/render/renderer_impl.hpp"
#include "engine/stopwatch.hpp"
#include "engine/unit_vector.hpp"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <numeric>

namespace vkray {
namespace {

// The packet walk's layout of given directions in an order (gpu::packet_order_index): 64
// consecutive rays of the order walk the tree together; a block of VKRAY_PACKET_ROWS rows holds
// whole packets.
constexpr uint32_t packet_rays = VKRAY_PACKET_COLUMNS * VKRAY_PACKET_ROWS;
constexpr uint32_t packet_block_positions = VKRAY_PACKET_GROUP_WIDTH * VKRAY_PACKET_ROWS;
static_assert(VKRAY_PACKET_GROUP_WIDTH % VKRAY_PACKET_COLUMNS == 0);

// What the shader writes for `query` besides each ray's hit: the depth and normal of the nearest
// hit or the first hits; nothing for an occlusion query or a count, whose answer is in the hits
// buffer alone (16 bytes a ray neither written nor read back).
AovSet given_ray_outputs(HitQuery query) {
  return query == HitQuery::nearest ? AovSet{Aov::depth, Aov::normal} : AovSet{};
}

}  // namespace

const char* given_ray_walk_name(GivenRayWalk walk) {
  switch (walk) {
    case GivenRayWalk::one_by_one: return "one by one";
    case GivenRayWalk::packets_in_place: return "packets in place";
    case GivenRayWalk::packets_in_order: return "packets in order";
    case GivenRayWalk::packets_by_direction: return "packets by direction";
    default: return "none";
  }
}

void RayHits::allocate(size_t ray_count, bool doubles, bool instances) {
  count = ray_count;
  instance.resize(instances ? count : 0);
  t.resize(count);
  normal.resize(3 * count);
  object.resize(count);
  primitive.resize(count);
  t64.resize(doubles ? count : 0);
  normal64.resize(doubles ? 3 * count : 0);
}

void RayHits::store(size_t ray, double distance, const glm::dvec3& unit_normal, ObjectPrimitive source,
                    uint32_t placing_instance) {
  if (!instance.empty()) instance[ray] = placing_instance;
  t[ray] = static_cast<float>(distance);
  for (int c = 0; c < 3; ++c) normal[c * count + ray] = static_cast<float>(unit_normal[c]);
  if (!t64.empty()) {
    t64[ray] = distance;
    for (int c = 0; c < 3; ++c) normal64[c * count + ray] = unit_normal[c];
  }
  object[ray] = source.object;
  primitive[ray] = source.primitive;
}

void Renderer::Impl::cast_given(const GivenRays& given, RaycastMode mode, uint32_t width, uint32_t tile_rows,
                                size_t positions, const glm::dvec3* origin, const std::vector<uint32_t>* order,
                                RayHits& hits) {
  const std::span<const GivenRay> rays = given.rays;
  const RayRanges& ranges = given.ranges;
  auto ray_at = [&](size_t position) {  // rays.size() for padding
    if (!order) return position;
    const size_t n = gpu::packet_order_index(static_cast<uint32_t>(position));
    return n < order->size() ? size_t{(*order)[n]} : rays.size();
  };
  // Ray k as traced: from the start of its range (RayRanges).
  auto traced = [&](size_t k) { return ranges.start(k) > 0.0 ? range_start_ray(rays[k], ranges.start(k)) : rays[k]; };
  const AovSet aovs = given_ray_outputs(given.query);
  // The lo parts of positions as for a camera (needs_lo_parts), wherever any of the rays starts.
  bool lo_parts = origin && needs_lo_parts(anchor, scene_radius, *origin);
  if (!origin) {
    std::atomic<bool> any_near = false;
    parallel_for_chunks(rays.size(), [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end && !any_near; ++k) {
        const GivenRay ray = traced(k);
        if (needs_lo_parts(anchor, scene_radius, {ray[0], ray[1], ray[2]})) any_near = true;
      }
    });
    lo_parts = any_near;
  }
  const vk::raii::Pipeline& chosen = pipeline->pipeline(aovs, lo_parts, mode, timings.pipeline_ms, given.query, given.hits);
  // The planes' heights above the one origin; rays from their own origins subtract it themselves.
  if (origin) set_planes_above(*origin);
  prepare_tile(width, tile_rows, aovs, nullptr, mode, nullptr, given.hits);
  double& ms_per_ray = origin ? camera_ms_per_pixel : given_ms_per_ray[{given.query, given.hits}];  // packets cost as pixels do
  DispatchSizer sizer(width, tile_rows, options.dispatch_budget_ms, ms_per_ray, workgroup_footprint(mode).height);
  gpu::RayGenParams params{};
  if (origin) params = make_ray_gen_params(CameraBasis{*origin, {}, {}, {}, 0.0}, anchor, precision(), 0, 0, 0, 0, counts);
  params.counts = counts;
  for (size_t first = 0, count = 0; first < positions; first += count) {
    count = std::min(size_t{width} * sizer.next_rows(), positions - first);
    const auto encode_start = Clock::now();
    parallel_for_chunks(count, [&](size_t begin, size_t end) {
      for (size_t p = begin; p < end; ++p) {
        const size_t listed = ray_at(first + p);
        const size_t k = listed < rays.size() ? listed : order->back();  // padding: the order's last ray again
        const double range_end = ranges.end(k) - ranges.start(k);  // from the range's start
        if (origin) {  // float32 alone: the packet walk's
          const glm::dvec3 direction(rays[k][3], rays[k][4], rays[k][5]);
          static_cast<glm::vec4*>(tile.rays->buffer.mapped)[p] = glm::vec4(glm::vec3(unit_vector(direction)), range_end);
        } else {
          const GivenRay ray = traced(k);
          static_cast<gpu::GpuRay*>(tile.rays->buffer.mapped)[p] =
              encode_ray({ray[0], ray[1], ray[2]}, {ray[3], ray[4], ray[5]}, range_end, anchor, precision());
        }
      }
    });
    timings.rays_ms += elapsed_ms(encode_start);
    params.image = glm::uvec4(width, static_cast<uint32_t>(count), 0, static_cast<uint32_t>((count + width - 1) / width));
    sizer.measured(params.image.w, dispatch_tile(chosen, params));
    ms_per_ray = sizer.slowest_ms_per_pixel();

    const auto copy_start = Clock::now();
    const auto* slots = static_cast<const uint32_t*>(tile.hits->host());  // with HitQuery::count: crossings
    const auto* instance_hits = tile.instance_hits ? static_cast<const uint32_t*>(tile.instance_hits->host()) : nullptr;
    const size_t plane_size = size_t{width} * params.image.w;  // the shader's planes span whole rows
    auto copy = [&]<typename T>(const T* depths, const T* unit_normals) {
      parallel_for_chunks(count, [&](size_t begin, size_t end) {
        for (size_t p = begin; p < end; ++p) {
          const size_t k = ray_at(first + p);
          if (k >= rays.size()) continue;
          for (size_t layer = 0; layer < given.hits; ++layer) {  // hit `layer` in the layer-th run of planes
            const size_t at = layer * plane_size + p;
            const T* layer_normals = unit_normals + 3 * layer * plane_size;
            const glm::dvec3 normal(layer_normals[p], layer_normals[plane_size + p], layer_normals[2 * plane_size + p]);
            hits.store(k * given.hits + layer, ranges.start(k) + depths[at], normal, hit_sources(slots[at]),
                       instance_hits ? instance_hits[at] : no_object);
          }
        }
      });
    };
    if (given.query == HitQuery::count) {  // one by one: no order
      std::memcpy(hits.crossings.data() + first, slots, count * sizeof(uint32_t));
    } else if (given.query == HitQuery::any) {  // whether each ray hit: its slot alone
      parallel_for_chunks(count, [&](size_t begin, size_t end) {
        for (size_t p = begin; p < end; ++p) {
          if (const size_t k = ray_at(first + p); k < rays.size()) hits.object[k] = hit_sources(slots[p]).object;
        }
      });
    } else if (!order && precision() == Precision::float32 && ranges.t_min.empty() && given.hits == 1) {  // in place: the planes as they are, the ids named
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
          if (instance_hits) hits.instance[first + k] = instance_hits[k];
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
        if (given.query == HitQuery::count) {
          hits.crossings[k] = count_reference_crossings(*reference, rays[k], ranges.start(k), ranges.end(k));
          return;
        }
        if (given.hits > 1) {
          const std::vector<ReferenceHit> first_hits =
              first_reference_hits(*reference, rays[k], ranges.start(k), ranges.end(k), given.hits);
          for (size_t layer = 0; layer < given.hits; ++layer) {
            const ReferenceHit& hit = first_hits[layer];
            hits.store(k * given.hits + layer, hit.t, hit.normal, reference->source(hit), hit.instance);
          }
          return;
        }
        const ReferenceHit hit = trace_reference_ray(*reference, rays[k], ranges.start(k), ranges.end(k));
        hits.store(k, hit.t, hit.normal, reference->source(hit), hit.instance);
      });
    }
  }
}

RayHits Renderer::Impl::cast_rays(const GivenRays& given) {
  const std::span<const GivenRay> rays = given.rays;
  check_given_rays(rays);
  check_ray_ranges(rays, given.ranges);
  if (given.hits < 1 || given.hits > VKRAY_HITS_MAX) {
    throw InputError("hits: " + std::to_string(given.hits) + " is not between 1 and " + std::to_string(VKRAY_HITS_MAX));
  }
  RayHits hits;
  hits.hits_per_ray = given.hits;
  if (given.query == HitQuery::count) {
    hits.count = rays.size();
    hits.crossings.resize(rays.size());
  } else {
    hits.allocate(rays.size() * given.hits, precision() == Precision::float64, instances.has_value());
  }
  reset_timings();
  if (rays.empty()) return hits;

  with_vulkan_errors("casting rays", [&] {
    const AovSet aovs = given_ray_outputs(given.query);
    // Rows of `width` holding `positions`, at most as many as the device's buffers hold.
    auto tile_rows = [&](uint32_t width, size_t positions, RaycastMode mode) {
      const auto rows = static_cast<uint32_t>(std::min<size_t>((positions + width - 1) / width, UINT32_MAX));
      return rows_per_tile(width, rows, aovs, mode, given.hits);
    };
    // Rays from one origin (a camera's, a LiDAR's) walk the tree in packets as a camera's pixels
    // do, where the camera's rays would (the float32 packet walk): one by one they take five times
    // as long (docs/python.md). A packet's rays must point nearly the same way: rays listed as an
    // image's rows keep their places, as a camera's pixels; others are ordered by direction, 64
    // consecutive ones a packet, in tiles of whole packets (where the device's buffers hold one).
    // Ranges that start past the origin move it, ray by ray: those rays walk one by one, as do
    // counts of crossings and first hits (the packet walk finds the nearest hit alone).
    const bool from_origins = std::all_of(given.ranges.t_min.begin(), given.ranges.t_min.end(), [](double t) { return t == 0.0; });
    const std::optional<glm::dvec3> origin =
        stats.search == PrimitiveSearch::bvh_packet && precision() == Precision::float32 && from_origins &&
                given.query != HitQuery::count && given.hits == 1
            ? shared_origin(rays)
            : std::nullopt;
    if (const std::optional<uint32_t> rows_width = origin ? scan_width(rays) : std::nullopt) {
      timings.given_walk = GivenRayWalk::packets_in_place;
      cast_given(given, RaycastMode::given_directions, *rows_width,
                 tile_rows(*rows_width, rays.size(), RaycastMode::given_directions), rays.size(), &*origin, nullptr, hits);
      return;
    }
    if (origin) {
      const size_t positions = (rays.size() + packet_block_positions - 1) / packet_block_positions * packet_block_positions;
      const uint32_t rows = tile_rows(VKRAY_PACKET_GROUP_WIDTH, positions, RaycastMode::given_directions) /
                            VKRAY_PACKET_ROWS * VKRAY_PACKET_ROWS;
      if (rows > 0) {
        // A list whose runs of 64 already point into small patches (a sensor's rings, scan lines)
        // makes packets as it is: sorting a million rays took as long as walking them.
        const auto order_start = Clock::now();
        std::vector<uint32_t> order;
        if (runs_stay_compact(rays, packet_rays)) {
          timings.given_walk = GivenRayWalk::packets_in_order;
          order.resize(rays.size());
          std::iota(order.begin(), order.end(), 0u);
        } else {
          timings.given_walk = GivenRayWalk::packets_by_direction;
          order = order_by_direction(rays);
        }
        timings.rays_ms += elapsed_ms(order_start);
        cast_given(given, RaycastMode::given_directions, VKRAY_PACKET_GROUP_WIDTH, rows, positions, &*origin, &order, hits);
        return;
      }
    }
    // Rows of one workgroup's width: a workgroup then holds consecutive rays, which callers
    // usually order as they lie in space (a scan line, an image's rows).
    timings.given_walk = GivenRayWalk::one_by_one;
    const uint32_t width = options.shader.workgroup_width;
    cast_given(given, RaycastMode::given_rays, width, tile_rows(width, rays.size(), RaycastMode::given_rays), rays.size(),
               nullptr, nullptr, hits);
  });
  return hits;
}

bool Renderer::Impl::casts_in_place() const {
  // The shader reads the caller's doubles in the float32 variant with double edge functions (in
  // packets or one by one); the float64 shader and ray queries take the host's encoding.
  return precision() == Precision::float32 && stats.search != PrimitiveSearch::ray_query &&
         resolve_edges(context.info, options.shader.edges) == EdgeArithmetic::double_products &&
         context.info.host_import_alignment > 0;
}

bool Renderer::Impl::cast_rays_in_place(std::span<const GivenRay> rays, const HitArrays& into) {
  if (!casts_in_place() || rays.empty() || rays.size() > UINT32_MAX / 3 || given_ray_fault(rays.front())) return false;
  reset_timings();
  const auto start = Clock::now();
  // One origin, as far as samples over the list show: the shader checks every ray against the
  // first and lists any other, so a sample only spares a list of many origins a wasted dispatch.
  const GivenRay& first = rays.front();
  constexpr size_t origin_samples = 1024;
  for (size_t sample = 0; sample < origin_samples; ++sample) {
    const GivenRay& ray = rays[(rays.size() - 1) * sample / (origin_samples - 1)];
    if (!std::equal(ray.begin(), ray.begin() + 3, first.begin())) return false;
  }
  // Packets as cast_rays makes them: an image's rows in place, runs of 64 that stay compact in
  // order, or any other list ordered by direction (on the device); one by one in rows of a
  // workgroup's width.
  const bool packets = stats.search == PrimitiveSearch::bvh_packet;
  uint32_t width = options.shader.workgroup_width;
  bool in_order = false, by_direction = false;
  timings.given_walk = GivenRayWalk::one_by_one;
  if (packets) {
    if (const std::optional<uint32_t> rows_width = scan_width(rays)) {
      width = *rows_width;
      timings.given_walk = GivenRayWalk::packets_in_place;
    } else {
      width = VKRAY_PACKET_GROUP_WIDTH;
      in_order = true;
      by_direction = !runs_stay_compact(rays, packet_rays);
      timings.given_walk = by_direction ? GivenRayWalk::packets_by_direction : GivenRayWalk::packets_in_order;
    }
  }
  const size_t count = rays.size();
  const size_t positions = in_order ? (count + packet_block_positions - 1) / packet_block_positions * packet_block_positions : count;
  const auto total_rows = static_cast<uint32_t>((positions + width - 1) / width);
  const AovSet aovs{Aov::depth, Aov::normal};
  uint32_t tile_rows = rows_per_tile(width, total_rows, aovs, RaycastMode::caller_arrays);
  if (in_order) tile_rows = tile_rows / VKRAY_PACKET_ROWS * VKRAY_PACKET_ROWS;
  // Texels for the texel-buffer variant and the ordering pass, a storage buffer for the other variant.
  const bool ray_texels = !options.shader.storage_geometry || by_direction;
  std::optional<CallerArrays> imported = tile_rows > 0 ? import_caller_arrays(rays, into, ray_texels) : std::nullopt;
  if (!imported) return false;
  CallerArrays& caller = *imported;
  const uint32_t written = (into.t ? VKRAY_CALLER_WRITE_T : 0u) | (into.normal ? VKRAY_CALLER_WRITE_NORMAL : 0u) |
                           (into.object ? VKRAY_CALLER_WRITE_MESH_ID : 0u) |
                           (into.primitive ? VKRAY_CALLER_WRITE_PRIMITIVE_ID : 0u) |
                           (by_direction ? VKRAY_CALLER_BY_DIRECTION : in_order ? VKRAY_CALLER_IN_ORDER : 0u);

  std::vector<uint32_t> listed;  // rays the shader left to the host, by index
  with_vulkan_errors("casting rays", [&] {
    if (!hit_source_table && !hit_sources.slots.empty()) {
      static_assert(sizeof(ObjectPrimitive) == 2 * sizeof(uint32_t));  // the shader's uvec2
      hit_source_table = upload_buffer(context, hit_sources.slots.data(), hit_sources.slots.size() * sizeof(ObjectPrimitive),
                                       vk::BufferUsageFlagBits::eStorageBuffer);
    }
    const glm::dvec3 origin(first[0], first[1], first[2]);
    const vk::raii::Pipeline& chosen =
        pipeline->pipeline(aovs, needs_lo_parts(anchor, scene_radius, origin), RaycastMode::caller_arrays, timings.pipeline_ms);
    set_planes_above(origin);
    timings.rays_ms += elapsed_ms(start);
    if (by_direction) {  // the device's time, not the host's
      if (!direction_order) direction_order.emplace(context);
      timings.order_gpu_ms = direction_order->run(*caller.ray_texels, static_cast<uint32_t>(count));
      timings.dispatch_gpu_ms += timings.order_gpu_ms;
      caller.order = &*direction_order;
    }
    const auto bind_start = Clock::now();
    prepare_tile(width, tile_rows, aovs, nullptr, RaycastMode::caller_arrays, &caller);
    timings.rays_ms += elapsed_ms(bind_start);

    gpu::RayGenParams params = make_ray_gen_params(CameraBasis{origin, {}, {}, {}, 0.0}, anchor, precision(), 0, 0, 0, 0, counts);
    params.counts = counts;
    params.camera[5] = glm::uvec4(written, 0u, hit_sources.first_sphere_object, hit_sources.first_plane_object);
    double& ms_per_ray = packets ? camera_ms_per_pixel : given_ms_per_ray[{HitQuery::nearest, 1}];  // packets cost as pixels do
    DispatchSizer sizer(width, tile_rows, options.dispatch_budget_ms, ms_per_ray,
                        workgroup_footprint(RaycastMode::caller_arrays).height);
    for (uint32_t first_row = 0, rows = 0; first_row < total_rows; first_row += rows) {
      rows = std::min(sizer.next_rows(), total_rows - first_row);
      params.image = glm::uvec4(width, static_cast<uint32_t>(count), first_row, rows);
      sizer.measured(rows, dispatch_tile(chosen, params));
      ms_per_ray = sizer.slowest_ms_per_pixel();
      const std::span<const uint32_t> left = listed_rays();  // by the rays' indices
      listed.insert(listed.end(), left.begin(), left.end());
    }
  });
  timings.rays_in_place = true;
  if (!listed.empty()) cast_listed_again(rays, listed, into);
  return true;
}

std::optional<CallerArrays> Renderer::Impl::import_caller_arrays(std::span<const GivenRay> rays, const HitArrays& into,
                                                                 bool ray_texels) {
  // Each array bound whole, from its first entry (the binding's offset alignment).
  const vk::PhysicalDeviceLimits& limits = context.limits;
  const size_t count = rays.size();
  const vk::DeviceSize ray_bytes = count * sizeof(GivenRay);
  const bool rays_bind = (!ray_texels || 3 * count <= limits.maxTexelBufferElements) &&
                         (!options.shader.storage_geometry || ray_bytes <= limits.maxStorageBufferRange);
  if (!rays_bind || count * 3 * sizeof(float) > limits.maxStorageBufferRange) return std::nullopt;
  CallerArrays caller;
  std::optional<ImportedHostMemory> imported_rays = import_host_memory(context, rays.data(), ray_bytes, geometry_usage);
  if (!imported_rays || (ray_texels && imported_rays->offset % limits.minTexelBufferOffsetAlignment != 0) ||
      (options.shader.storage_geometry && imported_rays->offset % limits.minStorageBufferOffsetAlignment != 0)) {
    return std::nullopt;
  }
  caller.rays = std::move(*imported_rays);
  auto import_output = [&](void* data, vk::DeviceSize bytes, std::optional<ImportedHostMemory>& imported) {
    if (!data) return true;
    imported = import_host_memory(context, data, bytes, vk::BufferUsageFlagBits::eStorageBuffer);
    return imported && imported->offset % limits.minStorageBufferOffsetAlignment == 0;
  };
  if (!import_output(into.t, count * sizeof(float), caller.t) ||
      !import_output(into.normal, 3 * count * sizeof(float), caller.normal) ||
      !import_output(into.object, count * sizeof(uint32_t), caller.object) ||
      !import_output(into.primitive, count * sizeof(uint32_t), caller.primitive)) {
    return std::nullopt;
  }
  if (ray_texels) {
    with_vulkan_errors("binding the caller's rays", [&] {
      caller.ray_texels = create_texel_view(context, caller.rays.buffer, vk::Format::eR32G32B32A32Uint, caller.rays.offset, ray_bytes);
    });
  }
  return caller;
}

void Renderer::Impl::cast_listed_again(std::span<const GivenRay> rays, std::vector<uint32_t>& listed, const HitArrays& into) {
  // The first bad ray by its index among all the rays (the shader lists every bad one), as
  // check_given_rays names it. Copied before it is checked: what is checked is what is cast, even
  // where the caller's other thread rewrites the rays meanwhile.
  std::sort(listed.begin(), listed.end());
  std::vector<GivenRay> again(listed.size());
  for (size_t n = 0; n < listed.size(); ++n) again[n] = rays[listed[n]];
  for (size_t n = 0; n < listed.size(); ++n) {
    if (const char* fault = given_ray_fault(again[n])) throw InputError("ray " + std::to_string(listed[n]) + ": " + fault);
  }
  RenderTimings in_place = timings;
  const RayHits hits = cast_rays({again, {}, HitQuery::nearest});
  in_place.add(timings);
  timings = in_place;
  parallel_for_chunks(listed.size(), [&](size_t begin, size_t end) {
    for (size_t n = begin; n < end; ++n) {
      const size_t k = listed[n];
      if (into.t) into.t[k] = hits.t[n];
      for (size_t c = 0; c < 3 && into.normal; ++c) into.normal[3 * k + c] = hits.normal[c * hits.count + n];
      if (into.object) into.object[k] = hits.object[n];
      if (into.primitive) into.primitive[k] = hits.primitive[n];
    }
  });
}

void Renderer::Impl::render_by_given_rays(const Camera& camera, Frame& frame) {
  const uint32_t width = frame.width, height = frame.height;
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
  const RayHits hits = cast_rays({rays, {}, HitQuery::nearest});
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

}  // namespace vkray
