#include "engine/bench/given_rays_bench.hpp"

#include "engine/bench/embree_baseline.hpp"
#include "engine/parallel.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/camera.hpp"
#include "engine/stopwatch.hpp"

#include <glm/geometric.hpp>

#include <chrono>
#include <cstdio>
#include <limits>
#include <cmath>
#include <numbers>
#include <random>

namespace vkray {
namespace {

// Rings of the spinning sensor: what a 64-beam LiDAR has.
constexpr size_t sensor_rings = 64;
GivenRay ray_from(const glm::dvec3& origin, const glm::dvec3& direction) {
  return {origin.x, origin.y, origin.z, direction.x, direction.y, direction.z};
}

// Relative distance errors of `t` against the reference where both hit, and the hit/miss flips.
struct DistanceErrors {
  size_t mismatches = 0, both_hit = 0;
  double p99 = 0.0, max = 0.0;
};

template <typename Distance>
DistanceErrors distance_errors(const std::vector<ReferenceHit>& reference, Distance&& t) {
  DistanceErrors errors;
  std::vector<double> relative;
  for (size_t k = 0; k < reference.size(); ++k) {
    const double exact = reference[k].t;
    const double found = t(k);
    if (std::isfinite(exact) != std::isfinite(found)) {
      ++errors.mismatches;
    } else if (std::isfinite(exact)) {
      relative.push_back(std::abs(found - exact) / exact);
    }
  }
  errors.both_hit = relative.size();
  errors.p99 = percentile(relative, 0.99);
  errors.max = relative.empty() ? 0.0 : *std::max_element(relative.begin(), relative.end());
  return errors;
}

// Occlusion answers (0 where occluded, +inf where not) against the reference's nearest hits
// within the same ranges: the flips alone.
DistanceErrors occlusion_flips(const std::vector<ReferenceHit>& reference, std::span<const float> found) {
  DistanceErrors errors;
  for (size_t k = 0; k < reference.size(); ++k) {
    if ((reference[k].kind != PrimitiveKind::none) != (found[k] == 0.0f)) ++errors.mismatches;
  }
  return errors;
}

}  // namespace

const std::vector<RayKindInfo>& ray_kinds() {
  static const std::vector<RayKindInfo> kinds = {
      {RayKind::camera_rows, "camera-rows", "one origin, a camera's pixel rays listed row by row"},
      {RayKind::sensor, "sensor", "one origin, a spinning 64-ring sensor (rings x azimuths all the way round)"},
      {RayKind::incoherent, "incoherent", "random origins around the model towards random points within it"},
      {RayKind::occlusion, "occlusion", "whether anything lies between pairs of random points around the model"},
      {RayKind::first_hits, "first-4-hits", "the incoherent rays' first 4 hits each, in order (multi-return)"},
  };
  return kinds;
}

std::optional<RayKind> ray_kind_from_name(const std::string& name) {
  for (const auto& info : ray_kinds()) {
    if (name == info.name) return info.kind;
  }
  return std::nullopt;
}

std::vector<GivenRay> make_rays(RayKind kind, const Scene& scene, size_t count) {
  std::vector<GivenRay> rays;
  switch (kind) {
    case RayKind::camera_rows: {
      const auto side = static_cast<uint32_t>(std::max(1.0, std::floor(std::sqrt(static_cast<double>(count)))));
      const CameraBasis basis = make_camera_basis(scene.camera, side, side);
      rays.resize(size_t{side} * side);
      for (uint32_t j = 0; j < side; ++j) {
        for (uint32_t i = 0; i < side; ++i) {
          const PixelRay ray = pixel_ray(scene.camera, basis, i, j, side, side);
          rays[size_t{j} * side + i] = ray_from(ray.origin, ray.direction);
        }
      }
      break;
    }
    case RayKind::sensor: {
      const CameraBasis basis = make_camera_basis(scene.camera, 1, 1);
      const glm::dvec3 axis = basis.up, forward = -basis.forward, side = basis.right;  // the camera looks along -forward
      const size_t azimuths = std::max<size_t>(1, count / sensor_rings);
      const double half_fov = 0.5 * scene.camera.fovy_degrees * std::numbers::pi / 180.0;
      rays.reserve(sensor_rings * azimuths);
      for (size_t ring = 0; ring < sensor_rings; ++ring) {
        const double elevation = -half_fov + 2.0 * half_fov * (static_cast<double>(ring) + 0.5) / sensor_rings;
        for (size_t a = 0; a < azimuths; ++a) {
          const double azimuth = 2.0 * std::numbers::pi * static_cast<double>(a) / static_cast<double>(azimuths);
          const glm::dvec3 around = std::cos(azimuth) * forward + std::sin(azimuth) * side;
          rays.push_back(ray_from(scene.camera.from, std::cos(elevation) * around + std::sin(elevation) * axis));
        }
      }
      break;
    }
    case RayKind::incoherent:
    case RayKind::first_hits:
    case RayKind::occlusion: {
      const glm::dvec3 centre = scene_centre(scene);
      const double radius = std::max(scene_radius(scene, centre), 1e-300);
      std::mt19937_64 random(kind != RayKind::occlusion ? 20261126 : 20261127);  // first hits: the incoherent rays
      std::normal_distribution<double> gaussian;
      std::uniform_real_distribution<double> uniform;
      auto on_sphere = [&] {
        glm::dvec3 v(gaussian(random), gaussian(random), gaussian(random));
        while (glm::length(v) == 0.0) v = {gaussian(random), gaussian(random), gaussian(random)};
        return glm::normalize(v);
      };
      auto in_ball = [&] { return centre + radius * std::cbrt(uniform(random)) * on_sphere(); };
      rays.reserve(count);
      for (size_t k = 0; k < count; ++k) {
        const glm::dvec3 origin = kind != RayKind::occlusion ? centre + 2.0 * radius * on_sphere() : in_ball();
        rays.push_back(ray_from(origin, in_ball() - origin));
      }
      break;
    }
  }
  return rays;
}

std::vector<double> segment_ends(std::span<const GivenRay> rays) {
  std::vector<double> ends(rays.size());
  for (size_t k = 0; k < rays.size(); ++k) ends[k] = glm::length(glm::dvec3(rays[k][3], rays[k][4], rays[k][5]));
  return ends;
}

GivenRaysRow bench_given_rays(GpuDevice& device, const Scene& scene, const std::string& kind,
                              const std::vector<GivenRay>& rays, const BenchTiming& timing) {
  GivenRaysRow row;
  row.kind = kind;
  row.rays = rays.size();
  const bool occlusion = ray_kind_from_name(kind) == RayKind::occlusion;
  const uint32_t hits = ray_kind_from_name(kind) == RayKind::first_hits ? bench_first_hits : 1;
  const std::vector<double> ends = occlusion ? segment_ends(rays) : std::vector<double>{};
  const RayRanges ranges{{}, ends};
  const ReferenceScene reference_scene(scene);
  std::vector<ReferenceHit> reference;
  if (hits == 1) {
    reference = trace_reference_rays(reference_scene, rays, ranges);
  } else {  // every ray's hits in turn, as cast_rays lists them
    reference.resize(rays.size() * hits);
    parallel_for_chunks(rays.size(), [&](size_t begin, size_t end) {
      for (size_t k = begin; k < end; ++k) {
        const std::vector<ReferenceHit> first = first_reference_hits(reference_scene, rays[k], 0.0, no_hit, hits);
        std::copy(first.begin(), first.end(), reference.begin() + static_cast<std::ptrdiff_t>(k * hits));
      }
    });
  }

  Renderer renderer(device, scene);
  // What Python's cast_rays runs: in place where the device takes the rays so (its four default
  // outputs into arrays of the caller's), else cast_rays. Only t is compared; an occlusion query's
  // answer as a distance, 0 where it is occluded.
  UninitializedVector<float> found;
  std::vector<float> t_in_place(rays.size()), normal(3 * rays.size());
  std::vector<uint32_t> object(rays.size()), primitive(rays.size());
  bool in_place = false;
  auto cast = [&] {
    if (!occlusion) {
      in_place = hits == 1 && renderer.cast_rays_in_place(rays, {t_in_place.data(), normal.data(), object.data(), primitive.data()});
      if (!in_place) found = std::move(renderer.cast_rays(rays, ranges, hits).t);
      return;
    }
    const std::vector<uint8_t> blocked = renderer.occluded(rays, ranges);
    found.resize(blocked.size());
    for (size_t k = 0; k < blocked.size(); ++k) found[k] = blocked[k] ? 0.0f : std::numeric_limits<float>::infinity();
  };
  cast();  // the first call: the pipeline
  row.vkray = time_stats(timed_runs(timing, [&] {
    const auto start = Clock::now();
    cast();
    return elapsed_ms(start);
  }));
  row.walk = std::string(given_ray_walk_name(renderer.timings().given_walk)) + (in_place ? " (imported)" : "");
  const bool with_embree = hits == 1;  // Embree has no call for first hits
  EmbreeRays embree;
  if (with_embree) {
    embree = trace_rays_with_embree(scene, rays, timing.frames, ranges, occlusion ? HitQuery::any : HitQuery::nearest);
    row.embree = embree.time;
    row.embree_variant = occlusion ? "embree-occluded" : "embree-1m";
    row.embree_threads = embree.threads;
  }

  auto errors = [&](std::span<const float> t) {
    if (occlusion) return occlusion_flips(reference, t);
    return distance_errors(reference, [&](size_t k) { return double{t[k]}; });
  };
  const DistanceErrors vkray_errors = errors(in_place ? std::span<const float>(t_in_place) : std::span<const float>(found));
  row.hit_mismatches = vkray_errors.mismatches;
  row.both_hit = vkray_errors.both_hit;
  row.t_rel_p99 = vkray_errors.p99;
  row.t_rel_max = vkray_errors.max;
  if (with_embree) {
    const DistanceErrors embree_errors = errors(embree.t);
    row.embree_hit_mismatches = embree_errors.mismatches;
    row.embree_t_rel_p99 = embree_errors.p99;
  }
  return row;
}

std::string given_rays_table_header() {
  char line[256];
  std::snprintf(line, sizeof line, "%-28s %-12s %8s  %-32s %10s %10s %8s %6s %9s %7s\n", "scene", "rays", "count", "walk",
                "vkray ms", "Embree ms", "E/vkray", "flips", "t p99", "E flips");
  return line;
}

std::string given_rays_table_row(const std::string& scene, const GivenRaysRow& row) {
  char line[512];
  const std::string t_p99 = row.both_hit > 0 ? (std::snprintf(line, sizeof line, "%.2e", row.t_rel_p99), std::string(line)) : "-";
  if (row.embree_variant.empty()) {  // no Embree row to compare with
    std::snprintf(line, sizeof line, "%-28s %-12s %8zu  %-32s %10.1f %10s %8s %6zu %9s %7s\n", scene.c_str(), row.kind.c_str(),
                  row.rays, row.walk.c_str(), row.vkray.median_ms, "-", "-", row.hit_mismatches, t_p99.c_str(), "-");
    return line;
  }
  std::snprintf(line, sizeof line, "%-28s %-12s %8zu  %-32s %10.1f %10.1f %8.2f %6zu %9s %7zu\n", scene.c_str(),
                row.kind.c_str(), row.rays, row.walk.c_str(), row.vkray.median_ms, row.embree.median_ms,
                row.embree.median_ms / row.vkray.median_ms, row.hit_mismatches, t_p99.c_str(), row.embree_hit_mismatches);
  return line;
}

}  // namespace vkray
