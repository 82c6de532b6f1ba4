// Renderer::cast_rays_in_place: rays from one origin read, and their hits written, by the device in
// the caller's own arrays. Where it walks as cast_rays does (the packet walk from the shared origin:
// as listed, or ordered by direction, here on the device) its hits are cast_rays' bit for bit; in
// every search it takes they lie in the camera image's error envelope of the reference. Rays the
// shader leaves to the host (from another origin, with a bad direction, past the loop budget) are
// cast again, and a bad one is named by its index as cast_rays names it.
#include "engine/render/renderer.hpp"
#include "engine/scene/camera.hpp"
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

constexpr uint32_t unwritten = 0xdeadbeefu;

// The caller's arrays for `count` rays, each entry first a value no hit has (so that an entry left
// unwritten shows).
struct CallerHits {
  explicit CallerHits(size_t count) : t(count, -1.0f), normal(3 * count, -1.0f), object(count, unwritten), primitive(count, unwritten) {}
  HitArrays arrays() { return {t.data(), normal.data(), object.data(), primitive.data()}; }
  std::vector<float> t, normal;
  std::vector<uint32_t> object, primitive;
};

// `rays` in a fixed random order: listed[n] is the index in `rays` of the n-th.
std::vector<GivenRay> shuffled(const std::vector<GivenRay>& rays, std::vector<size_t>& listed) {
  listed.resize(rays.size());
  std::iota(listed.begin(), listed.end(), size_t{0});
  std::shuffle(listed.begin(), listed.end(), std::mt19937_64(20261128));
  std::vector<GivenRay> result;
  for (const size_t k : listed) result.push_back(rays[k]);
  return result;
}

// How many rays' entries in `in_place` differ from cast_rays' `hits` of the same rays in any bit
// (its normals are planes, the caller's x, y, z together).
size_t differing_rays(const CallerHits& in_place, const RayHits& hits) {
  size_t differing = 0;
  for (size_t k = 0; k < hits.count; ++k) {
    bool same = std::memcmp(&in_place.t[k], &hits.t[k], sizeof(float)) == 0 && in_place.object[k] == hits.object[k] &&
                in_place.primitive[k] == hits.primitive[k];
    for (size_t c = 0; c < 3; ++c) {
      same = same && std::memcmp(&in_place.normal[3 * k + c], &hits.normal[c * hits.count + k], sizeof(float)) == 0;
    }
    differing += same ? 0 : 1;
  }
  return differing;
}

// The in-place hits of the camera's pixel rays against the reference, in the camera image's envelope.
void expect_within_envelope(const Scene& scene, const CallerHits& hits) {
  Frame frame(scene.width, scene.height, {Aov::depth, Aov::normal});
  frame.depth = hits.t;
  frame.normal.resize(hits.normal.size());
  std::vector<ObjectPrimitive> ids(hits.t.size());
  for (size_t k = 0; k < hits.t.size(); ++k) {
    for (size_t c = 0; c < 3; ++c) frame.normal[c * frame.pixel_count() + k] = hits.normal[3 * k + c];
    ids[k] = {hits.object[k], hits.primitive[k]};
  }
  const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids);
  EXPECT_EQ(report.failures, 0u) << report.describe();
  EXPECT_LT(report.stats.depth_p99, 1e-5) << report.describe();
  EXPECT_LT(report.stats.normal_deg_p99, 0.01) << report.describe();
}

