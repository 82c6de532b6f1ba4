// The CPU baseline vkray is measured against: Embree 3 tracing the same primary rays on all CPU
// cores, one ray at a time (rtcIntersect1) and in packets of 8 (rtcIntersect8).
#pragma once

#include "engine/frame.hpp"
#include "engine/scene/scene.hpp"
#include "engine/statistics.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace vkray {

struct EmbreeResult {
  double build_ms = 0.0;      // scene commit (Embree's own BVH build)
  TimeStats single;           // over the timed runs, all cores
  TimeStats packet;
  uint32_t threads = 0;
  Frame frame;                // depth and normal from the packet path, for the error against the reference
};

// Traces the scene camera's primary rays at width x height (the same rays as vkray: pixel_uv and
// CameraBasis::direction), `repeats` timed runs of each mode after one warm-up. Triangles and
// spheres go to Embree; infinite planes, which Embree lacks, are intersected after each query.
// Throws std::runtime_error when Embree fails.
EmbreeResult trace_with_embree(const Scene& scene, uint32_t width, uint32_t height, uint32_t repeats);

// Embree on given rays: rtcIntersect1M in chunks of 1024 rays on every core (what Open3D's
// RaycastingScene.cast_rays does), or rtcOccluded1M for occlusion queries (`query` any: what
// Open3D's test_occlusions does), each ray over its range (tnear, tfar in float); origins relative
// to the scene's anchor and unit directions in float, made once outside the timed runs; `repeats`
// timed runs after a warm-up. Planes, which Embree lacks, are intersected after each query, as for
// the camera's rays.
struct EmbreeRays {
  TimeStats time;
  unsigned threads = 0;
  std::vector<float> t;  // distance along the unit direction; +inf on a miss; for occlusion queries 0 where one hit
};
EmbreeRays trace_rays_with_embree(const Scene& scene, std::span<const GivenRay> rays, uint32_t repeats,
                                  const RayRanges& ranges = {}, HitQuery query = HitQuery::nearest);

// Embree's point queries (rtcPointQuery, Open3D's compute_distance and compute_closest_points): each
// point's nearest triangle or sphere through a callback that shrinks the query's radius to the
// distance found (the nearest point in double: engine's point_geometry), in chunks of 1024 points on
// every core; the points relative to the scene's anchor in float, made once outside the timed runs;
// `repeats` timed runs after a warm-up. Planes are measured after each query, as for rays.
struct EmbreePoints {
  TimeStats time;
  unsigned threads = 0;
  std::vector<float> distance;  // +inf where the scene is empty
};
EmbreePoints query_points_with_embree(const Scene& scene, std::span<const glm::dvec3> points, uint32_t repeats);

}  // namespace vkray
