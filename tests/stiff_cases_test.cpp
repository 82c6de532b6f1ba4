// The numerically hard cases (engine/bench/stiff_cases.hpp), each a test: the default shader writes no
// NaN and stays within the reference envelope (engine/reference/envelope.cpp) on every pixel; the
// textbook variant the case is about (StiffCase::fails_with) leaves it, so the test would notice
// the fix being undone. Cases no variant fails say why in StiffCase::why.
#include "engine/bench/bench.hpp"
#include "engine/bench/stiff_cases.hpp"
#include "tests/gpu_test_support.hpp"

#include <cmath>

namespace vkray {
namespace {

constexpr uint32_t test_width = 64, test_height = 48;

const std::vector<StiffCase>& cases() {
  static const std::vector<StiffCase> all = stiff_cases(test_width, test_height);
  return all;
}

Frame render_with(const Scene& scene, const RendererOptions& options) {
  Renderer renderer(test::device(), scene, options);
  return renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
}

size_t nan_pixels(const Frame& frame) {
  size_t count = 0;
  for (size_t p = 0; p < frame.pixel_count(); ++p) {
    const glm::vec3 normal = frame.normal_at(p);
    count += std::isnan(frame.depth[p]) || std::isnan(normal.x) || std::isnan(normal.y) || std::isnan(normal.z);
  }
  return count;
}

class StiffCaseTest : public ::testing::TestWithParam<size_t> {};

TEST_P(StiffCaseTest, DefaultWithinTheEnvelopeTextbookVariantNot) {
  const StiffCase& stiff = cases()[GetParam()];
  SCOPED_TRACE(stiff.name + ": " + stiff.what);
  const Frame frame = test::render(stiff.scene);
  EXPECT_EQ(nan_pixels(frame), 0u);
  // Above a million pixels (7680x4320) every 64th row is checked: 520k of them.
  const uint32_t row_step = frame.pixel_count() > 1'000'000 ? 64 : 1;
  const test::EnvelopeReport report = test::check_against_reference(stiff.scene, frame, row_step);
  EXPECT_EQ(report.failures, 0u) << report.describe();
  std::printf("    default: %s\n", report.stats.summary().c_str());
  // The 7680x4320 case is about the image's size (tiles, buffers, readback), which the default's
  // render takes; the other arithmetics and walks are the smaller cases' subject (at this size their
  // renders took 120 of the test's 132 s, the ray queries most).
  if (row_step > 1) {
    std::printf("    the other arithmetics and walks: left to the smaller cases\n");
    return;
  }
  // On a CPU device the default takes edge functions from double products; the float arithmetic
  // with its error-free fallback, which GPUs run, must meet the same bounds.
  if (stiff.scene.triangle_count() > 0) {
    const Frame float_edges = render_with(stiff.scene, find_bench_variant("float-edges").options);
    const test::EnvelopeReport float_report = test::check_against_reference(stiff.scene, float_edges, row_step);
    EXPECT_EQ(float_report.failures, 0u) << "float-edges: " << float_report.describe();
  }
  // The device's own structures propose the candidates; vkray's tests decide (ray_query_walk.glsl).
  if (test::ray_queries() && (stiff.scene.triangle_count() > 0 || !stiff.scene.spheres.empty())) {
    RendererOptions options;
    options.scene.search = PrimitiveSearch::ray_query;
    const Frame queried = render_with(stiff.scene, options);
    const test::EnvelopeReport queried_report = test::check_against_reference(stiff.scene, queried, row_step);
    EXPECT_EQ(queried_report.failures, 0u) << "ray queries: " << queried_report.describe();
    std::printf("    ray queries: %s\n", queried_report.stats.summary().c_str());
  }

  if (stiff.fails_with.empty()) {
    EXPECT_FALSE(stiff.why.empty()) << "a case no variant fails must say why";
    return;
  }
  const Frame textbook = render_with(stiff.scene, find_bench_variant(stiff.fails_with).options);
  const test::EnvelopeReport textbook_report = test::check_against_reference(stiff.scene, textbook);
  EXPECT_GT(textbook_report.failures, 0u) << stiff.fails_with << " stays within the envelope: the case tests nothing";
  std::printf("    %s: %zu pixels outside; %s\n", stiff.fails_with.c_str(), textbook_report.failures,
              textbook_report.stats.summary().c_str());
}

std::string case_name(const ::testing::TestParamInfo<size_t>& info) {
  std::string name = cases()[info.param].name;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Cases, StiffCaseTest, ::testing::Range(size_t{0}, cases().size()), case_name);

const StiffCase& named(const std::string& name) {
  for (const auto& stiff : cases()) {
    if (stiff.name == name) return stiff;
  }
  throw std::invalid_argument("no stiff case " + name);
}

bool same_bits(const Frame& a, const Frame& b) {
  return a.depth == b.depth && a.normal == b.normal;
}

// Coincident surfaces: the documented tie-break makes the plane win wherever a triangle lies in it,
// so the image is bit for bit the plane's alone; without the rule rounding would pick per pixel.
TEST(CoincidentSurfaces, ATriangleInAPlaneLeavesThePlanesImage) {
  const Scene& with_triangle = named("triangle-in-plane").scene;
  Scene plane_alone = with_triangle;
  plane_alone.meshes.clear();
  EXPECT_TRUE(same_bits(test::render(with_triangle), test::render(plane_alone)));
}

// Identical triangles tie exactly; whichever wins, the outputs are the same as one copy's.
TEST(CoincidentSurfaces, IdenticalTrianglesGiveOneTrianglesImage) {
  const Scene& triple = named("identical-triangles").scene;
  Scene single = triple;
  single.meshes[0].triangles.resize(1);
  EXPECT_TRUE(same_bits(test::render(triple), test::render(single)));
}

// The image does not depend on the run: the same scene twice gives the same bits.
TEST(CoincidentSurfaces, ASphereTouchingAPlaneRendersTheSameEveryRun) {
  const Scene& touching = named("sphere-touching-plane").scene;
  EXPECT_TRUE(same_bits(test::render(touching), test::render(touching)));
}

// A ray exactly parallel to a plane misses it: depth +inf and normal 0 on the middle row.
TEST(PlaneParallelRays, TheParallelRowMisses) {
  const Scene& scene = named("plane-parallel-rays").scene;
  const Frame frame = test::render(scene);
  const uint32_t middle = scene.height / 2;
  for (uint32_t i = 0; i < scene.width; ++i) {
    const size_t p = size_t{middle} * scene.width + i;
    EXPECT_EQ(frame.depth[p], INFINITY) << "pixel " << i;
    EXPECT_EQ(frame.normal_at(p), glm::vec3(0.0f)) << "pixel " << i;
  }
  EXPECT_TRUE(std::isfinite(frame.depth[size_t{middle + 1} * scene.width]));  // the row below hits
}

// The float64 shader agrees with the reference to 1e-12 (relative depth) on every case that
// needs no more than the built-in size.
TEST(Float64Shader, AgreesWithTheReferenceTo1e12) {
  RendererOptions options;
  options.shader.precision = Precision::float64;
  for (const auto& stiff : cases()) {
    if (size_t{stiff.scene.width} * stiff.scene.height > size_t{test_width} * test_height) continue;
    SCOPED_TRACE(stiff.name);
    const Frame frame = render_with(stiff.scene, options);
    const auto reference = render_reference_hits(ReferenceScene(stiff.scene), stiff.scene.camera,
                                                 stiff.scene.width, stiff.scene.height);
    const FrameError error = measure_error(frame, reference);
    EXPECT_EQ(error.hit_mismatches, 0u) << error.summary();
    EXPECT_LE(error.depth_max, 1e-12) << error.summary();
  }
}

}  // namespace
}  // namespace vkray