// Spheres, planes and a mesh in each search the device runs in place: a camera's pixel rays within
// the envelope, and in packets the same bits as cast_rays, listed as an image's rows, as a sensor's
// rings and shuffled (ordered by direction: on the device here, on the host by cast_rays; a packet's
// rays share only its culling, which never drops a hit, so any order gives the same bits).
TEST(RaysInPlace, MatchCastRaysAndTheReference) {
  const Scene scene = sized(default_scene(), 64, 48);
  for (const PrimitiveSearch search :
       runnable({PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray, PrimitiveSearch::bvh_packet})) {
    SCOPED_TRACE(testing::Message() << "search " << traversal_name(search));
    RendererOptions options;
    options.scene.search = search;
    Renderer renderer(device(), scene, options);
    const std::vector<GivenRay> rays = pixel_rays(scene);
    CallerHits in_place(rays.size());
    if (!renderer.casts_in_place()) {
      EXPECT_FALSE(renderer.cast_rays_in_place(rays, in_place.arrays()));
      EXPECT_EQ(in_place.object, std::vector<uint32_t>(rays.size(), unwritten));
      std::printf("    not run here: rays in place (%s imports no host memory or takes no double edge functions)\n",
                  device().info().name.c_str());
      continue;
    }
    ASSERT_TRUE(renderer.cast_rays_in_place(rays, in_place.arrays()));
    EXPECT_TRUE(renderer.timings().rays_in_place);
    const bool packets = search == PrimitiveSearch::bvh_packet;
    EXPECT_EQ(renderer.timings().given_walk, packets ? GivenRayWalk::packets_in_place : GivenRayWalk::one_by_one);
    expect_within_envelope(scene, in_place);
    if (!packets) continue;  // cast_rays walks them one by one from their own origins
    EXPECT_EQ(differing_rays(in_place, renderer.cast_rays(rays)), 0u);

    const std::vector<GivenRay> rings = sensor_rings(scene);
    CallerHits ring_hits(rings.size());
    ASSERT_TRUE(renderer.cast_rays_in_place(rings, ring_hits.arrays()));
    EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_in_order);
    const RayHits cast = renderer.cast_rays(rings);
    EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_in_order);
    EXPECT_EQ(differing_rays(ring_hits, cast), 0u);
    size_t hit = 0;
    for (const float t : ring_hits.t) hit += std::isfinite(t) ? 1 : 0;
    EXPECT_GT(hit, rings.size() / 20);  // the scene's objects are in view, not only misses

    std::vector<size_t> listed;
    const std::vector<GivenRay> mixed = shuffled(rays, listed);
    CallerHits mixed_hits(mixed.size());
    ASSERT_TRUE(renderer.cast_rays_in_place(mixed, mixed_hits.arrays()));
    EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_by_direction);
    if (renderer.timings().has_gpu_times) {
      EXPECT_GT(renderer.timings().order_gpu_ms, 0.0);
    }
    const RayHits sorted = renderer.cast_rays(mixed);
    EXPECT_EQ(renderer.timings().given_walk, GivenRayWalk::packets_by_direction);
    EXPECT_EQ(differing_rays(mixed_hits, sorted), 0u);
    CallerHits by_pixel(rays.size());
    for (size_t n = 0; n < listed.size(); ++n) {
      const size_t k = listed[n];
      by_pixel.t[k] = mixed_hits.t[n];
      for (size_t c = 0; c < 3; ++c) by_pixel.normal[3 * k + c] = mixed_hits.normal[3 * n + c];
      by_pixel.object[k] = mixed_hits.object[n];
      by_pixel.primitive[k] = mixed_hits.primitive[n];
    }
    EXPECT_EQ(differing_rays(by_pixel, renderer.cast_rays(rays)), 0u);
  }
}

