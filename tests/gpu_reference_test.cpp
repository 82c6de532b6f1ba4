// GPU output against the double-precision reference, pixel by pixel, on lavapipe (or any device).
#include "engine/scene/camera.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "shaders/gpu_layout.h"
#include "tests/gpu_test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace vkray {
namespace {

using namespace test;

TEST(GpuReference, DefaultScene) { expect_matches_reference(sized(default_scene(), 160, 120)); }

TEST(GpuReference, DefaultSceneOnePixel) { expect_matches_reference(sized(default_scene(), 1, 1)); }

TEST(GpuReference, DefaultSceneWideOddSize) { expect_matches_reference(sized(default_scene(), 97, 31)); }

TEST(GpuReference, DefaultScenePortraitOddSize) { expect_matches_reference(sized(default_scene(), 31, 97)); }

// Rays nearly parallel to a plane: the camera sits 1e-3 above the ground looking at the horizon.
TEST(GpuReference, GrazingPlane) {
  Scene scene;
  scene.camera = {{0, 1e-3, 0}, {0, 1e-3, -1}, {0, 1, 0}, 60};
  scene.planes.push_back({{0, 0, 0}, {0, 1, 0}});
  expect_matches_reference(sized(scene, 64, 64));
}

// A sphere of radius 1e-2 at distance 1e3 seen through a narrow lens (it fills the view), and a
// sphere of radius 1e5 used as a ground right under the camera: the two cancellation cases of the
// textbook quadratic.
TEST(GpuReference, TinyFarSphereAndHugeNearSphere) {
  Scene tiny;
  tiny.camera = {{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 2e-3};
  tiny.spheres.push_back({{1e-3, 0, -1e3}, 1e-2});
  expect_matches_reference(sized(tiny, 48, 48), Percentiles::ill_conditioned);

  Scene huge;
  huge.camera = {{0, 2, 0}, {0, 0, -10}, {0, 1, 0}, 70};
  huge.spheres.push_back({{0, -1e5, 0}, 1e5});
  expect_matches_reference(sized(huge, 64, 48), Percentiles::ill_conditioned);
}

// A field of view of 1e-18 degrees and a focal length of 1e30 pixels put the image plane 1e20 and
// more away: its vectors' squares overflow float32 unless scaled (CameraBasis::step_scale), and the
// GPU missed every pixel the reference hit.
TEST(GpuReference, ExtremelyNarrowFieldsOfView) {
  Scene scene = sized(default_scene(), 32, 24);
  Scene by_intrinsics = scene;
  by_intrinsics.camera.intrinsics = PinholeIntrinsics{1e30, 1e30, 15.5, 11.5};
  for (const double fovy : {1e-18, 1e-300}) {
    scene.camera.fovy_degrees = fovy;
    for (const Scene& narrow : {scene, by_intrinsics}) {
      SCOPED_TRACE(narrow.camera.intrinsics ? "fx = 1e30" : "fovy = " + std::to_string(fovy));
      const Frame frame = render(narrow);
      // The default camera looks at the middle sphere: every pixel sees it.
      EXPECT_EQ(std::count_if(frame.depth.begin(), frame.depth.end(), [](float depth) { return std::isfinite(depth); }),
                32 * 24);
      expect_frame_matches_reference(narrow, frame);
    }
  }
}

TEST(GpuReference, CameraInsideSphere) {
  Scene scene;
  scene.camera = {{0.2, 0.1, 0}, {1, 0, -1}, {0, 1, 0}, 90};
  scene.spheres.push_back({{0, 0, 0}, 3});
  expect_matches_reference(sized(scene, 48, 48));
}

// Looking straight down and straight up with up = +y: the course formula's right vector is 0/0;
// the fallback frame must give a correct image.
TEST(GpuReference, CameraLookingStraightDownAndUp) {
  Scene scene = default_scene();
  scene.camera = {{0.3, 6, 0.2}, {0.3, 0, 0.2}, {0, 1, 0}, 60};
  expect_matches_reference(sized(scene, 64, 48));
  scene.camera = {{0.3, 0.5, 0.2}, {0.3, 9, 0.2}, {0, 1, 0}, 60};
  scene.spheres.push_back({{0.3, 4, 0.2}, 1});
  expect_matches_reference(sized(scene, 64, 48));
}

// The default scene moved to x = 1e6, z = -2e6: float32 steps there are 0.06-0.125 units, so
// without the anchor-relative upload the image would fall apart. It must match both the reference
// and the untranslated render.
TEST(GpuReference, LargeWorldCoordinates) {
  const Scene original_scene = sized(default_scene(), 96, 72);
  const Frame original = render(original_scene);
  const Scene scene = translated(original_scene, {1e6, 0, -2e6});
  expect_matches_reference(scene);
  const Frame moved = render(scene);
  size_t differing_hits = 0;
  for (size_t p = 0; p < moved.pixel_count(); ++p) differing_hits += moved.hit(p) != original.hit(p);
  EXPECT_LE(differing_hits, 2u);
}

// Needle triangles (aspect ratio 1e6) and exactly degenerate ones (repeated vertex, collinear)
// in one mesh with a normal triangle.
TEST(GpuReference, NeedleAndDegenerateTriangles) {
  Scene scene;
  scene.camera = {{0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 50};
  Mesh mesh;
  mesh.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0},              // regular
                    {-1.2, 0.2, 0.5}, {1.2, 0.2, 0.5}, {0, 0.2 + 2.4e-6, 0.5},  // needle, 1e-6 high
                    {-1, 0.6, 0.2}, {1, 0.6, 0.2}, {0, 0.6, 0.2},     // collinear
                    {0.5, 0.5, 0.1}};
  mesh.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 9, 0}, {0, 2, 2}};
  scene.meshes.push_back(mesh);
  expect_matches_reference(sized(scene, 64, 64));
}

