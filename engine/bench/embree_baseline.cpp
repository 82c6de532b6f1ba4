#include "engine/bench/embree_baseline.hpp"

#include "engine/reference/reference.hpp"
#include "engine/scene/camera.hpp"
#include "engine/stopwatch.hpp"
#include "engine/unit_vector.hpp"
#include "shaders/point_geometry.h"

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace vkray {
namespace {

// Pixels of the image in 8x8 tiles handed out to the worker threads; a packet is a 4x2 block, the
// shape vkray's subgroups have (shaders/raycast.comp).
constexpr uint32_t tile_side = 8;

void check(RTCDevice device, const char* what) {
  if (const RTCError error = rtcGetDeviceError(device); error != RTC_ERROR_NONE) {
    throw std::runtime_error(std::string("Embree: ") + what + " failed (RTCError " + std::to_string(error) + ")");
  }
}

class EmbreeScene {
 public:
  EmbreeScene(const Scene& scene, const glm::dvec3& anchor) : device_(rtcNewDevice(nullptr)) {
    if (!device_) throw std::runtime_error("Embree: rtcNewDevice failed");
    scene_ = rtcNewScene(device_);
    // Static scene, highest build quality: the fastest traversal Embree offers, the fair bar.
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    for (const auto& mesh : scene.meshes) add_mesh(mesh, anchor);
    if (!scene.spheres.empty()) add_spheres(scene.spheres, anchor);
    check(device_, "adding geometry");
    const auto start = Clock::now();
    rtcCommitScene(scene_);
    check(device_, "building the scene");
    build_ms = elapsed_ms(start);
  }
  ~EmbreeScene() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  RTCScene handle() const { return scene_; }
  // By geometry ID, as rtcAttachGeometry numbered them: the mesh or the spheres it holds.
  struct Attached {
    const Mesh* mesh = nullptr;
    const std::vector<Sphere>* spheres = nullptr;
  };
  const std::vector<Attached>& attached() const { return attached_; }
  void check_errors(const char* what) const { check(device_, what); }
  double build_ms = 0.0;

 private:
  void add_mesh(const Mesh& mesh, const glm::dvec3& anchor) {
    if (mesh.triangles.empty()) return;
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      const glm::vec3 p(mesh.positions[i] - anchor);
      vertices[3 * i] = p.x, vertices[3 * i + 1] = p.y, vertices[3 * i + 2] = p.z;
    }
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangles.size()));
    for (size_t i = 0; i < mesh.triangles.size(); ++i) std::copy_n(mesh.triangles[i].begin(), 3, indices + 3 * i);
    attached_.push_back({&mesh, nullptr});
    commit(geometry);
  }

  void add_spheres(const std::vector<Sphere>& spheres, const glm::dvec3& anchor) {
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* points = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                               4 * sizeof(float), spheres.size()));
    for (size_t i = 0; i < spheres.size(); ++i) {
      const glm::vec3 c(spheres[i].center - anchor);
      points[4 * i] = c.x, points[4 * i + 1] = c.y, points[4 * i + 2] = c.z;
      points[4 * i + 3] = static_cast<float>(spheres[i].radius);
    }
    attached_.push_back({nullptr, &spheres});
    commit(geometry);
  }

  void commit(RTCGeometry geometry) {
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);
  }

  RTCDevice device_;
  RTCScene scene_ = nullptr;
  std::vector<Attached> attached_;
};

// Rays a call of rtcIntersect1M takes: the chunk Open3D's RaycastingScene hands to it.
constexpr size_t rays_a_call = 1024;

// Runs `trace_tile(tile_x, tile_y)` over every 8x8 tile on all hardware threads; returns the time.
template <typename TraceTile>
double run_tiles(uint32_t width, uint32_t height, unsigned threads, TraceTile trace_tile) {
  const uint32_t tiles_x = (width + tile_side - 1) / tile_side;
  const uint32_t tiles = tiles_x * ((height + tile_side - 1) / tile_side);
  std::atomic<uint32_t> next{0};
  const auto start = Clock::now();
  {
    std::vector<std::jthread> workers;
    for (unsigned t = 0; t < threads; ++t) {
      workers.emplace_back([&] {
        for (uint32_t tile = next++; tile < tiles; tile = next++) trace_tile(tile % tiles_x, tile / tiles_x);
      });
    }
  }
  return elapsed_ms(start);
}