// A ray from another origin (one the origin samples miss) is cast again from its own: the same bits
// as cast_rays gives it alone, the rest those of the list without it. A zero or non-finite direction
// is named by the ray's index, as cast_rays names it. Rays from many origins are not taken. A sensor's
// rings as listed (in order) and shuffled (ordered by direction on the device).
void expect_rays_the_shader_leaves_are_cast_again(Renderer& renderer, const std::vector<GivenRay>& rings, GivenRayWalk walk) {
  const RayHits original = renderer.cast_rays(rings);
  // A ray that hits something, among the first 16 (the list's 1024 origin samples are 16 rays apart).
  size_t m = 1;
  while (m < 16 && !std::isfinite(original.t[m])) ++m;
  ASSERT_LT(m, 16u);
  std::vector<GivenRay> moved = rings;
  moved[m][1] += 0.25;
  CallerHits in_place(moved.size());
  ASSERT_TRUE(renderer.cast_rays_in_place(moved, in_place.arrays()));
  EXPECT_EQ(renderer.timings().given_walk, walk);
  const RayHits alone = renderer.cast_rays(std::span(moved).subspan(m, 1));
  EXPECT_NE(alone.t[0], original.t[m]);  // it sees the scene from higher up
  CallerHits expected(moved.size());
  for (size_t k = 0; k < moved.size(); ++k) {
    const RayHits& source = k == m ? alone : original;
    const size_t n = k == m ? 0 : k;
    expected.t[k] = source.t[n];
    for (size_t c = 0; c < 3; ++c) expected.normal[3 * k + c] = source.normal[c * source.count + n];
    expected.object[k] = source.object[n];
    expected.primitive[k] = source.primitive[n];
  }
  EXPECT_EQ(std::memcmp(in_place.t.data(), expected.t.data(), in_place.t.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(in_place.normal.data(), expected.normal.data(), in_place.normal.size() * sizeof(float)), 0);
  EXPECT_EQ(in_place.object, expected.object);
  EXPECT_EQ(in_place.primitive, expected.primitive);

  auto message = [&](std::vector<GivenRay> rays) {
    CallerHits hits(rays.size());
    try {
      renderer.cast_rays_in_place(rays, hits.arrays());
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  std::vector<GivenRay> bad = rings;
  bad[9][5] = NAN;
  bad[5][3] = bad[5][4] = bad[5][5] = 0.0;
  EXPECT_EQ(message(bad), "ray 5: the direction is 0");
  bad[5] = rings[5];
  EXPECT_EQ(message(bad), "ray 9: the direction is not finite");

  std::vector<GivenRay> two_origins = rings;
  for (size_t k = 1; k < two_origins.size(); k += 2) two_origins[k][0] += 1.0;
  CallerHits untouched(two_origins.size());
  EXPECT_FALSE(renderer.cast_rays_in_place(two_origins, untouched.arrays()));
  EXPECT_EQ(untouched.object, std::vector<uint32_t>(two_origins.size(), unwritten));
}

TEST(RaysInPlace, RaysTheShaderLeavesAreCastAgain) {
  const Scene scene = default_scene();
  Renderer renderer(device(), scene);
  if (!renderer.casts_in_place()) GTEST_SKIP() << "no rays in place on " << device().info().name;
  const bool packets = renderer.scene_stats().search == PrimitiveSearch::bvh_packet;
  expect_rays_the_shader_leaves_are_cast_again(renderer, sensor_rings(scene),
                                               packets ? GivenRayWalk::packets_in_order : GivenRayWalk::one_by_one);
  std::vector<size_t> listed;
  expect_rays_the_shader_leaves_are_cast_again(renderer, shuffled(sensor_rings(scene), listed),
                                               packets ? GivenRayWalk::packets_by_direction : GivenRayWalk::one_by_one);
}

// Rays past the loop budget are finished (cast again, then by the reference) within the envelope;
// tiles of rays give the bits of one dispatch; arrays left out are not written.
TEST(RaysInPlace, LoopBudgetTilesAndArraysLeftOut) {
  Scene scene = sized(default_scene(), 96, 72);  // large enough for its rows to walk in place
  scene.meshes.push_back(quad_grid({-3, 0.01, -3}, {6, 0, 0}, {0, 0, 6}, 20));
  Renderer whole(device(), scene);
  if (!whole.casts_in_place()) GTEST_SKIP() << "no rays in place on " << device().info().name;
  const std::vector<GivenRay> rays = pixel_rays(scene);
  CallerHits one_dispatch(rays.size());
  ASSERT_TRUE(whole.cast_rays_in_place(rays, one_dispatch.arrays()));
  EXPECT_EQ(whole.timings().tiles, 1u);

  RendererOptions budget;
  budget.loop_budget = 3;
  Renderer short_walks(device(), scene, budget);
  CallerHits finished(rays.size());
  ASSERT_TRUE(short_walks.cast_rays_in_place(rays, finished.arrays()));
  EXPECT_GT(short_walks.timings().unfinished_rays, rays.size() / 4);
  expect_within_envelope(scene, finished);

  RendererOptions small;
  small.max_tile_bytes = 8 * 16 * sizeof(uint32_t);  // the list of rays left to the host: 8 rows of 16
  Renderer tiled(device(), scene, small);
  CallerHits tiles(rays.size());
  ASSERT_TRUE(tiled.cast_rays_in_place(rays, tiles.arrays()));
  EXPECT_GT(tiled.timings().tiles, 1u);
  EXPECT_EQ(std::memcmp(tiles.t.data(), one_dispatch.t.data(), tiles.t.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(tiles.normal.data(), one_dispatch.normal.data(), tiles.normal.size() * sizeof(float)), 0);
  EXPECT_EQ(tiles.object, one_dispatch.object);
  EXPECT_EQ(tiles.primitive, one_dispatch.primitive);

  CallerHits some(rays.size());
  ASSERT_TRUE(whole.cast_rays_in_place(rays, {some.t.data(), nullptr, nullptr, some.primitive.data()}));
  EXPECT_EQ(std::memcmp(some.t.data(), one_dispatch.t.data(), some.t.size() * sizeof(float)), 0);
  EXPECT_EQ(some.primitive, one_dispatch.primitive);
  EXPECT_EQ(some.normal, std::vector<float>(3 * rays.size(), -1.0f));
  EXPECT_EQ(some.object, std::vector<uint32_t>(rays.size(), unwritten));
}

// Where the shader cannot take them, nothing is written: the float64 shader, no rays, a bad first ray.
TEST(RaysInPlace, WhereItDoesNotApply) {
  const Scene scene = sized(default_scene(), 16, 12);
  RendererOptions doubles;
  doubles.shader.precision = Precision::float64;
  Renderer float64(device(), scene, doubles);
  EXPECT_FALSE(float64.casts_in_place());
  std::vector<GivenRay> rays = pixel_rays(scene);
  CallerHits hits(rays.size());
  EXPECT_FALSE(float64.cast_rays_in_place(rays, hits.arrays()));
  Renderer renderer(device(), scene);
  EXPECT_FALSE(renderer.cast_rays_in_place({}, hits.arrays()));
  rays[0][3] = rays[0][4] = rays[0][5] = 0.0;
  EXPECT_FALSE(renderer.cast_rays_in_place(rays, hits.arrays()));
  EXPECT_EQ(hits.object, std::vector<uint32_t>(rays.size(), unwritten));
}

}  // namespace
}  // namespace vkray
