// Ray masks (Renderer::set_ray_mask, the scene's masks): in every search, shader variant and kind of
// ray, what a mask hides is never hit and what it lets through is traced as the reference traces the
// scene without what it hides.
#include "engine/reference/reference.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/render/gpu_scene_encoding.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <set>

namespace vkray {
namespace {

using namespace test;

// The built-in scene, each object with a mask of its own bit: the pyramid 1, the cube 2, the sphere
// 4, the ground plane 8; with `tree_spheres`, twelve small spheres more (masks 16 and 32 in turn),
// enough for the tree to hold them (a handful are tested one by one beside it).
Scene masked_scene(bool tree_spheres) {
  Scene scene = sized(default_scene(), 64, 48);
  scene.meshes[0].mask = 1;
  scene.meshes[1].mask = 2;
  scene.spheres[0].mask = 4;
  scene.planes[0].mask = 8;
  if (tree_spheres) {
    for (int k = 0; k < 12; ++k) {
      scene.spheres.push_back({{-1.9 + 0.35 * k, 0.25 + 0.1 * (k % 3), 2.2}, 0.15, Mask(k % 2 == 0 ? 16 : 32)});
    }
  }
  return scene;
}

// Ray masks each test takes: every bit first, then each object's bit alone, pairs, all but one.
constexpr Mask ray_masks[] = {0xff, 1, 2, 4, 8, 16, 3, 12, 0x30, 0xfe, 0xfb};

// The objects (mesh ids) a frame's pixels hit.
std::set<uint32_t> objects_hit(const Frame& frame) {
  std::set<uint32_t> objects;
  for (size_t p = 0; p < frame.pixel_count(); ++p) {
    if (frame.mesh_id[p] != no_object) objects.insert(frame.mesh_id[p]);
  }
  return objects;
}

// Renders `scene` with each ray mask and checks every pixel against the reference of what that
// mask lets through (ids too), and that exactly the objects in view with every bit that the mask
// lets through are hit: none it hides, and each of the others (hiding an object only uncovers more).
void expect_masks_render_as_reference(const Scene& scene, const RendererOptions& options) {
  Renderer renderer(device(), scene, options);
  const AovSet aovs{Aov::depth, Aov::normal, Aov::mesh_id, Aov::primitive_id};
  std::set<uint32_t> in_view;
  for (const Mask mask : ray_masks) {
    SCOPED_TRACE(testing::Message() << "ray mask " << int(mask));
    renderer.set_ray_mask(mask);
    const Frame frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
    if (options.loop_budget == 0) {
      EXPECT_EQ(renderer.timings().unfinished_rays, 0u) << "rays finished on the CPU";
    }
    std::vector<ObjectPrimitive> ids(frame.pixel_count());
    for (size_t p = 0; p < ids.size(); ++p) ids[p] = {frame.mesh_id[p], frame.primitive_id[p]};
    const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids, mask);
    EXPECT_EQ(report.failures, 0u) << report.describe();
    const std::set<uint32_t> hit = objects_hit(frame);
    if (mask == every_mask_bit) in_view = hit;
    std::set<uint32_t> expected;
    for (const uint32_t object : in_view) {
      if (mask_hits(object_mask(scene, object), mask)) expected.insert(object);
    }
    EXPECT_EQ(hit, expected);
  }
  EXPECT_EQ(in_view.size(), scene.object_count())
      << "every object must be in view";
}

TEST(Masks, EverySearchSeesWhatTheMaskLetsThrough) {
  for (const bool tree_spheres : {false, true}) {
    const Scene scene = masked_scene(tree_spheres);
    for (const PrimitiveSearch search : runnable({PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray,
                                                  PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query})) {
      RendererOptions options;
      options.scene.search = search;
      SCOPED_TRACE(variant_name(options) + (tree_spheres ? ", spheres in the tree" : ""));
      expect_masks_render_as_reference(scene, options);
    }
  }
}

// The variants that read masks their own way: the generic shader (the search mode beside the ray
// mask in one word), float64, geometry in storage buffers; and rays past a small loop budget, which
// the host finishes with the reference of the same mask.
TEST(Masks, ShaderVariantsAndRaysFinishedOnTheHost) {
  const Scene scene = masked_scene(true);
  std::vector<RendererOptions> variants(5);
  for (RendererOptions& options : variants) options.scene.search = PrimitiveSearch::bvh_per_ray;
  variants[1].shader.generic = true;
  variants[2].shader.precision = Precision::float64;
  variants[3].shader.storage_geometry = true;
  variants[4].loop_budget = 6;
  for (const RendererOptions& options : variants) {
    SCOPED_TRACE(variant_name(options));
    expect_masks_render_as_reference(scene, options);
  }
  Renderer renderer(device(), scene, variants[4]);
  renderer.set_ray_mask(2);
  renderer.render(scene.camera, scene.width, scene.height, {Aov::depth});
  EXPECT_GT(renderer.timings().unfinished_rays, 0u) << "the loop budget must leave rays to the host";
}

// cast_rays and occluded with a mask: the pixel rays given one by one (from one origin, and so the
// packet walk where it runs) against the reference of the mask; each ray occluded exactly where it
// hit something.
TEST(Masks, GivenRaysAndOcclusionQueries) {
  const Scene scene = masked_scene(true);
  const std::vector<GivenRay> rays = pixel_rays(scene);
  for (const PrimitiveSearch search : runnable({PrimitiveSearch::brute_force, PrimitiveSearch::bvh_per_ray,
                                                PrimitiveSearch::bvh_packet, PrimitiveSearch::ray_query})) {
    RendererOptions options;
    options.scene.search = search;
    Renderer renderer(device(), scene, options);
    for (const Mask mask : ray_masks) {
      SCOPED_TRACE(testing::Message() << traversal_name(search) << ", ray mask " << int(mask));
      renderer.set_ray_mask(mask);
      const RayHits hits = renderer.cast_rays(rays);
      const std::vector<uint8_t> blocked = renderer.occluded(rays);
      Frame frame(scene.width, scene.height, {Aov::depth, Aov::normal});
      frame.depth.assign(hits.t.begin(), hits.t.end());
      frame.normal.assign(hits.normal.begin(), hits.normal.end());
      std::vector<ObjectPrimitive> ids(hits.count);
      size_t hidden = 0, occlusion_differs = 0;
      for (size_t k = 0; k < hits.count; ++k) {
        ids[k] = {hits.object[k], hits.primitive[k]};
        if (ids[k].object != no_object && !mask_hits(object_mask(scene, ids[k].object), mask)) ++hidden;
        if (bool(blocked[k]) != std::isfinite(hits.t[k])) ++occlusion_differs;
      }
      EXPECT_EQ(hidden, 0u) << "rays hit objects their mask hides";
      EXPECT_EQ(occlusion_differs, 0u);
      const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids, mask);
      EXPECT_EQ(report.failures, 0u) << report.describe();
    }
  }
}

