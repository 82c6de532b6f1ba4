// Random scenes in the spirit of pbrt-v4's shape tests: spheres, planes and triangles seen by random
// cameras, each scene at a magnitude 10^U(-8, 8) (its positions, sizes and camera distances within
// about three decades of it). Whatever the scene, the GPU writes no NaN, every depth is +inf or
// positive and finite, every normal is unit or zero, and every pixel lies within the reference
// envelope of the other GPU tests (engine/reference/envelope.cpp).
//
// A second set draws the magnitude per primitive instead, from 10^U(-4, 4): a 1e-6 triangle may sit
// beside a 1e4 sphere, and the camera looks at either. float32 relative to the scene's centre
// cannot hold both (ulp 1e-3 at 1e4); positions split into hi and lo parts, relative to the camera,
// can: their ~48 bits cover the eight decades and float32's seven below the smallest primitive.
// Sixteen decades per primitive would need more than 48 bits.
#include "engine/scene/mesh_generators.hpp"
#include "tests/gpu_test_support.hpp"

#include <glm/geometric.hpp>

#include <cmath>

namespace vkray {
namespace {

glm::dvec3 random_point(PortableRandom& random, double magnitude) {
  return magnitude * glm::dvec3(random.uniform(-1.0, 1.0), random.uniform(-1.0, 1.0), random.uniform(-1.0, 1.0));
}

enum class Magnitudes { per_scene, per_primitive };

Scene random_scene(uint64_t seed, uint32_t width, uint32_t height, Magnitudes magnitudes) {
  PortableRandom random(seed);
  // The scene's magnitude, anywhere in sixteen decades; each primitive 1 to 100 times smaller. Or
  // one magnitude per primitive, within eight decades.
  double magnitude = std::pow(10.0, random.uniform(-8.0, 8.0));
  auto next_primitive = [&] {
    if (magnitudes == Magnitudes::per_primitive) magnitude = std::pow(10.0, random.uniform(-4.0, 4.0));
  };
  auto size_below = [&](double scale) { return scale * std::pow(10.0, random.uniform(-2.0, 0.0)); };
  Scene scene;
  scene.width = width;
  scene.height = height;
  std::vector<std::pair<glm::dvec3, double>> targets;  // centre and size of each finite primitive
  const auto spheres = random.below(5), planes = random.below(3), triangles = random.below(7);
  for (uint64_t k = 0; k < spheres; ++k) {
    next_primitive();
    const Sphere sphere{random_point(random, magnitude), size_below(magnitude)};
    scene.spheres.push_back(sphere);
    targets.emplace_back(sphere.center, sphere.radius);
  }
  for (uint64_t k = 0; k < planes; ++k) {
    next_primitive();
    scene.planes.push_back({random_point(random, magnitude), random.unit_vector()});
  }
  if (triangles > 0) {
    Mesh mesh;
    for (uint64_t k = 0; k < triangles; ++k) {
      next_primitive();
      const glm::dvec3 centre = random_point(random, magnitude);
      const double size = size_below(magnitude);
      for (int corner = 0; corner < 3; ++corner) mesh.positions.push_back(centre + random_point(random, size));
      const auto first = static_cast<uint32_t>(3 * k);
      mesh.triangles.push_back({first, first + 1, first + 2});
      targets.emplace_back(centre, size);
    }
    scene.meshes.push_back(std::move(mesh));
  }
  // Most cameras look at one of the finite primitives from 1 to 1000 times its size; the rest look
  // anywhere from anywhere in the scene.
  if (!targets.empty() && random.uniform() < 0.75) {
    const auto& [centre, size] = targets[random.below(targets.size())];
    scene.camera.to = centre;
    scene.camera.from = centre + size * std::pow(10.0, random.uniform(0.0, 3.0)) * random.unit_vector();
  } else {
    scene.camera.from = random_point(random, magnitude);
    scene.camera.to = scene.camera.from + magnitude * random.unit_vector();
  }
  scene.camera.up = random.uniform() < 0.5 ? glm::dvec3(0.0, 1.0, 0.0) : random.unit_vector();
  scene.camera.fovy_degrees = random.uniform(1.0, 170.0);
  return scene;
}

// The scenes of seeds first .. first + count - 1.
void expect_random_scenes_within_envelope(Magnitudes magnitudes, int first, int count) {
  const int scenes = count;
  constexpr uint32_t width = 40, height = 30;
  size_t hits = 0;
  for (int seed = first; seed < first + count; ++seed) {
    const Scene scene = random_scene(static_cast<uint64_t>(seed), width, height, magnitudes);
    if (scene.spheres.empty() && scene.planes.empty() && scene.meshes.empty()) continue;
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Frame frame = test::render(scene);
    size_t bad_depth = 0, bad_normal = 0;
    for (size_t p = 0; p < frame.pixel_count(); ++p) {
      const float depth = frame.depth[p];
      const glm::dvec3 normal(frame.normal_at(p));
      const bool hit = std::isfinite(depth);
      hits += hit ? 1 : 0;
      if (std::isnan(depth) || !(depth > 0.0f) || (!hit && depth != INFINITY)) ++bad_depth;
      const double length = glm::length(normal);
      // A float normalize leaves the length within a few ulp of 1.
      const bool unit = std::abs(length - 1.0) < 1e-6;
      if (std::isnan(length) || (hit && !unit) || (!hit && length != 0.0)) ++bad_normal;
    }
    EXPECT_EQ(bad_depth, 0u);
    EXPECT_EQ(bad_normal, 0u);
    const test::EnvelopeReport report = test::check_against_reference(scene, frame);
    EXPECT_EQ(report.failures, 0u) << report.describe();
    // On a CPU device the default takes triangle edge functions from double products; the float
    // arithmetic with its error-free fallback, which GPUs run, must meet the same envelope.
    if (scene.triangle_count() > 0) {
      ShaderVariant float_edges;
      float_edges.edges = EdgeArithmetic::float_error_free;
      const test::EnvelopeReport float_report = test::check_against_reference(scene, test::render(scene, float_edges));
      EXPECT_EQ(float_report.failures, 0u) << "float-edges: " << float_report.describe();
    }
  }
  // Not a vacuous pass: a good share of all pixels see something.
  EXPECT_GT(hits, static_cast<size_t>(scenes) * width * height / 5);
  std::printf("    %zu of %d pixels hit\n", hits, scenes * static_cast<int>(width * height));
}

// 120 scenes of each kind, in six shards of 20 seeds: a test each, within the suite's budget (shards
// of 30 took 25 to 34 s on 2 cores).
constexpr int scenes_a_shard = 20;

class RandomScenes : public ::testing::TestWithParam<int> {};

TEST_P(RandomScenes, NoNaNUnitNormalsAndWithinTheEnvelope) {
  expect_random_scenes_within_envelope(Magnitudes::per_scene, 1 + GetParam() * scenes_a_shard, scenes_a_shard);
}

TEST_P(RandomScenes, EightDecadesInOneSceneWithinTheEnvelope) {
  expect_random_scenes_within_envelope(Magnitudes::per_primitive, 1 + GetParam() * scenes_a_shard, scenes_a_shard);
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomScenes, ::testing::Range(0, 6));

}  // namespace
}  // namespace vkray