// Runs `chunk(first, end, context)` over `count` items in chunks of rays_a_call on `threads` workers,
// each taking the next chunk in turn, with a `Context` of its own made once; returns the time.
template <typename Context, typename Chunk>
double run_chunks(size_t count, unsigned threads, Chunk chunk) {
  const size_t chunks = (count + rays_a_call - 1) / rays_a_call;
  std::atomic<size_t> next{0};
  const auto start = Clock::now();
  {
    std::vector<std::jthread> workers;
    for (unsigned t = 0; t < threads; ++t) {
      workers.emplace_back([&] {
        Context context;
        for (size_t c = next++; c < chunks; c = next++) chunk(c * rays_a_call, std::min(count, (c + 1) * rays_a_call), context);
      });
    }
  }
  return elapsed_ms(start);
}

// What a point query's callback reads: the scene's primitives in double and the query point.
struct PointQueryData {
  const EmbreeScene* embree;
  glm::dvec3 point;
};

// rtcPointQuery's callback: the primitive's distance to the point; a nearer one shrinks the query's
// radius, which prunes the rest of Embree's walk (true: the radius changed).
bool nearest_primitive(RTCPointQueryFunctionArguments* arguments) {
  const auto* data = static_cast<const PointQueryData*>(arguments->userPtr);
  const EmbreeScene::Attached& attached = data->embree->attached()[arguments->geomID];
  double distance;
  if (attached.mesh) {
    const Mesh& mesh = *attached.mesh;
    const auto& triangle = mesh.triangles[arguments->primID];
    const glm::dvec3 a = mesh.positions[triangle[0]] - data->point, b = mesh.positions[triangle[1]] - data->point,
                     c = mesh.positions[triangle[2]] - data->point;
    const glm::dvec2 weights = point_geometry::nearest_on_triangle(a, b, c);
    distance = glm::length(a + weights.x * (b - a) + weights.y * (c - a));
  } else {
    const Sphere& sphere = (*attached.spheres)[arguments->primID];
    distance = std::abs(glm::length(sphere.center - data->point) - sphere.radius);
  }
  if (!(distance < arguments->query->radius)) return false;
  arguments->query->radius = static_cast<float>(distance);
  return true;
}

}  // namespace

EmbreePoints query_points_with_embree(const Scene& scene, std::span<const glm::dvec3> points, uint32_t repeats) {
  const glm::dvec3 anchor = scene_anchor(scene);
  EmbreeScene embree(scene, anchor);
  EmbreePoints result;
  result.threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<glm::vec3> relative(points.size());
  for (size_t k = 0; k < points.size(); ++k) relative[k] = glm::vec3(points[k] - anchor);
  result.distance.assign(points.size(), std::numeric_limits<float>::infinity());
  auto query = [&] {
    return run_chunks<RTCPointQueryContext>(points.size(), result.threads, [&](size_t first, size_t end, RTCPointQueryContext& context) {
      for (size_t k = first; k < end; ++k) {
        rtcInitPointQueryContext(&context);
        const glm::vec3& p = relative[k];
        RTCPointQuery point_query{p.x, p.y, p.z, 0.0f, std::numeric_limits<float>::infinity()};
        PointQueryData data{&embree, points[k]};
        rtcPointQuery(embree.handle(), &point_query, &context, nearest_primitive, &data);
        result.distance[k] = point_query.radius;
      }
    });
  };
  query();  // warm-up
  std::vector<double> times_ms;
  for (uint32_t r = 0; r < std::max(repeats, 1u); ++r) times_ms.push_back(query());
  result.time = time_stats(times_ms);
  embree.check_errors("querying points");
  for (size_t k = 0; k < points.size(); ++k) {
    for (const Plane& plane : scene.planes) {
      const double height = std::abs(glm::dot(plane.normal, points[k] - plane.point));
      result.distance[k] = std::min(result.distance[k], static_cast<float>(height));
    }
  }
  return result;
}

