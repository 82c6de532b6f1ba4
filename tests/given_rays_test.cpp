// Rays the caller gives (Renderer::cast_rays) against the double-precision reference. A camera's
// pixel rays, given as rays, must land in the same error envelope as the camera's image (their
// float32 directions are rounded once, inside the camera path's bound) and hit the same object and
// primitive as the reference wherever that is stable under the envelope's perturbations, however
// they are listed: in the image's rows (rays from one origin keep their places in packets), in a
// random order (ordered by direction into packets) or from origins that differ (one ray at a time).
#include "engine/scene/camera.hpp"
#include "engine/render/ray_order.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>

namespace vkray {
namespace {

using namespace test;

// How a camera's pixel rays are listed for cast_rays.
enum class Listing {
  image_rows,        // row by row, as the image: one origin, scan_width finds the rows
  shuffled,          // a fixed random order: one origin, ordered by direction into packets
  distinct_origins,  // row by row, the first ray's origin one ulp off: each ray on its own
};
constexpr Listing listings[] = {Listing::image_rows, Listing::shuffled, Listing::distinct_origins};

std::string listing_name(Listing listing) {
  return listing == Listing::image_rows ? "image rows" : listing == Listing::shuffled ? "shuffled" : "distinct origins";
}

// The walk cast_rays takes for `rays` listed as `listing` says: packets where the renderer's camera
// rays take them (and the rays share its origin), in place where scan_width finds the image's rows
// (its own tests check which images it finds), else one by one.
// Ranges that start past the origin move it: those rays walk one by one.
GivenRayWalk expected_walk(const Renderer& renderer, Listing listing, std::span<const GivenRay> rays,
                           const RayRanges& ranges = {}) {
  const bool moved = std::any_of(ranges.t_min.begin(), ranges.t_min.end(), [](double t) { return t > 0.0; });
  if (renderer.scene_stats().search != PrimitiveSearch::bvh_packet || listing == Listing::distinct_origins || moved) {
    return GivenRayWalk::one_by_one;
  }
  return scan_width(rays) ? GivenRayWalk::packets_in_place : GivenRayWalk::packets_by_direction;
}

// The pixel rays of `scene`'s camera listed as `listing` says; pixel_of[k] is the pixel whose ray
// is listed k-th.
std::vector<GivenRay> camera_rays(const Scene& scene, Listing listing, std::vector<size_t>& pixel_of) {
  std::vector<GivenRay> rays = pixel_rays(scene);
  pixel_of.resize(rays.size());
  std::iota(pixel_of.begin(), pixel_of.end(), size_t{0});
  if (listing == Listing::shuffled) {
    std::shuffle(pixel_of.begin(), pixel_of.end(), std::mt19937_64(20261125));
    std::vector<GivenRay> listed(rays.size());
    for (size_t k = 0; k < rays.size(); ++k) listed[k] = rays[pixel_of[k]];
    rays = std::move(listed);
  }
  if (listing == Listing::distinct_origins) rays[0][0] = std::nextafter(rays[0][0], INFINITY);
  return rays;
}

// Casts the pixel rays of `scene`'s camera as given rays listed as `listing` says, over `ranges`
// (in that listing's order); returns them as a Frame in pixel order, and their ids. Checks the walk
// cast_rays took.
Frame cast_camera_rays(Renderer& renderer, const Scene& scene, std::vector<ObjectPrimitive>& ids,
                       Listing listing = Listing::image_rows, const RayRanges& ranges = {}) {
  std::vector<size_t> pixel_of;
  const std::vector<GivenRay> rays = camera_rays(scene, listing, pixel_of);
  const RayHits hits = renderer.cast_rays(rays, ranges);
  EXPECT_EQ(renderer.timings().given_walk, expected_walk(renderer, listing, rays, ranges));
  Frame frame(scene.width, scene.height, {Aov::depth, Aov::normal});
  frame.depth.resize(hits.count);
  frame.normal.resize(3 * hits.count);
  ids.assign(hits.count, {});
  for (size_t k = 0; k < hits.count; ++k) {
    const size_t pixel = pixel_of[k];
    frame.depth[pixel] = hits.t[k];
    for (size_t c = 0; c < 3; ++c) frame.normal[c * frame.pixel_count() + pixel] = hits.normal[c * hits.count + k];
    ids[pixel] = {hits.object[k], hits.primitive[k]};
  }
  return frame;
}

void expect_given_rays_match_reference(const Scene& scene, RendererOptions options = {},
                                       Percentiles percentiles = Percentiles::checked) {
  Renderer renderer(device(), scene, options);
  for (const Listing listing : listings) {
    SCOPED_TRACE(listing_name(listing));
    std::vector<ObjectPrimitive> ids;
    const Frame frame = cast_camera_rays(renderer, scene, ids, listing);
    const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids);
    EXPECT_EQ(report.failures, 0u) << report.describe();
    if (percentiles == Percentiles::checked) {
      EXPECT_LT(report.stats.depth_p99, 1e-5) << report.describe();
      EXPECT_LT(report.stats.normal_deg_p99, 0.01) << report.describe();
    }
  }
}

// Spheres, planes and a mesh, in every search mode and both precisions, every listing. Rays from
// one origin take the packet walk where the camera's would (the float32 shader's); the others walk
// the tree one by one. Ray queries, where the device has them, in float32 (their only precision).
TEST(GivenRays, DefaultSceneInEverySearchAndPrecision) {
  const Scene scene = sized(default_scene(), 64, 48);
  for (const PrimitiveSearch search : runnable({PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray,
                                                PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query})) {
    for (const Precision precision : {Precision::float32, Precision::float64}) {
      const bool float32_only = search == PrimitiveSearch::bvh_packet || search == PrimitiveSearch::ray_query;
      if (float32_only && precision == Precision::float64) continue;
      SCOPED_TRACE(testing::Message() << "search " << int(search) << ", precision " << int(precision));
      RendererOptions options;
      options.scene.search = search;
      options.shader.precision = precision;
      expect_given_rays_match_reference(scene, options);
      // The image is large enough for its rows to keep their places: that walk is checked here.
      if (search == PrimitiveSearch::bvh_packet) {
        Renderer renderer(device(), scene, options);
        std::vector<ObjectPrimitive> ids;
        cast_camera_rays(renderer, scene, ids);
        EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_in_place);
      }
    }
  }
}

