// Point queries on the device (Renderer::closest_points, winding_numbers): the points as GpuPoints
// in the rays' place, answered by shaders/point_walk.glsl in dispatches of rows as given rays are;
// the data only point queries read (each instance's linear map, the winding number's caps) made at
// the first query after the scene changed.
#include "engine/parallel.hpp"
#include "engine/render/dispatch_sizer.hpp"
#include "engine/render/renderer_impl.hpp"
#include "engine/scene/winding_caps.hpp"
#include "engine/stopwatch.hpp"

#include <glm/gtc/matrix_access.hpp>

#include <cmath>
#include <cstring>
#include <unordered_map>

namespace vkray {

PointHits Renderer::closest_points(std::span<const glm::dvec3> points, std::span<const double> max_distances) {
  return impl_->query_points(points, max_distances, HitQuery::nearest);
}

PointHits Renderer::winding_numbers(std::span<const glm::dvec3> points) { return impl_->query_points(points, {}, HitQuery::winding); }

void Renderer::Impl::keep_point_source(const GpuScene& gpu_scene, bool rewritten_alone) {
  const GpuScene::Rewritten& rewritten = gpu_scene.rewritten;
  const auto keep = [&]<typename T, typename Item, typename Convert>(std::vector<T>& kept, const std::vector<Item>& items,
                                                                     const GpuScene::ItemRange& range, Convert convert) {
    kept.resize(items.size());
    const size_t first = rewritten_alone ? range.first : 0, end = rewritten_alone ? std::min(range.end, items.size()) : items.size();
    for (size_t k = first; k < end; ++k) kept[k] = convert(items[k]);
  };
  keep(point_records, gpu_scene.primitives, rewritten.slots, [](const gpu::GpuPrimitive& record) { return record.indices; });
  keep(point_links, gpu_scene.bvh_nodes, rewritten.nodes,
       [](const gpu::GpuBvhNode& node) { return std::array<uint32_t, 2>{node.children.x, node.children.y}; });
  const std::span<const uint32_t> roots = instanced_mesh_roots(gpu_scene);
  mesh_roots.assign(roots.begin(), roots.end());
  point_data_stale = true;
}

void Renderer::Impl::make_point_data(bool winding) {
  if (!point_data_stale && (!winding || winding_caps || stats.search == PrimitiveSearch::brute_force)) return;
  const auto start = Clock::now();
  const bool walks_tree = stats.search != PrimitiveSearch::brute_force;
  Bvh shape;  // every tree's nodes together, their leaves' slots as the records hold them
  shape.nodes = point_links;
  shape.primitive_order.resize(point_records.size());
  for (uint32_t slot = 0; slot < shape.primitive_order.size(); ++slot) shape.primitive_order[slot] = slot;
  const auto kind = [&](uint32_t slot) { return point_records[slot].w & VKRAY_PRIMITIVE_KIND_BITS; };
  // A slot's triangle by vertex index in its winding's order (the record holds the canonical order,
  // turned where VKRAY_PRIMITIVE_FLIPPED says); none for a sphere, an instance or padding.
  const auto corners = [&](uint32_t slot) -> std::optional<std::array<uint32_t, 3>> {
    const glm::uvec4& record = point_records[slot];
    if (kind(slot) != VKRAY_PRIMITIVE_TRIANGLE || record.x == record.y) return std::nullopt;
    if (record.w & VKRAY_PRIMITIVE_FLIPPED) return std::array<uint32_t, 3>{record.x, record.z, record.y};
    return std::array<uint32_t, 3>{record.x, record.y, record.z};
  };
  // Each instanced mesh's caps (a tree of its own, in its coordinates), and whether it is closed; then
  // the world's, in which an instance of a closed mesh may stand outside its subtree's box as nothing.
  std::vector<WindingCaps> trees;
  std::unordered_map<uint32_t, bool> closed_by_root;
  const std::vector<Instance>& placed = host_scene.instances;
  for (const Instance& instance : placed) {
    if (instance.mesh >= mesh_roots.size() || !walks_tree || closed_by_root.contains(mesh_roots[instance.mesh])) continue;
    const uint32_t root = mesh_roots[instance.mesh];
    trees.push_back(build_winding_caps(shape, corners, [](uint32_t) { return true; }, root));
    closed_by_root[root] = trees.back().root.empty();
  }
  // Not where objects carry ray masks: a cap stands for its whole subtree, and a query's mask may
  // hide part of one. There the walk sums every visible triangle's term (exact, slower).
  if (walks_tree && winding && !host_scene.has_masks()) {
    trees.push_back(build_winding_caps(
        shape, corners,
        [&](uint32_t slot) { return kind(slot) != VKRAY_PRIMITIVE_INSTANCE || closed_by_root[point_records[slot].y]; }, 0));
  }
  // Each instance's rows of its linear map, its least scale (rounded down) and its mesh's closedness.
  std::vector<glm::vec4> placement_texels;
  std::vector<gpu::GpuPoint> placement_points;
  for (const Instance& instance : placed) {
    const double least = smallest_scale(instance.linear);
    const bool closed = instance.mesh < mesh_roots.size() && closed_by_root[mesh_roots[instance.mesh]];
    for (int row = 0; row < 3; ++row) {
      const double w = row == 0 ? least : row == 1 ? (closed ? 1.0 : 0.0) : 0.0;
      const glm::dvec4 texel(glm::row(instance.linear, row), w);
      if (precision() == Precision::float64) {
        gpu::GpuPoint point;
        std::memcpy(&point, &texel, sizeof(point));
        placement_points.push_back(point);
      } else {
        placement_texels.push_back(glm::vec4(texel));
        if (row == 0) placement_texels.back().w = float_below(least);
      }
    }
  }
  const auto upload = [&]<typename T>(const std::vector<T>& items) -> std::optional<TexelBuffer> {
    if (items.empty()) return std::nullopt;
    return texel_views_of(context, upload_buffer(context, items.data(), items.size() * sizeof(T), geometry_usage));
  };
  placements = precision() == Precision::float64 ? upload(placement_points) : upload(placement_texels);
  if (winding && walks_tree) {
    std::vector<glm::uvec4> node_caps(point_links.size(), glm::uvec4(VKRAY_NO_CAP, 0u, VKRAY_NO_CAP, 0u));
    std::vector<CapEdge> edges;
    for (const WindingCaps& caps : trees) {
      const auto offset = static_cast<uint32_t>(edges.size());
      for (size_t node = 0; node < caps.first.size(); ++node) {
        for (int side = 0; side < 2; ++side) {
          if (caps.first[node][side] == WindingCaps::no_cap) continue;
          node_caps[node][2 * side] = caps.first[node][side] + offset;
          node_caps[node][2 * side + 1] = caps.count[node][side];
        }
      }
      edges.insert(edges.end(), caps.edges.begin(), caps.edges.end());
    }
    std::vector<glm::uvec4> edge_texels(std::max<size_t>(1, (edges.size() + 1) / 2), glm::uvec4(0u));  // never an empty buffer
    for (size_t e = 0; e < edges.size(); ++e) {
      const auto column = static_cast<glm::length_t>(2 * (e % 2));
      edge_texels[e / 2][column] = edges[e].from;
      edge_texels[e / 2][column + 1] = edges[e].to;
    }
    winding_caps = upload(node_caps);
    cap_edges = upload(edge_texels);
  } else {
    winding_caps.reset(), cap_edges.reset();
  }
  point_data_stale = false;
  // The tiles' bindings name the buffers replaced above: the next call binds anew.
  tile = TileOutputs{};
  parked_tile = TileOutputs{};
  timings.upload_ms += elapsed_ms(start);
}

PointHits Renderer::Impl::query_points(std::span<const glm::dvec3> points, std::span<const double> max_distances, HitQuery query) {
  if (stats.search == PrimitiveSearch::ray_query) {
    throw InputError("point queries walk vkray's own tree, which a renderer of ray queries has none of: make one with traversal "
                     "'auto', 'per-ray', 'packet' or 'brute-force'");
  }
  check_query_points(points, max_distances);
  PointHits hits;
  hits.allocate(points.size(), precision() == Precision::float64, query == HitQuery::nearest);
  reset_timings();
  if (points.empty()) return hits;
  with_vulkan_errors("querying points", [&] {
    make_point_data(query == HitQuery::winding);
    const AovSet aovs = query == HitQuery::nearest ? AovSet{Aov::depth, Aov::normal} : AovSet{Aov::depth};
    const uint32_t width = options.shader.workgroup_width;
    const auto rows = static_cast<uint32_t>(std::min<size_t>((points.size() + width - 1) / width, UINT32_MAX));
    const uint32_t tile_rows = rows_per_tile(width, rows, aovs, RaycastMode::points);
    // The lo parts of positions always: a point's nearest point is near it, wherever it lies.
    const vk::raii::Pipeline& chosen = pipeline->pipeline(aovs, true, RaycastMode::points, timings.pipeline_ms, query);
    prepare_tile(width, tile_rows, aovs, nullptr, RaycastMode::points);
    double& ms_per_point = given_ms_per_ray[{query, 0u}];
    DispatchSizer sizer(width, tile_rows, options.dispatch_budget_ms, ms_per_point, workgroup_footprint(RaycastMode::points).height);
    gpu::RayGenParams params{};
    params.counts = counts;
    const bool doubles = precision() == Precision::float64;
    for (size_t first = 0, count = 0; first < points.size(); first += count) {
      count = std::min(size_t{width} * sizer.next_rows(), points.size() - first);
      const auto encode_start = Clock::now();
      auto* encoded = static_cast<gpu::GpuPoint*>(tile.rays->buffer.mapped);
      parallel_for_chunks(count, [&](size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) {
          // The largest distance rounded up to float (float32 shaders read it so): a bound never shortened.
          const double most = max_distance_of(max_distances, first + k);
          const double w = doubles || std::isinf(most) ? most : double{float_above(most)};
          gpu::GpuPoint point;
          const glm::dvec4 value(points[first + k] - anchor, w);
          if (doubles) {
            std::memcpy(&point, &value, sizeof(point));
          } else {
            point.first = glm::vec4(value);
            point.second = glm::vec4(value - glm::dvec4(point.first));
            point.first.w = static_cast<float>(w), point.second.w = 0.0f;
          }
          encoded[k] = point;
        }
      });
      timings.rays_ms += elapsed_ms(encode_start);
      params.image = glm::uvec4(width, static_cast<uint32_t>(count), 0, static_cast<uint32_t>((count + width - 1) / width));
      sizer.measured(params.image.w, dispatch_tile(chosen, params));
      ms_per_point = sizer.slowest_ms_per_pixel();

      const auto copy_start = Clock::now();
      const auto* slots = static_cast<const uint32_t*>(tile.hits->host());
      const auto* placing_instances = tile.instance_hits ? static_cast<const uint32_t*>(tile.instance_hits->host()) : nullptr;
      const size_t plane_size = size_t{width} * params.image.w;
      auto copy = [&]<typename T>(const T* distances, const T* offsets) {
        parallel_for_chunks(count, [&](size_t begin, size_t end) {
          for (size_t p = begin; p < end; ++p) {
            const glm::dvec3 offset = query == HitQuery::nearest
                                          ? glm::dvec3(offsets[p], offsets[plane_size + p], offsets[2 * plane_size + p])
                                          : glm::dvec3(0.0);
            hits.store(first + p, distances[p], offset, query == HitQuery::nearest ? hit_sources(slots[p]) : ObjectPrimitive{},
                       placing_instances ? placing_instances[p] : no_object);
          }
        });
      };
      if (doubles) {
        copy(static_cast<const double*>(tile.depth->host()), query == HitQuery::nearest ? static_cast<const double*>(tile.normal->host()) : nullptr);
      } else {
        copy(static_cast<const float*>(tile.depth->host()), query == HitQuery::nearest ? static_cast<const float*>(tile.normal->host()) : nullptr);
      }
      timings.readback_ms += elapsed_ms(copy_start);
      if (tile.overflow) {  // past a device's loop budget: the reference answers
        finish_unfinished([&](uint32_t index) {
          answer_point(*reference, points[first + index], max_distance_of(max_distances, first + index), query, hits, first + index);
        });
      }
    }
  });
  return hits;
}

}  // namespace vkray
