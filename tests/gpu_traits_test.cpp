// What a real GPU brings that lavapipe does not, forced on lavapipe (VKRAY_DEVICE_OVERRIDE, a
// fence timeout of 1 ms, the validation layer hidden from the loader): a device that refuses the
// packet walk and ray queries, work that never finishes, a machine without the layer, a discrete
// GPU's transfer. Each test makes its own devices after setting the environment and restores it.
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace vkray {
namespace {

// Sets an environment variable for the scope, then restores what was there.
class ScopedVariable {
 public:
  ScopedVariable(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value, 1);
  }
  ~ScopedVariable() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }
  ScopedVariable(const ScopedVariable&) = delete;
  ScopedVariable& operator=(const ScopedVariable&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

const Scene& small_scene() {
  static const Scene scene = test::sized(default_scene(), 32, 24);
  return scene;
}

// A device without double edge functions by default and without ray queries refuses both
// traversals by name, before anything is built or uploaded: under the validation layer (which the
// suite runs) an upload with ray-query usage on a device without the feature aborts the process.
TEST(GpuTraits, RefusedTraversalsAreRefusedBeforeAnyUpload) {
  const ScopedVariable override_device("VKRAY_DEVICE_OVERRIDE", "discrete,no-ray-query");
  GpuDevice device;
  EXPECT_EQ(device.info().type, "discrete");
  EXPECT_FALSE(device.info().ray_query);
  EXPECT_EQ(device.info().overridden, "discrete,no-ray-query");
  for (const PrimitiveSearch search : {PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query}) {
    SCOPED_TRACE(traversal_name(search));
    RendererOptions options;
    options.scene.search = search;
    try {
      Renderer renderer(device, small_scene(), options);
      FAIL() << "not refused";
    } catch (const GpuError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("traversal '" + std::string(traversal_name(search)) + "' cannot run on"), std::string::npos)
          << message;
      EXPECT_EQ(message, message.substr(0, message.find('\n'))) << "one line";
    }
  }
  // What such a device runs by default: the walk per ray with float edge functions, exactly.
  Renderer renderer(device, small_scene());
  EXPECT_EQ(renderer.scene_stats().search, PrimitiveSearch::bvh_per_ray);
  test::expect_frame_matches_reference(small_scene(), renderer.render(small_scene().camera, 32, 24, {Aov::depth, Aov::normal}));
  // Asked for by name with double edge functions, which such a device has, the packet walk runs.
  ShaderVariant double_edges;
  double_edges.edges = EdgeArithmetic::double_products;
  EXPECT_EQ(search_obstacle(PrimitiveSearch::bvh_packet, device.info(), double_edges), "");
}

TEST(GpuTraits, UnknownOverrideWordsAreRefused) {
  const ScopedVariable override_device("VKRAY_DEVICE_OVERRIDE", "discrete,fast");
  EXPECT_THROW(GpuDevice(), GpuError);
}

// A submission that does not finish within the fence timeout is a lost device, in one line, and
// nothing more runs on it; the process neither hangs nor aborts (the suite's validation layer would
// abort on objects destroyed while in use).
TEST(GpuTraits, AFenceTimeoutIsADeviceLossNotAHang) {
  const ScopedVariable timeout("VKRAY_FENCE_TIMEOUT_MS", "1");
  GpuDevice device;
  const Scene scene = test::sized(default_scene(), 1920, 1080);
  RendererOptions options;
  options.dispatch_budget_ms = 0.0;  // one dispatch of the whole image: far over 1 ms on lavapipe
  try {
    Renderer renderer(device, scene, options);
    renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
    FAIL() << "no timeout";
  } catch (const DeviceLostError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("did not finish a submission within 1 ms"), std::string::npos) << message;
  }
  EXPECT_THROW(Renderer(device, small_scene()), DeviceLostError) << "the device is treated as lost";
}

TEST(GpuTraits, FenceTimeoutsMustBeWholeMilliseconds) {
  for (const char* bad : {"0", "-5", "1.5", "soon", "99999999999999999999"}) {
    const ScopedVariable timeout("VKRAY_FENCE_TIMEOUT_MS", bad);
    EXPECT_THROW(GpuDevice(), GpuError) << bad;
  }
}

// A GPU server seldom has the validation layer: VKRAY_VALIDATION=if-installed runs without it
// where the loader lists none, VKRAY_VALIDATION=1 refuses to start without it.
TEST(GpuTraits, ValidationIfInstalledRunsWithoutTheLayer) {
  const ScopedVariable hidden("VK_LOADER_LAYERS_DISABLE", "VK_LAYER_KHRONOS_validation");
  {
    const ScopedVariable validation("VKRAY_VALIDATION", "if-installed");
    GpuDevice device;
    EXPECT_FALSE(device.validation());
  }
  const ScopedVariable validation("VKRAY_VALIDATION", "1");
  try {
    GpuDevice device;
    FAIL() << "started without the layer";
  } catch (const GpuError& error) {
    EXPECT_NE(std::string(error.what()).find("validation layer is missing"), std::string::npos) << error.what();
  }
}

