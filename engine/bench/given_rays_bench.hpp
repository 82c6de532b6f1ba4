// Rays that are not an image's pixels, timed against Embree on the same rays and measured against
// the reference in the same run: the rays of LiDAR and depth-sensor simulation, visibility and
// sampling, cast as Python's cast_rays casts them: in place where the device takes them so
// (Renderer::cast_rays_in_place), else through Renderer::cast_rays.
#pragma once

#include "engine/bench/bench.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/scene/scene.hpp"
#include "engine/statistics.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vkray {

enum class RayKind { camera_rows, sensor, incoherent, occlusion, first_hits };

// How many first hits the first_hits kind asks each ray for (Renderer::cast_rays' `hits`): a
// multi-return LiDAR's usual count.
inline constexpr uint32_t bench_first_hits = 4;

struct RayKindInfo {
  RayKind kind;
  const char* name;
  const char* description;
};

// Every kind, by the name rows carry.
const std::vector<RayKindInfo>& ray_kinds();
std::optional<RayKind> ray_kind_from_name(const std::string& name);

// About `count` rays of `kind` for a framed scene (deterministic: the same rays on every machine):
// - camera_rows: the scene camera's pixel rays at sqrt(count) x sqrt(count), row by row;
// - sensor: a spinning sensor at the camera, its axis the camera's up: 64 rings spread over the
//   vertical field of view around the view direction, each count / 64 azimuths all the way round;
// - incoherent: from random points on the sphere of the geometry's bounding box's diagonal around
//   its centre towards random points in the box;
// - occlusion: segments between pairs of random points within the box's bounding sphere, each ray's
//   direction the segment itself (segment_ranges gives the ranges of its occlusion query);
// - first_hits: the incoherent rays again, each asked for its first bench_first_hits hits.
std::vector<GivenRay> make_rays(RayKind kind, const Scene& scene, size_t count);

// The ranges of occlusion rays: each ray up to the length of its direction, the segment's far end.
std::vector<double> segment_ends(std::span<const GivenRay> rays);

struct GivenRaysRow {
  std::string kind;
  size_t rays = 0;
  std::string walk;  // how cast_rays walked them (given_ray_walk_name), " (imported)" where in place
  // Wall time of a whole cast_rays call (occluded for occlusion rays): ordering, writing, dispatch,
  // reading back.
  TimeStats vkray;
  // rtcIntersect1M (rtcOccluded1M) in chunks of 1024 rays on every core, what Open3D's cast_rays
  // (test_occlusions) does; none for first hits, which Embree has no call for.
  TimeStats embree;
  std::string embree_variant;  // its name as a bench row: embree-1m, embree-occluded for occlusion, empty for none
  uint32_t embree_threads = 0;
  // vkray's and Embree's answers against the reference's (distances relative to it, where both hit;
  // for occlusion rays, only whether each is occluded; for first hits, each of a ray's hits).
  size_t hit_mismatches = 0, embree_hit_mismatches = 0;
  size_t both_hit = 0;
  double t_rel_p99 = 0.0, t_rel_max = 0.0, embree_t_rel_p99 = 0.0;
};

// Casts `rays` (occlusion queries over segment_ends for the occlusion kind) as `timing` says after
// a first call, through a Renderer of `scene` made with the device's defaults, and `timing.frames`
// times through Embree; `kind` names the row.
GivenRaysRow bench_given_rays(GpuDevice& device, const Scene& scene, const std::string& kind,
                              const std::vector<GivenRay>& rays, const BenchTiming& timing);

// `vkray bench --suite rays`' table: its header, and a row of `scene`.
std::string given_rays_table_header();
std::string given_rays_table_row(const std::string& scene, const GivenRaysRow& row);

}  // namespace vkray
