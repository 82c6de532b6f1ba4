#include "engine/bench/points_bench.hpp"

#include "engine/bench/embree_baseline.hpp"
#include "engine/point_outputs.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/point_samples.hpp"
#include "engine/stopwatch.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vkray {

const char* point_set_name(PointSet set) { return set == PointSet::uniform ? "uniform" : "near-surface"; }

std::vector<glm::dvec3> bench_points(const Scene& scene, PointSet set, size_t count) {
  const Bounds box = sample_box(scene, 1.2);
  if (set == PointSet::uniform) return uniform_points(box, count, 20261202);
  const Bounds model = finite_bounds(scene);
  return near_surface_points(scene, count, glm::length(model.upper - model.lower) / 200.0, 20261203);
}

PointsRow bench_point_queries(GpuDevice& device, const Scene& scene, PointSet set, size_t count, const BenchTiming& timing,
                              size_t check_every) {
  PointsRow row;
  row.set = point_set_name(set);
  const std::vector<glm::dvec3> points = bench_points(scene, set, count);
  row.points = points.size();
  Renderer renderer(device, scene);
  PointHits nearest, winding;
  const auto timed = [&](auto&& call) {
    call();  // the first call: the pipeline and the point queries' data
    return time_stats(timed_runs(timing, [&] {
      const auto start = Clock::now();
      call();
      return elapsed_ms(start);
    }));
  };
  row.distance = timed([&] { nearest = renderer.closest_points(points); });
  // The signed distance: both queries, as Renderer.signed_distance makes them.
  row.signed_distance = timed([&] {
    nearest = renderer.closest_points(points);
    winding = renderer.winding_numbers(points);
  });
  const EmbreePoints embree = query_points_with_embree(scene, points, timing.frames);
  row.embree = embree.time;
  row.embree_threads = embree.threads;

  std::vector<glm::dvec3> checked;
  for (size_t k = 0; k < points.size(); k += std::max<size_t>(check_every, 1)) checked.push_back(points[k]);
  const ReferenceScene reference(scene);
  const PointHits exact = reference_point_hits(reference, checked, {}, HitQuery::nearest);
  const PointHits exact_winding = reference_point_hits(reference, checked, {}, HitQuery::winding);
  const Bounds box = finite_bounds(scene);
  const double diagonal = glm::length(box.upper - box.lower);
  row.checked = checked.size();
  for (size_t c = 0; c < checked.size(); ++c) {
    const size_t k = c * std::max<size_t>(check_every, 1);
    const double d = exact.distance_at(c);
    row.distance_error = std::max(row.distance_error, std::abs(nearest.distance_at(k) - d) / diagonal);
    row.embree_error = std::max(row.embree_error, std::abs(double{embree.distance[k]} - d) / diagonal);
    if (d > 1e-4 * diagonal && inside_by_winding(winding.distance_at(k)) != inside_by_winding(exact_winding.distance_at(c))) {
      ++row.sign_flips;
    }
  }
  return row;
}

std::string points_table_header() {
  char line[256];
  std::snprintf(line, sizeof line, "%-28s %-13s %8s %11s %10s %10s %8s %8s %10s %10s %6s\n", "scene", "points", "count",
                "distance ms", "signed ms", "Embree ms", "E/vkray", "signed/d", "error", "E error", "flips");
  return line;
}

std::string points_table_row(const std::string& scene, const PointsRow& row) {
  char line[512];
  std::snprintf(line, sizeof line, "%-28s %-13s %8zu %11.1f %10.1f %10.1f %8.2f %8.2f %10.2e %10.2e %6zu\n", scene.c_str(),
                row.set.c_str(), row.points, row.distance.median_ms, row.signed_distance.median_ms, row.embree.median_ms,
                row.embree.median_ms / row.distance.median_ms, row.signed_distance.median_ms / row.distance.median_ms,
                row.distance_error, row.embree_error, row.sign_flips);
  return line;
}

}  // namespace vkray
