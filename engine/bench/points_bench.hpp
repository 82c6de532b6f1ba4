// Point queries timed against Embree's rtcPointQuery on the same points and measured against the
// reference in the same run (`vkray bench --suite points`): the unsigned distance, and the signed
// distance whose sign is the winding number's, as Python's Renderer.distance and signed_distance
// call them (docs/points.md).
#pragma once

#include "engine/bench/bench.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/scene/scene.hpp"
#include "engine/statistics.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace vkray {

// The points of a row: `count` uniform in the box 1.2 times the model's, or near its surface (on it,
// moved by a Gaussian of sigma 1/200 of the box's diagonal: DeepSDF's draws). Deterministic.
enum class PointSet { uniform, near_surface };
const char* point_set_name(PointSet set);
std::vector<glm::dvec3> bench_points(const Scene& scene, PointSet set, size_t count);

struct PointsRow {
  std::string set;
  size_t points = 0;
  // Wall time of a whole call (writing the points, dispatches, reading back), the unsigned distance and
  // the signed distance; Embree's rtcPointQuery in chunks of 1024 points on every core.
  TimeStats distance, signed_distance, embree;
  uint32_t embree_threads = 0;
  // Against the reference, on every `check_every`-th point: the largest error of vkray's and
  // Embree's distances relative to the scene's box diagonal, and the points whose sign differs from
  // the fp64 winding number's among those farther than 1e-4 of the diagonal from the surface.
  size_t checked = 0, sign_flips = 0;
  double distance_error = 0.0, embree_error = 0.0;
};

PointsRow bench_point_queries(GpuDevice& device, const Scene& scene, PointSet set, size_t count, const BenchTiming& timing,
                              size_t check_every);

std::string points_table_header();
std::string points_table_row(const std::string& scene, const PointsRow& row);

}  // namespace vkray