// Given rays read as storage buffers too, with the geometry (the storage-geometry variant).
TEST(GivenRays, StorageGeometryVariant) {
  RendererOptions options;
  options.shader.storage_geometry = true;
  expect_given_rays_match_reference(sized(default_scene(), 48, 36), options);
}

// Rays that start inside a sphere and inside a closed mesh, and rays parallel to a plane (the
// camera at the plane's height: its middle row is parallel to it).
TEST(GivenRays, FromInsideAndParallelToPlanes) {
  Scene inside_sphere;
  inside_sphere.camera = {{0.2, 0.1, 0}, {1, 0, -1}, {0, 1, 0}, 90};
  inside_sphere.spheres.push_back({{0, 0, 0}, 3});
  expect_given_rays_match_reference(sized(inside_sphere, 33, 33));

  Scene inside_cube = cube_scene();
  const Box box = mesh_bounds(inside_cube.meshes[0]);
  inside_cube.camera = {0.5 * (box.lower + box.upper), box.upper, {0, 1, 0}, 100};
  expect_given_rays_match_reference(sized(inside_cube, 33, 33));

  Scene parallel;
  parallel.camera = {{0, 1, 0}, {0, 1, -1}, {0, 1, 0}, 60};
  parallel.planes.push_back({{0, 1, -5}, {0, 1, 0}});
  parallel.planes.push_back({{0, 0, 0}, {0, 1, 0}});
  parallel.spheres.push_back({{0, 1, -8}, 1});
  expect_given_rays_match_reference(sized(parallel, 33, 33), {}, Percentiles::ill_conditioned);
}

// Far from the world origin, where the origin's lo part carries the precision.
TEST(GivenRays, LargeWorldCoordinates) {
  expect_given_rays_match_reference(translated(sized(default_scene(), 48, 36), {1e6, 0, -2e6}));
}