EmbreeResult trace_with_embree(const Scene& scene, uint32_t width, uint32_t height, uint32_t repeats) {
  const glm::dvec3 anchor = scene_anchor(scene);
  EmbreeScene embree(scene, anchor);
  const CameraBasis camera = make_camera_basis(scene.camera, width, height);
  const glm::vec3 origin(camera.origin - anchor);
  // Directions made once, outside the timed runs, as vkray's are (on the GPU, per pixel).
  std::vector<glm::vec3> directions(size_t{width} * height);
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) directions[size_t{j} * width + i] = glm::vec3(camera.direction(pixel_uv(i, j, width, height)));
  }

  EmbreeResult result;
  result.build_ms = embree.build_ms;
  result.threads = std::max(1u, std::thread::hardware_concurrency());
  result.frame = Frame(width, height, {Aov::depth, Aov::normal});
  result.frame.allocate();
  Frame& frame = result.frame;

  // Planes after Embree's answer, as the shader tests them before the tree (the nearer wins).
  auto store = [&](uint32_t i, uint32_t j, const glm::vec3& dir, float t, glm::vec3 normal) {
    const glm::dvec3 ray_origin = camera.origin, ray_dir(dir);
    for (const auto& plane : scene.planes) {
      const double t_plane = intersect_plane(plane.normal, plane.point, ray_origin, ray_dir, t);
      if (t_plane < t) t = static_cast<float>(t_plane), normal = glm::vec3(plane.normal);
    }
    const size_t p = size_t{j} * width + i;
    const bool hit = t < std::numeric_limits<float>::infinity();
    if (hit) normal = glm::vec3(unit_vector(glm::dvec3(normal)));
    if (glm::dot(normal, dir) > 0.0f) normal = -normal;
    frame.depth[p] = t;
    for (size_t c = 0; c < 3; ++c) frame.normal[c * frame.pixel_count() + p] = hit ? normal[int(c)] : 0.0f;
  };

  auto trace_single = [&](uint32_t tile_x, uint32_t tile_y) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (uint32_t j = tile_y * tile_side; j < std::min(height, (tile_y + 1) * tile_side); ++j) {
      for (uint32_t i = tile_x * tile_side; i < std::min(width, (tile_x + 1) * tile_side); ++i) {
        const glm::vec3& dir = directions[size_t{j} * width + i];
        RTCRayHit query{};
        query.ray = {origin.x, origin.y, origin.z, 0.0f, dir.x, dir.y, dir.z, 0.0f,
                     std::numeric_limits<float>::infinity(), ~0u, 0, 0};
        query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(embree.handle(), &context, &query);
      }
    }
  };

  auto trace_packets = [&](uint32_t tile_x, uint32_t tile_y, bool keep) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (uint32_t block_y = 0; block_y < tile_side; block_y += 2) {
      for (uint32_t block_x = 0; block_x < tile_side; block_x += 4) {
        alignas(32) int valid[8];
        RTCRayHit8 packet{};
        for (uint32_t k = 0; k < 8; ++k) {
          const uint32_t i = tile_x * tile_side + block_x + k % 4, j = tile_y * tile_side + block_y + k / 4;
          valid[k] = i < width && j < height ? -1 : 0;
          const glm::vec3 dir = valid[k] ? directions[size_t{j} * width + i] : glm::vec3(0, 0, 1);
          packet.ray.org_x[k] = origin.x, packet.ray.org_y[k] = origin.y, packet.ray.org_z[k] = origin.z;
          packet.ray.dir_x[k] = dir.x, packet.ray.dir_y[k] = dir.y, packet.ray.dir_z[k] = dir.z;
          packet.ray.tnear[k] = 0.0f;
          packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
          packet.ray.mask[k] = ~0u;
          packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect8(valid, embree.handle(), &context, &packet);
        if (!keep) continue;
        for (uint32_t k = 0; k < 8; ++k) {
          if (!valid[k]) continue;
          const bool hit = packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
          store(tile_x * tile_side + block_x + k % 4, tile_y * tile_side + block_y + k / 4,
                {packet.ray.dir_x[k], packet.ray.dir_y[k], packet.ray.dir_z[k]},
                hit ? packet.ray.tfar[k] : std::numeric_limits<float>::infinity(),
                {packet.hit.Ng_x[k], packet.hit.Ng_y[k], packet.hit.Ng_z[k]});
        }
      }
    }
  };

  run_tiles(width, height, result.threads, trace_single);  // warm-up
  std::vector<double> single_ms, packet_ms;
  for (uint32_t r = 0; r < std::max(repeats, 1u); ++r) {
    single_ms.push_back(run_tiles(width, height, result.threads, trace_single));
    packet_ms.push_back(run_tiles(width, height, result.threads, [&](uint32_t x, uint32_t y) { trace_packets(x, y, false); }));
  }
  result.single = time_stats(single_ms);
  result.packet = time_stats(packet_ms);
  run_tiles(width, height, result.threads, [&](uint32_t x, uint32_t y) { trace_packets(x, y, true); });
  embree.check_errors("tracing");
  return result;
}