// The other ways the same rays go: after set_vertices (refitted in place from its second call), into
// the viewer's storage image, and read and written in the caller's arrays (where the device does).
TEST(Masks, MovedMeshesTheImageTargetAndRaysInPlace) {
  Scene scene = masked_scene(true);
  Renderer renderer(device(), scene);
  const AovSet aovs{Aov::depth, Aov::normal, Aov::mesh_id, Aov::primitive_id};
  for (const double shift : {0.1, 0.2}) {
    std::vector<glm::dvec3> moved = scene.meshes[0].positions;
    for (glm::dvec3& p : moved) p.x -= shift;
    renderer.set_vertices(0, moved);
    EXPECT_TRUE(renderer.timings().tree_refitted);  // the records' masks kept through the refit
    scene.meshes[0].positions = moved;
    for (const Mask mask : {Mask(1), Mask(0xfe)}) {
      SCOPED_TRACE(testing::Message() << "moved by " << shift << ", ray mask " << int(mask));
      renderer.set_ray_mask(mask);
      const Frame frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
      std::vector<ObjectPrimitive> ids(frame.pixel_count());
      for (size_t p = 0; p < ids.size(); ++p) ids[p] = {frame.mesh_id[p], frame.primitive_id[p]};
      const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids, mask);
      EXPECT_EQ(report.failures, 0u) << report.describe();
      EXPECT_EQ(objects_hit(frame).contains(0), mask == 1) << "the pyramid, mask 1";
    }
  }

  renderer.set_ray_mask(2);  // the cube alone
  const Frame cube = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth});
  ImageTarget target(device(), scene.width, scene.height);
  const DepthRange depths = renderer.render(scene.camera, Aov::depth, target);
  const DepthRange expected = finite_depth_range(cube);
  EXPECT_EQ(depths.near, expected.near);
  EXPECT_EQ(depths.far, expected.far);

  if (!renderer.casts_in_place()) GTEST_SKIP() << device().info().name << " casts no rays in place";
  const std::vector<GivenRay> rays = pixel_rays(scene);
  renderer.set_ray_mask(0x30);  // the small spheres alone
  const RayHits hits = renderer.cast_rays(rays);
  std::vector<float> t(rays.size()), normal(3 * rays.size());
  std::vector<uint32_t> object(rays.size()), primitive(rays.size());
  ASSERT_TRUE(renderer.cast_rays_in_place(rays, {t.data(), normal.data(), object.data(), primitive.data()}));
  size_t differing = 0, spheres = 0, hidden = 0;
  for (size_t k = 0; k < rays.size(); ++k) {
    differing += t[k] != hits.t[k] || object[k] != hits.object[k] || primitive[k] != hits.primitive[k];
    spheres += object[k] != no_object;
    hidden += object[k] != no_object && !mask_hits(object_mask(scene, object[k]), 0x30);
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(spheres, 0u);
  EXPECT_EQ(hidden, 0u);
}