// A budget of a few iterations: nearly every ray is finished on the CPU, ids included, whichever
// walk and listing (a packet's rays that ran out are finished by their place in the list).
TEST(GivenRays, RaysBeyondTheLoopBudgetAreFinished) {
  Scene scene = sized(default_scene(), 24, 18);
  scene.meshes.push_back(quad_grid({-3, 0.01, -3}, {6, 0, 0}, {0, 0, 6}, 20));
  for (const PrimitiveSearch search : runnable({PrimitiveSearch::bvh_per_ray, PrimitiveSearch::bvh_packet})) {
    RendererOptions options;
    options.loop_budget = 3;
    options.scene.search = search;
    Renderer renderer(device(), scene, options);
    for (const Listing listing : listings) {
      SCOPED_TRACE(testing::Message() << "search " << int(search) << ", " << listing_name(listing));
      std::vector<ObjectPrimitive> ids;
      const Frame frame = cast_camera_rays(renderer, scene, ids, listing);
        EXPECT_GT(renderer.timings().unfinished_rays, frame.pixel_count() / 4);
      const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids);
      EXPECT_EQ(report.failures, 0u) << report.describe();
    }
  }
}

// More rays than one dispatch holds: tiles of rays give the same values as one dispatch, in every
// listing (tiles of whole packets where the rays are ordered by direction; 1200 rays are 9 tiles
// and a padded packet there).
TEST(GivenRays, TilesOfRaysGiveTheSameValues) {
  const Scene scene = sized(default_scene(), 40, 30);
  Renderer whole(device(), scene);
  RendererOptions small;
  small.max_tile_bytes = 8 * 16 * sizeof(float) * 3;  // 128 rays' normals: 8 packet rows of 16
  Renderer tiled(device(), scene, small);
  for (const Listing listing : listings) {
    SCOPED_TRACE(listing_name(listing));
    std::vector<ObjectPrimitive> whole_ids, tiled_ids;
    const Frame a = cast_camera_rays(whole, scene, whole_ids, listing);
    const Frame b = cast_camera_rays(tiled, scene, tiled_ids, listing);
    EXPECT_GT(tiled.timings().tiles, 1u);
    EXPECT_EQ(whole.timings().tiles, 1u);
    EXPECT_EQ(std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(a.normal.data(), b.normal.data(), a.normal.size() * sizeof(float)), 0);
    EXPECT_EQ(whole_ids, tiled_ids);
  }
}

// A spinning sensor at the camera (16 rings, 1024 azimuths a ring, listed ring by ring) walks in
// packets of 64 consecutive rays as listed; shuffled, the same rays are ordered by direction. A
// packet's rays only share its culling, which never drops a hit: both give the same bits.
TEST(GivenRays, SensorRingsWalkInTheirOrder) {
  const Scene scene = default_scene();
  Renderer renderer(device(), scene);
  if (renderer.scene_stats().search != PrimitiveSearch::bvh_packet) GTEST_SKIP() << "no packet walk on this device";
  const std::vector<GivenRay> rays = sensor_rings(scene);
  const RayHits in_order = renderer.cast_rays(rays);
  EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_in_order);
  std::vector<size_t> listed(rays.size());
  std::iota(listed.begin(), listed.end(), size_t{0});
  std::shuffle(listed.begin(), listed.end(), std::mt19937_64(20261127));
  std::vector<GivenRay> shuffled_rays;
  for (const size_t k : listed) shuffled_rays.push_back(rays[k]);
  const RayHits sorted = renderer.cast_rays(shuffled_rays);
  EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_by_direction);
  size_t differing = 0, hits = 0;
  for (size_t n = 0; n < listed.size(); ++n) {
    const size_t k = listed[n];
    hits += std::isfinite(in_order.t[k]) ? 1 : 0;
    if (std::memcmp(&in_order.t[k], &sorted.t[n], sizeof(float)) != 0 || in_order.primitive[k] != sorted.primitive[n] ||
        in_order.object[k] != sorted.object[n] || in_order.normal[k] != sorted.normal[n]) {
      ++differing;
    }
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(hits, rays.size() / 20);  // the scene's objects are in view, not only misses
}