EmbreeRays trace_rays_with_embree(const Scene& scene, std::span<const GivenRay> rays, uint32_t repeats,
                                  const RayRanges& ranges, HitQuery query) {
  const glm::dvec3 anchor = scene_anchor(scene);
  EmbreeScene embree(scene, anchor);
  EmbreeRays result;
  result.threads = std::max(1u, std::thread::hardware_concurrency());
  std::vector<RTCRayHit> queries(rays.size());  // occlusion queries use the leading RTCRay alone
  std::vector<glm::vec3> origins(rays.size()), directions(rays.size());
  for (size_t k = 0; k < rays.size(); ++k) {
    origins[k] = glm::vec3(glm::dvec3(rays[k][0], rays[k][1], rays[k][2]) - anchor);
    directions[k] = glm::vec3(unit_vector(glm::dvec3(rays[k][3], rays[k][4], rays[k][5])));
  }
  // An intersect context made ready once per worker.
  struct IntersectContext {
    RTCIntersectContext context;
    IntersectContext() { rtcInitIntersectContext(&context); }
  };
  auto trace = [&] {
    return run_chunks<IntersectContext>(rays.size(), result.threads, [&](size_t first, size_t end, IntersectContext& worker) {
      for (size_t k = first; k < end; ++k) {  // a query is also its answer: set anew each run
        const glm::vec3 &o = origins[k], &d = directions[k];
        queries[k] = {};
        queries[k].ray = {o.x, o.y, o.z, static_cast<float>(ranges.start(k)), d.x, d.y, d.z, 0.0f,
                          static_cast<float>(ranges.end(k)), ~0u, 0, 0};
        queries[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
      }
      const auto count = static_cast<unsigned>(end - first);
      if (query == HitQuery::any) {
        rtcOccluded1M(embree.handle(), &worker.context, &queries[first].ray, count, sizeof(RTCRayHit));
      } else {
        rtcIntersect1M(embree.handle(), &worker.context, &queries[first], count, sizeof(RTCRayHit));
      }
    });
  };
  trace();  // warm-up
  std::vector<double> times_ms;
  for (uint32_t r = 0; r < std::max(repeats, 1u); ++r) times_ms.push_back(trace());
  result.time = time_stats(times_ms);
  embree.check_errors("tracing given rays");
  result.t.resize(rays.size());
  constexpr float miss = std::numeric_limits<float>::infinity();
  for (size_t k = 0; k < rays.size(); ++k) {
    // rtcOccluded1M sets tfar to -inf where it found a hit.
    float t = query == HitQuery::any ? (queries[k].ray.tfar == -miss ? 0.0f : miss)
              : queries[k].hit.geomID == RTC_INVALID_GEOMETRY_ID ? miss
                                                                  : queries[k].ray.tfar;
    for (const auto& plane : scene.planes) {
      const glm::dvec3 origin(rays[k][0], rays[k][1], rays[k][2]);
      const double plane_t = intersect_plane(plane.normal, plane.point, origin, glm::dvec3(directions[k]), ranges.end(k));
      if (plane_t > ranges.start(k) && plane_t < t) t = query == HitQuery::any ? 0.0f : static_cast<float>(plane_t);
    }
    result.t[k] = t;
  }
  return result;
}

}  // namespace vkray