// A plane made of 2 x 16 x 16 triangles, viewed so that many pixel-centre rays pass exactly
// through shared edges and vertices. Watertight intersection must hit every pixel: a single miss
// is a crack.
TEST(GpuReference, SharedEdgesHaveNoCracks) {
  Scene scene;
  scene.camera = {{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 90};
  scene.meshes.push_back(quad_grid({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}, 16));
  for (uint32_t size : {64u, 65u}) {
    const Frame frame = render(sized(scene, size, size));
    size_t misses = 0;
    for (size_t p = 0; p < frame.pixel_count(); ++p) misses += !frame.hit(p);
    EXPECT_EQ(misses, 0u) << "cracks at " << size << "x" << size;
  }
  // A tilted, irregular grid too, against the reference.
  scene.meshes[0] = quad_grid({-3, -2.5, -1}, {6.1, 0.3, 1.7}, {-0.2, 5.3, 0.9}, 23);
  expect_matches_reference(sized(scene, 80, 80));
}

TEST(GpuReference, ObjMeshWithQuadsAndNegativeIndices) {
  Scene scene;
  scene.camera = {{2.5, 3, 4}, {0, 1, 0}, {0, 1, 0}, 40};
  // An octahedron written with n-gon-free negative indices and a quad pyramid base.
  scene.meshes.push_back(load_obj_text("v 0 2 0\nv 1 1 0\nv 0 1 1\nv -1 1 0\nv 0 1 -1\nv 0 0 0\n"
                                       "f -6 -4 -5\nf -6 -3 -4\nf -6 -2 -3\nf -6 -5 -2\nf -1 -5 -4\nf -1 -4 -3\n"
                                       "f -1 -3 -2\nf -1 -2 -5\n",
                                       "octahedron.obj"));
  scene.planes.push_back({{0, 0, 0}, {0, 1, 0}});
  expect_matches_reference(sized(scene, 72, 56));
}

// lavapipe stops a shader invocation after 65535 loop iterations in total. Loops without a tree
// (spheres, planes) have a static count: a scene that needs more is refused with a clear error,
// never rendered with geometry silently missing.
TEST(GpuRenderer, SceneBeyondTheDriversLoopLimitIsRefused) {
  const uint64_t limit = device().info().max_loop_iterations;
  if (limit == 0) GTEST_SKIP() << device().info().name << " has no known loop limit";
  Scene scene;
  scene.camera = {{0, 0, 2}, {0, 0, 0}, {0, 1, 0}, 90};
  scene.planes.assign(limit, Plane{{0, 0, -1}, {0, 0, 1}});
  try {
    Renderer renderer(device(), scene);
    FAIL() << "a scene of " << scene.planes.size() << " planes was accepted";
  } catch (const GpuError& error) {
    EXPECT_NE(std::string(error.what()).find("loop iterations"), std::string::npos) << error.what();
  }
}

// A tree walk has no static bound. A ray that runs out of the loop budget is finished on the CPU:
// with a budget of a few iterations almost every ray runs out, and the image still matches the
// reference on every pixel, so no geometry was dropped.
TEST(GpuRenderer, RaysBeyondTheLoopBudgetAreFinishedNotDropped) {
  Scene scene = sized(default_scene(), 48, 36);
  scene.meshes.push_back(quad_grid({-3, 0.01, -3}, {6, 0, 0}, {0, 0, 6}, 40));
  for (const PrimitiveSearch search : runnable({PrimitiveSearch::bvh_per_ray, PrimitiveSearch::bvh_packet})) {
    RendererOptions options;
    options.scene.search = search;
    options.loop_budget = 3;
    Renderer renderer(device(), scene, options);
    const Frame frame = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
    EXPECT_GT(renderer.timings().unfinished_rays, frame.pixel_count() / 4);  // all that hit the grid
    expect_frame_matches_reference(scene, frame);
  }
}

TEST(GpuRenderer, TilingGivesIdenticalImages) {
  const Scene scene = sized(default_scene(), 64, 48);
  const AovSet all{Aov::depth, Aov::normal, Aov::uv};
  Renderer whole(device(), scene);
  const Frame reference = whole.render(scene.camera, 64, 48, all);
  EXPECT_EQ(whole.timings().tiles, 1u);
  RendererOptions tiled_options;
  tiled_options.max_tile_bytes = 64 * 12 * 5;  // 5 rows of normals per tile
  Renderer tiled(device(), scene, tiled_options);
  const Frame frame = tiled.render(scene.camera, 64, 48, all);
  EXPECT_EQ(tiled.timings().tiles, 10u);
  EXPECT_EQ(0, std::memcmp(frame.depth.data(), reference.depth.data(), frame.depth.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(frame.normal.data(), reference.normal.data(), frame.normal.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(frame.uv.data(), reference.uv.data(), frame.uv.size() * sizeof(float)));
}

// Dispatches sized by their measured time: a budget far below what a row takes leaves one
// workgroup's rows a dispatch after the first (8 per ray, 32 for the packet walk), and the pixels
// are those of one dispatch. Under the default budget the count depends on the times measured (a
// loaded machine takes more): the first dispatch holds 64 of the 160 rows, so at least two, and the
// images are the same; dispatch_sizer_test.cpp checks the sizes for given times.
TEST(GpuRenderer, DispatchesSizedByTimeGiveIdenticalImages) {
  const Scene scene = sized(default_scene(), 1024, 160);  // the first dispatch: 65536 pixels, 64 rows
  const AovSet all{Aov::depth, Aov::normal, Aov::uv};
  for (const auto& [search, row_step] : {std::pair{PrimitiveSearch::bvh_per_ray, uint32_t{VKRAY_WORKGROUP_Y}},
                                         std::pair{PrimitiveSearch::bvh_packet, uint32_t{VKRAY_PACKET_GROUP_HEIGHT}}}) {
    if (runnable({search}).empty()) continue;
    SCOPED_TRACE(testing::Message() << "search " << int(search));
    RendererOptions unbudgeted;
    unbudgeted.dispatch_budget_ms = 0.0;
    unbudgeted.scene.search = search;
    Renderer whole(device(), scene, unbudgeted);
    const Frame reference = whole.render(scene.camera, 1024, 160, all);
    EXPECT_EQ(whole.timings().tiles, 1u);

    RendererOptions tight = unbudgeted;
    tight.dispatch_budget_ms = 1e-6;
    Renderer budgeted(device(), scene, tight);
    const Frame frame = budgeted.render(scene.camera, 1024, 160, all);
    EXPECT_EQ(budgeted.timings().tiles, 1u + 96u / row_step);
    EXPECT_GT(budgeted.timings().longest_dispatch_ms, 0.0);
    EXPECT_EQ(0, std::memcmp(frame.depth.data(), reference.depth.data(), frame.depth.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(frame.normal.data(), reference.normal.data(), frame.normal.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(frame.uv.data(), reference.uv.data(), frame.uv.size() * sizeof(float)));

    RendererOptions generous_options;  // the default budget, 200 ms
    generous_options.scene.search = search;
    Renderer generous(device(), scene, generous_options);
    for (int render = 0; render < 2; ++render) {  // the second with the scene's cost known
      const Frame again = generous.render(scene.camera, 1024, 160, all);
      if (render == 0) {
        EXPECT_GE(generous.timings().tiles, 2u);
      }
      EXPECT_EQ(0, std::memcmp(again.depth.data(), reference.depth.data(), again.depth.size() * sizeof(float)));
      EXPECT_EQ(0, std::memcmp(again.normal.data(), reference.normal.data(), again.normal.size() * sizeof(float)));
    }
  }
}

// One Renderer, many renders: a new camera and size must give what a fresh Renderer gives, and
// each output alone must equal the same output rendered together with the others.
// The first pipeline made beside the tree's build (RendererOptions::first_aovs) renders what one
// made on first use renders; where the built scene turns out other than planned (zero-area triangles
// dropped, leaving few enough for brute force), it is made again, not used.
TEST(GpuRenderer, FirstPipelineMadeBesideTheUploadRendersTheSame) {
  Scene dropped = sized(default_scene(), 48, 36);
  dropped.meshes.clear();
  dropped.spheres.clear();
  Mesh mesh;  // 9 triangles planned, a tree; all of them zero-area, so none is built
  for (int k = 0; k < 9; ++k) {
    const double x = k - 4.0;
    mesh.positions.insert(mesh.positions.end(), {{x, 0, 0}, {x + 0.8, 0, 0}, {x + 0.4, 0, 0}});
    mesh.triangles.push_back({3u * k, 3u * k + 1, 3u * k + 2});
  }
  dropped.meshes.push_back(mesh);
  const AovSet aovs{Aov::depth, Aov::normal};
  for (const auto& [scene, planned_as_built] : {std::pair{sized(default_scene(), 48, 36), true}, {dropped, false}}) {
    Renderer on_first_use(device(), scene);
    const Frame expected = on_first_use.render(scene.camera, scene.width, scene.height, aovs);
    RendererOptions options;
    options.first_aovs = aovs;
    Renderer prepared(device(), scene, options);
    EXPECT_EQ(prepared.timings().pipeline_beside_upload_ms > 0.0,
              planned_as_built && device().info().favours_packet_walk);
    const Frame frame = prepared.render(scene.camera, scene.width, scene.height, aovs);
    EXPECT_EQ(0, std::memcmp(frame.depth.data(), expected.depth.data(), frame.depth.size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(frame.normal.data(), expected.normal.data(), frame.normal.size() * sizeof(float)));
  }
}

TEST(GpuRenderer, RerenderAndOutputSubsets) {
  Scene scene = sized(default_scene(), 40, 30);
  Renderer renderer(device(), scene);
  renderer.render(scene.camera, 40, 30, {Aov::depth, Aov::normal});
  Camera moved = scene.camera;
  moved.from += glm::dvec3(0.5, 0.2, -1);
  moved.fovy_degrees = 30;
  const Frame again = renderer.render(moved, 23, 17, {Aov::depth, Aov::normal});
  scene.camera = moved;
  const Frame fresh = render(sized(scene, 23, 17));
  EXPECT_EQ(0, std::memcmp(again.depth.data(), fresh.depth.data(), fresh.depth.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(again.normal.data(), fresh.normal.data(), fresh.normal.size() * sizeof(float)));

  const Frame depth_only = renderer.render(moved, 23, 17, {Aov::depth});
  const Frame normal_only = renderer.render(moved, 23, 17, {Aov::normal});
  EXPECT_TRUE(depth_only.normal.empty());
  EXPECT_TRUE(normal_only.depth.empty());
  EXPECT_EQ(0, std::memcmp(depth_only.depth.data(), fresh.depth.data(), fresh.depth.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(normal_only.normal.data(), fresh.normal.data(), fresh.normal.size() * sizeof(float)));
}

// The uv output is the shader's own pixel-to-UV mapping. Vulkan allows 2.5 ulp for float
// division, so each coordinate must be within 3 ulp of the exact value; and the unit disk must
// touch the middle of both shorter borders while staying off the longer ones.
TEST(GpuRenderer, UvMappingAndUnitDisk) {
  for (auto [width, height] : {std::pair{40u, 20u}, std::pair{17u, 50u}, std::pair{1u, 1u}}) {
    Renderer renderer(device(), default_scene());
    const Frame frame = renderer.render(default_scene().camera, width, height, {Aov::uv});
    for (uint32_t j = 0; j < height; ++j) {
      for (uint32_t i = 0; i < width; ++i) {
        const glm::dvec2 exact = pixel_uv(i, j, width, height);
        const size_t p = size_t{j} * width + i;
        for (int c = 0; c < 2; ++c) {
          const double ulp = std::max(std::abs(exact[c]), 0x1p-126) * 0x1p-23;
          ASSERT_NEAR(frame.uv_at(p)[c], exact[c], 3 * ulp) << i << "," << j << " of " << width << "x" << height;
        }
      }
    }
    auto in_disk = [&](uint32_t i, uint32_t j) {
      const size_t p = size_t{j} * width + i;
      return glm::dot(frame.uv_at(p), frame.uv_at(p)) <= 1.0f;
    };
    if (width > 1 && height > 1) {
      if (width >= height) {  // touches top and bottom rows in the middle column, not the side columns
        EXPECT_TRUE(in_disk(width / 2, 0));
        EXPECT_TRUE(in_disk(width / 2, height - 1));
        EXPECT_FALSE(in_disk(0, height / 2));
      } else {
        EXPECT_TRUE(in_disk(0, height / 2));
        EXPECT_TRUE(in_disk(width - 1, height / 2));
        EXPECT_FALSE(in_disk(width / 2, 0));
      }
    }
  }
}

// Real meshes with their defects (quads, n-gons, degenerate triangles, non-manifold edges, a flat
// mesh), at a size where the brute-force reference is quick.
TEST(GpuReference, SharedModels) {
  if (!std::filesystem::is_directory(models_dir)) GTEST_SKIP() << "shared models folder " << models_dir << " is absent";
  for (const char* name : {"suzanne.obj", "cruiser.obj", "f-16.obj", "obj-spec-cube-negative-indices.obj", "alligator.obj"}) {
    SCOPED_TRACE(name);
    expect_matches_reference(framed_model(name, 80, 60));
  }
}

// Every mesh of ../shared/models (but the truncated one) renders and matches the reference, in a
// thumbnail so the brute-force reference over up to 124k triangles stays within seconds.
TEST(GpuReference, EverySharedModelRenders) {
  if (!std::filesystem::is_directory(models_dir)) GTEST_SKIP() << "shared models folder " << models_dir << " is absent";
  size_t models = 0;
  for (const auto& entry : std::filesystem::directory_iterator(models_dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".obj" || name.find("truncated") != std::string::npos) continue;
    SCOPED_TRACE(name);
    const Scene scene = framed_model(name.c_str(), 24, 18);
    const Frame frame = render(scene);
    size_t hits = 0;
    for (size_t p = 0; p < frame.pixel_count(); ++p) hits += frame.hit(p);
    EXPECT_GT(hits, 0u) << "the framed model is in view";
    const test::EnvelopeReport report = test::check_against_reference(scene, frame);
    EXPECT_EQ(report.failures, 0u) << report.describe();
    ++models;
  }
  EXPECT_GE(models, 20u);
}

}  // namespace
}  // namespace vkray