// Ranges with every search, precision and listing, against the reference's nearest hits: t_max 1%
// short of a ray's nearest hit leaves it a miss, 1% past it keeps that hit, the same bits (the bound
// only culls what lies beyond it); an occlusion query over the same ranges says which; t_min half
// way to it moves the ray's start, and the hit stays within the camera image's error envelope. 1%
// is far beyond float32's distance error (below 1e-5 here), so no ray is ambiguous.
TEST(GivenRays, RangesAndOcclusionQueries) {
  const Scene scene = sized(default_scene(), 32, 24);
  const ReferenceScene reference(scene);
  for (const PrimitiveSearch search : runnable({PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray,
                                                PrimitiveSearch::bvh_packet})) {
    for (const Precision precision : {Precision::float32, Precision::float64}) {
      if (search == PrimitiveSearch::bvh_packet && precision == Precision::float64) continue;
      RendererOptions options;
      options.scene.search = search;
      options.shader.precision = precision;
      Renderer renderer(device(), scene, options);
      for (const Listing listing : listings) {
        SCOPED_TRACE(testing::Message() << "search " << int(search) << ", precision " << int(precision) << ", "
                                        << listing_name(listing));
        std::vector<size_t> pixel_of;
        const std::vector<GivenRay> rays = camera_rays(scene, listing, pixel_of);
        const std::vector<ReferenceHit> nearest = trace_reference_rays(reference, rays);
        const RayHits unranged = renderer.cast_rays(rays);
        std::vector<double> t_max(rays.size()), t_min(rays.size(), 0.0);
        std::vector<uint8_t> expect_hit(rays.size());
        for (size_t k = 0; k < rays.size(); ++k) {
          const bool hit = std::isfinite(nearest[k].t);
          expect_hit[k] = hit && k % 2 == 0;
          t_max[k] = hit ? nearest[k].t * (k % 2 == 0 ? 1.01 : 0.99) : (k % 3 == 0 ? 1.0 : INFINITY);
          if (hit && k % 3 != 0) t_min[k] = 0.5 * nearest[k].t;
        }
        const RayHits ranged = renderer.cast_rays(rays, {{}, t_max});
        EXPECT_EQ(renderer.timings().given_walk, expected_walk(renderer, listing, rays));
        const std::vector<uint8_t> blocked = renderer.occluded(rays, {{}, t_max});
        EXPECT_EQ(renderer.timings().given_walk, expected_walk(renderer, listing, rays));
        size_t wrong_hits = 0, wrong_values = 0;
        for (size_t k = 0; k < rays.size(); ++k) {
          if (std::isfinite(ranged.t[k]) != bool(expect_hit[k]) || blocked[k] != expect_hit[k]) ++wrong_hits;
          if (expect_hit[k] && (ranged.t[k] != unranged.t[k] || ranged.primitive[k] != unranged.primitive[k] ||
                                ranged.object[k] != unranged.object[k])) {
            ++wrong_values;
          }
        }
        EXPECT_EQ(wrong_hits, 0u);
        EXPECT_EQ(wrong_values, 0u);

        std::vector<ObjectPrimitive> ids;
        const Frame moved = cast_camera_rays(renderer, scene, ids, listing, {t_min, {}});
        const EnvelopeReport report = check_against_reference(scene, moved, 1, &ids);
        EXPECT_EQ(report.failures, 0u) << report.describe();
      }
    }
  }
}