// The reference with a mask is the reference of the scene without what the mask hides, hit for hit
// (the same double arithmetic on the same primitives; ids mapped back to the whole scene's).
TEST(Masks, ReferenceIsTheSceneWithoutWhatTheMaskHides) {
  const Scene scene = masked_scene(true);
  for (const Mask mask : ray_masks) {
    SCOPED_TRACE(testing::Message() << "ray mask " << int(mask));
    Scene kept = scene;
    std::vector<uint32_t> whole_id;  // kept's object ids in the whole scene
    kept.meshes.clear(), kept.spheres.clear(), kept.planes.clear();
    uint32_t object = 0;
    for (const Mesh& mesh : scene.meshes) {
      if (mask_hits(mesh.mask, mask)) kept.meshes.push_back(mesh), whole_id.push_back(object);
      ++object;
    }
    for (const Sphere& sphere : scene.spheres) {
      if (mask_hits(sphere.mask, mask)) kept.spheres.push_back(sphere), whole_id.push_back(object);
      ++object;
    }
    for (const Plane& plane : scene.planes) {
      if (mask_hits(plane.mask, mask)) kept.planes.push_back(plane), whole_id.push_back(object);
      ++object;
    }
    const ReferenceScene masked(scene, mask), without(kept);
    const std::vector<ReferenceHit> hits = render_reference_hits(masked, scene.camera, 96, 72);
    const std::vector<ReferenceHit> expected = render_reference_hits(without, scene.camera, 96, 72);
    size_t differing = 0;
    for (size_t p = 0; p < hits.size(); ++p) {
      const ObjectPrimitive got = masked.source(hits[p]), want = without.source(expected[p]);
      // A triangle keeps its index in its mesh; a sphere's or plane's index is its place among the whole scene's.
      ObjectPrimitive want_whole = want;
      if (want.object != no_object) {
        want_whole.object = whole_id[want.object];
        const auto meshes = static_cast<uint32_t>(scene.meshes.size()), spheres = static_cast<uint32_t>(scene.spheres.size());
        if (want.object >= kept.meshes.size()) {
          want_whole.primitive = want_whole.object - meshes - (want_whole.object >= meshes + spheres ? spheres : 0);
        }
      }
      if (hits[p].t != expected[p].t || hits[p].normal != expected[p].normal || got != want_whole) ++differing;
    }
    EXPECT_EQ(differing, 0u);
  }
}

// A scene whose objects keep every bit is specialized without masks: no mask read or tested, no
// buffer for them. One mask set turns them on, with a texel each for the spheres tested one by one
// and the planes, and each primitive's mask above its kind.
TEST(Masks, OnlyAScenesMasksAreTested) {
  Scene scene = masked_scene(false);
  for (Mesh& mesh : scene.meshes) mesh.mask = every_mask_bit;
  scene.spheres[0].mask = every_mask_bit;
  scene.planes[0].mask = every_mask_bit;
  EXPECT_FALSE(scene.has_masks());
  GpuSceneOptions options;
  options.search = PrimitiveSearch::bvh_per_ray;
  const GpuScene plain = make_gpu_scene(scene, options);
  EXPECT_FALSE(plain.shape().masks);
  EXPECT_TRUE(plain.apart_masks.empty());
  set_object_mask(scene, 1, 2);  // the cube
  EXPECT_TRUE(scene.has_masks());
  const GpuScene masked = make_gpu_scene(scene, options);
  EXPECT_TRUE(masked.shape().masks);
  EXPECT_EQ(masked.apart_masks.size(), 2u) << "the sphere tested apart and the plane";
  for (size_t slot = 0; slot < masked.primitives.size(); ++slot) {
    const uint32_t object = masked.hit_sources.slots[slot].object;
    EXPECT_EQ(scene_encoding::primitive_mask(masked.primitives[slot].indices.w), object_mask(scene, object));
  }
  EXPECT_THROW(set_object_mask(scene, 4, 1), InputError) << "two meshes, a sphere and a plane: ids 0 to 3";
  Renderer renderer(device(), scene);
  EXPECT_THROW(renderer.set_ray_mask(0), InputError);
}

std::vector<Mesh> no_models(const std::filesystem::path&) { return {}; }

// A scene file's masks: on a mesh entry (every mesh of its model), a sphere and a plane; a mask
// beyond 8 bits is refused with its place named.
TEST(Masks, SceneFiles) {
  const Scene scene = parse_scene(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
    "spheres": [{"center": [0, 0, 0], "radius": 1, "mask": 4}],
    "planes": [{"point": [0, -1, 0], "normal": [0, 1, 0], "mask": 8}],
    "meshes": [{"positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]], "mask": 3}]})",
                                  "masks.json", "", no_models);
  EXPECT_EQ(scene.meshes[0].mask, 3);
  EXPECT_EQ(scene.spheres[0].mask, 4);
  EXPECT_EQ(scene.planes[0].mask, 8);
  try {
    parse_scene(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
      "spheres": [{"center": [0, 0, 0], "radius": 1, "mask": 256}]})", "masks.json", "", no_models);
    ADD_FAILURE() << "a mask of 256 was taken";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("spheres[0].mask"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace vkray