// The transfer a device takes by default, and the memory its shaders' buffers are in, as opened:
// a discrete GPU stages (its host-visible memory, where it has any, is read uncached across the
// bus); direct always maps the shaders' buffers; what is reported is what was taken.
TEST(GpuTraits, TheTransferReportedIsTheOneTaken) {
  // The automatic choice is tested: a transfer forced by the suite (Staging.*) is lifted here.
  const ScopedVariable automatic_transfer_choice("VKRAY_TRANSFER", "");
  {
    const ScopedVariable override_device("VKRAY_DEVICE_OVERRIDE", "discrete");
    GpuDevice discrete;
    EXPECT_EQ(discrete.transfer(), TransferMode::staging);
    EXPECT_EQ(discrete.transfer_description().rfind("staging (shaders' buffers in memory type", 0), 0u)
        << discrete.transfer_description();
  }
  GpuDevice direct({}, TransferMode::direct);
  EXPECT_NE(direct.transfer_description().find("host-visible, coherent"), std::string::npos)
      << direct.transfer_description();
  EXPECT_EQ(GpuDevice().transfer(), automatic_transfer(GpuDevice().info()).mode);
}

// Staging copies back what each dispatch wrote, not the whole tile's buffers: with dispatches of a
// few rows, the bytes read back are the image's outputs once.
TEST(GpuTraits, StagingReadsBackOnlyTheRowsWritten) {
  GpuDevice device({}, TransferMode::staging);
  const Scene scene = test::sized(default_scene(), 1024, 160);  // the first dispatch: 65536 pixels, 64 rows
  RendererOptions options;
  options.dispatch_budget_ms = 1e-6;  // a workgroup's rows a dispatch after the first
  Renderer renderer(device, scene, options);
  const Frame frame = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal, Aov::uv});
  EXPECT_GT(renderer.timings().tiles, 3u);
  // Depth, normal and uv; where a loop budget applies, the count of the list of unfinished rays a
  // dispatch (the list itself only where it lists any, and here no ray runs out).
  const bool budget = renderer.scene_stats().loop_budget > 0;
  const uint64_t pixels = uint64_t{scene.width} * scene.height;
  const uint64_t expected = pixels * (1 + 3 + 2) * sizeof(float) + (budget ? renderer.timings().tiles * sizeof(uint32_t) : 0);
  EXPECT_EQ(renderer.timings().unfinished_rays, 0u);
  EXPECT_EQ(renderer.timings().readback_bytes, expected);
  test::expect_frame_matches_reference(scene, frame);
}

// An occlusion query and a count of crossings write and read back each ray's answer alone, 4 bytes,
// not a nearest hit's depth and normal beside it; the answers are the nearest-hit call's (whether
// it hit) and the reference's (how many crossings). Rays through a 128x40 image, listed as its rows:
// whole packet blocks and workgroup rows, so every position written is a ray's.
TEST(GpuTraits, OcclusionQueriesAndCountsReadBackTheirAnswersAlone) {
  GpuDevice device({}, TransferMode::staging);
  const Scene scene = default_scene();
  constexpr uint32_t width = 128, height = 40;
  const CameraBasis basis = make_camera_basis(scene.camera, width, height);
  std::vector<GivenRay> rays;
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) {
      const PixelRay ray = pixel_ray(scene.camera, basis, i, j, width, height);
      rays.push_back({ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z});
    }
  }
  Renderer renderer(device, scene);
  const bool budget = renderer.scene_stats().loop_budget > 0;
  auto answers_alone = [&] {
    return uint64_t{rays.size()} * sizeof(uint32_t) + (budget ? renderer.timings().tiles * sizeof(uint32_t) : 0);
  };
  const RayHits nearest = renderer.cast_rays(rays);
  EXPECT_GT(renderer.timings().readback_bytes, 4 * answers_alone()) << "a nearest hit's depth and normal too";
  const std::vector<uint8_t> occluded = renderer.occluded(rays);
  EXPECT_EQ(renderer.timings().readback_bytes, answers_alone());
  const std::vector<uint32_t> crossings = renderer.count_intersections(rays);
  EXPECT_EQ(renderer.timings().readback_bytes, answers_alone());
  EXPECT_EQ(renderer.timings().unfinished_rays, 0u);
  const ReferenceScene reference(scene);
  size_t hit = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    EXPECT_EQ(occluded[k], nearest.object[k] != no_object ? 1 : 0) << "ray " << k;
    hit += occluded[k];
    EXPECT_EQ(crossings[k], count_reference_crossings(reference, rays[k], 0.0, no_hit)) << "ray " << k;
  }
  EXPECT_GT(hit, rays.size() / 4);
  EXPECT_LT(hit, rays.size());
}

}  // namespace
}  // namespace vkray