// t_min past a ray's first hit on a sphere: its far side, or a plane behind it where the ray
// leaves the sphere before t_min, against the reference over the same ranges. Rays whose far hit
// lies within 1e-3 of t_min either way are left out: there float32's distance error (below 1e-5)
// could put the hit on either side.
TEST(GivenRays, RangesThatStartPastTheFirstHit) {
  Scene scene;
  scene.camera = {{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40};
  scene.spheres.push_back({{0, 0, 0}, 1});
  scene.planes.push_back({{0, 0, -3}, {0, 0, 1}});
  scene = sized(scene, 32, 32);
  const ReferenceScene reference(scene);
  for (const Precision precision : {Precision::float32, Precision::float64}) {
    SCOPED_TRACE(testing::Message() << "precision " << int(precision));
    RendererOptions options;
    options.shader.precision = precision;
    Renderer renderer(device(), scene, options);
    std::vector<size_t> pixel_of;
    const std::vector<GivenRay> rays = camera_rays(scene, Listing::image_rows, pixel_of);
    const std::vector<ReferenceHit> nearest = trace_reference_rays(reference, rays);
    std::vector<double> t_min(rays.size(), 0.0);  // the rays that miss the sphere find the plane
    for (size_t k = 0; k < rays.size(); ++k) {
      if (nearest[k].kind == PrimitiveKind::sphere) t_min[k] = 1.05 * nearest[k].t;
    }
    const std::vector<ReferenceHit> exact = trace_reference_rays(reference, rays, {t_min, {}});
    const RayHits hits = renderer.cast_rays(rays, {t_min, {}});
    size_t checked = 0, sphere_hits = 0;
    for (size_t k = 0; k < rays.size(); ++k) {
      ASSERT_TRUE(std::isfinite(exact[k].t));
      if (std::abs(exact[k].t - t_min[k]) < 1e-3 * t_min[k]) continue;
      ++checked;
      if (exact[k].kind == PrimitiveKind::sphere) ++sphere_hits;
      EXPECT_NEAR(hits.t[k], exact[k].t, 1e-5 * exact[k].t) << "ray " << k;
      EXPECT_EQ((ObjectPrimitive{hits.object[k], hits.primitive[k]}), reference.source(exact[k])) << "ray " << k;
    }
    EXPECT_GT(sphere_hits, rays.size() / 10);  // the far side of the sphere, not only the plane
    EXPECT_GT(checked, rays.size() * 9 / 10);
  }
}

TEST(GivenRays, BadRangesAreRefusedByIndex) {
  Renderer renderer(device(), sized(default_scene(), 4, 4));
  const std::vector<GivenRay> rays(3, GivenRay{0, 1, 5, 0, 0, -1});
  auto message = [&](std::vector<double> t_min, std::vector<double> t_max) {
    try {
      renderer.occluded(rays, {t_min, t_max});
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({0, -1, 0}, {}), "ray 1: t_min is negative or not finite");
  EXPECT_EQ(message({0, 0, INFINITY}, {}), "ray 2: t_min is negative or not finite");
  EXPECT_EQ(message({}, {1, NAN, 1}), "ray 1: t_max is NaN or below t_min");
  EXPECT_EQ(message({0, 2, 0}, {1, 1, 1}), "ray 1: t_max is NaN or below t_min");
  EXPECT_EQ(message({0, 0, 3e15}, {}), "ray 2: the range starts farther than 1e15 from the world origin on some axis");
  EXPECT_EQ(message({0, 0}, {}), "t_min: 2 values for 3 rays (one a ray, or none)");
  EXPECT_EQ(message({}, {1, 1, 1, 1}), "t_max: 4 values for 3 rays (one a ray, or none)");
  EXPECT_EQ(message({0, 1, 0}, {0, 1, INFINITY}), "no error");  // empty ranges are misses
  const std::vector<uint8_t> blocked = renderer.occluded(rays, {std::vector<double>{0, 1, 0}, std::vector<double>{0, 1, INFINITY}});
  EXPECT_EQ(blocked, (std::vector<uint8_t>{0, 0, 1}));
}

TEST(GivenRays, BadRaysAreRefusedByIndex) {
  Renderer renderer(device(), sized(default_scene(), 4, 4));
  auto message = [&](std::vector<GivenRay> rays) {
    try {
      renderer.cast_rays(rays);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  const GivenRay good{0, 1, 5, 0, 0, -1};
  EXPECT_EQ(message({good, {0, 1, 5, 0, 0, 0}}), "ray 1: the direction is 0");
  EXPECT_EQ(message({good, good, {NAN, 1, 5, 0, 0, -1}}), "ray 2: the origin is not finite");
  EXPECT_EQ(message({{0, 1, 5, 0, INFINITY, -1}}), "ray 0: the direction is not finite");
  EXPECT_EQ(message({{0, 2e15, 5, 0, 0, -1}}), "ray 0: the origin is farther than 1e15 from the world origin on some axis");
  EXPECT_EQ(renderer.cast_rays({}).count, 0u);
}

}  // namespace
}  // namespace vkray
