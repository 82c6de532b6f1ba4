// Instances on the device: a mesh stored once and placed by transforms is traced by taking each ray
// into the mesh's coordinates (shaders/primitives.glsl), and every pixel and given ray agrees with
// the fp64 reference within the error envelope, ids included: rotated, sheared, mirrored, masked,
// at extreme scales far from the origin, in every search and shader variant.
#include "engine/reference/reference.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "tests/gpu_test_support.hpp"

#include <glm/matrix.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace vkray {
namespace {

using namespace test;

glm::dmat3 turned_about_y(double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  return glm::dmat3(glm::dvec3(c, 0.0, -s), glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(s, 0.0, c));  // columns
}

// An ordinary mesh, a sphere and a ground plane, with a fine closed mesh (meshes[1]) and a coarse one
// (meshes[2]) placed four times: turned, sheared and unevenly scaled, mirrored by a negative scale,
// and the coarse one masked 2.
Scene instanced_scene(uint32_t image_width = 96, uint32_t image_height = 64) {
  Scene scene;
  scene.width = image_width, scene.height = image_height;
  scene.meshes.push_back(make_sphere_mesh(300, glm::dvec3(-2.5, 0.5, 0.0), 0.7));
  Mesh ball = make_sphere_mesh(1500);
  ball.instanced = true;
  scene.meshes.push_back(ball);
  Mesh facets = make_sphere_mesh(48, glm::dvec3(0.0), 0.6);  // coarse: flat facets, sharp edges
  facets.instanced = true;
  scene.meshes.push_back(facets);
  scene.spheres.push_back({glm::dvec3(2.5, 0.4, -1.0), 0.6});
  scene.planes.push_back({glm::dvec3(0.0, -1.5, 0.0), glm::dvec3(0.0, 1.0, 0.0)});
  glm::dmat3 sheared(1.0);
  sheared[1][0] = 0.4;  // x += 0.4 y
  sheared = sheared * glm::dmat3(glm::dvec3(0.5, 0.0, 0.0), glm::dvec3(0.0, 1.3, 0.0), glm::dvec3(0.0, 0.0, 0.8));
  const glm::dmat3 mirrored(glm::dvec3(-0.6, 0.0, 0.0), glm::dvec3(0.0, 0.6, 0.0), glm::dvec3(0.0, 0.0, 0.6));
  scene.instances = {{1, turned_about_y(0.7), glm::dvec3(0.0)},
                     {1, sheared, glm::dvec3(0.3, 1.4, 1.5)},
                     {1, mirrored, glm::dvec3(1.0, -0.6, 2.2)},
                     {2, turned_about_y(0.3) * 0.8, glm::dvec3(-1.2, -1.0, 1.8), 2}};
  scene.camera = {glm::dvec3(0.5, 2.0, 7.0), glm::dvec3(0.0, 0.0, 0.0), glm::dvec3(0.0, 1.0, 0.0), 55.0};
  check_scene(scene);
  return scene;
}

std::vector<ObjectPrimitive> frame_ids(const Frame& frame) {
  std::vector<ObjectPrimitive> ids(frame.pixel_count());
  for (size_t p = 0; p < ids.size(); ++p) ids[p] = {frame.mesh_id[p], frame.primitive_id[p]};
  return ids;
}

// Renders depth, normal and ids and checks every pixel against the reference of `mask`; returns the
// objects hit.
std::set<uint32_t> expect_render_as_reference(const Scene& scene, const RendererOptions& options, Mask mask = every_mask_bit) {
  Renderer renderer(device(), scene, options);
  renderer.set_ray_mask(mask);
  const Frame frame = renderer.render(scene.camera, scene.width, scene.height,
                                      {Aov::depth, Aov::normal, Aov::mesh_id, Aov::primitive_id});
  const std::vector<ObjectPrimitive> ids = frame_ids(frame);
  const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids, mask);
  EXPECT_EQ(report.failures, 0u) << report.describe();
  std::set<uint32_t> objects;
  for (const ObjectPrimitive& id : ids) objects.insert(id.object);
  return objects;
}

// Every instance in view, through each search and variant: brute force, per ray, in packets and by
// ray queries, generic, float64, geometry in storage buffers, and rays past a small loop budget that the host
// finishes.
TEST(GpuInstances, EveryPixelAsTheReferenceInEveryVariant) {
  const Scene scene = instanced_scene();
  RendererOptions budgeted;
  budgeted.loop_budget = 40;
  std::vector<RendererOptions> variants = searches_with();
  std::vector<RendererOptions> budgeted_walks = searches_with(budgeted, true);  // brute force has no loop budget
  for (RendererOptions& options : budgeted_walks) {  // a ray query's loop counts candidates, a handful a ray
    if (options.scene.search == PrimitiveSearch::ray_query) options.loop_budget = 2;
  }
  variants.insert(variants.end(), budgeted_walks.begin(), budgeted_walks.end());
  variants.resize(variants.size() + 3);
  variants[variants.size() - 3].shader.generic = true;
  variants[variants.size() - 2].shader.precision = Precision::float64;
  variants[variants.size() - 1].shader.storage_geometry = true;
  for (const RendererOptions& options : variants) {
    SCOPED_TRACE(variant_name(options));
    const std::set<uint32_t> hit = expect_render_as_reference(scene, options);
    EXPECT_EQ(hit, (std::set<uint32_t>{0, 1, 2, 3, 4, no_object})) << "every object in view, and sky";
  }
  for (const RendererOptions& options : budgeted_walks) {
    Renderer renderer(device(), scene, options);
    EXPECT_EQ(renderer.scene_stats().search, options.scene.search) << variant_name(options);
    renderer.render(scene.camera, scene.width, scene.height, {Aov::depth});
    EXPECT_GT(renderer.timings().unfinished_rays, 0u) << variant_name(options) << ": the loop budget must leave rays to the host";
  }
}

// Masks: the coarse mesh's instance has mask 2; a ray mask without it sees through to what lies behind.
TEST(GpuInstances, InstanceMasks) {
  const Scene scene = instanced_scene();
  for (const RendererOptions& options : searches_with()) {
    SCOPED_TRACE(variant_name(options));
    EXPECT_TRUE(expect_render_as_reference(scene, options, 0xfd).count(2) == 0) << "the masked instance was hit";
    EXPECT_TRUE(expect_render_as_reference(scene, options, 2).count(2) == 1) << "the instance its mask lets through";
  }
}

// An instance 1e-6 across and one 1e6 across, each placed 1e5 from the origin and mirrored, seen
// from a camera a few of its sizes away: the ray is taken into its mesh's coordinates from the
// difference of origin and translation, so each keeps the precision of its own size.
TEST(GpuInstances, ExtremeScalesFarFromTheOrigin) {
  for (const double scale : {1e-6, 1e6}) {
    SCOPED_TRACE(testing::Message() << "scale " << scale);
    Scene scene;
    scene.width = 64, scene.height = 48;
    Mesh ball = make_sphere_mesh(1500);
    ball.instanced = true;
    scene.meshes.push_back(ball);
    const glm::dvec3 at(1e5, -0.5e5, 0.7e5);
    const glm::dmat3 mirrored_turned = turned_about_y(0.4) * glm::dmat3(glm::dvec3(-scale, 0.0, 0.0),
                                                                         glm::dvec3(0.0, scale, 0.0),
                                                                         glm::dvec3(0.0, 0.0, 1.5 * scale));
    scene.instances = {{0, mirrored_turned, at}, {0, glm::dmat3(0.5 * scale), at + glm::dvec3(1.6 * scale, 0.3 * scale, 0.0)}};
    scene.camera = {at + glm::dvec3(0.8, 1.2, 4.0) * scale, at + glm::dvec3(0.5 * scale, 0.0, 0.0), glm::dvec3(0.0, 1.0, 0.0), 50.0};
    check_scene(scene);
    RendererOptions float64;
    float64.shader.precision = Precision::float64;
    std::vector<RendererOptions> variants = searches_with();
    variants.push_back(float64);
    for (const RendererOptions& options : variants) {
      SCOPED_TRACE(variant_name(options));
      const std::set<uint32_t> hit = expect_render_as_reference(scene, options);
      EXPECT_EQ(hit, (std::set<uint32_t>{0, no_object}));
    }
  }
}

// Given rays, each from its own origin and all from one, occlusion queries and counts of crossings:
// ray by ray as the reference has them, in every search.
TEST(GpuInstances, GivenRaysOcclusionAndCrossings) {
  const Scene scene = instanced_scene(48, 32);
  const std::vector<GivenRay> rays = pixel_rays(scene);
  std::vector<GivenRay> scattered = rays;  // a copy, each ray moved along itself
  for (size_t k = 0; k < scattered.size(); ++k) {  // each from a point of its own along its pixel ray
    for (int c = 0; c < 3; ++c) scattered[k][c] += 0.5 * double(k % 5) * scattered[k][3 + c];
  }
  for (const RendererOptions& options : searches_with()) {
    SCOPED_TRACE(variant_name(options));
    Renderer renderer(device(), scene, options);
    const ReferenceScene reference(scene);
    const std::vector<GivenRay>& moved = scattered;
    for (const std::vector<GivenRay>* given : {&rays, &moved}) {
      const RayHits hits = renderer.cast_rays(*given);
      const std::vector<uint8_t> blocked = renderer.occluded(*given);
      const std::vector<uint32_t> crossings = renderer.count_intersections(*given);
      if (given == &rays) {  // the pixel rays: as the camera's, within the envelope
        Frame frame(scene.width, scene.height, {Aov::depth, Aov::normal});
        frame.depth.assign(hits.t.begin(), hits.t.end());
        frame.normal.assign(hits.normal.begin(), hits.normal.end());
        std::vector<ObjectPrimitive> ids(hits.count);
        for (size_t k = 0; k < hits.count; ++k) ids[k] = {hits.object[k], hits.primitive[k]};
        const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids);
        EXPECT_EQ(report.failures, 0u) << report.describe();
      }
      size_t occlusion_differs = 0, crossings_differ = 0, instances_hit = 0, instance_differs = 0;
      ASSERT_EQ(hits.instance.size(), given->size()) << "a scene with instances names the instance each ray hit";
      for (size_t k = 0; k < given->size(); ++k) {
        const GivenRay& ray = (*given)[k];
        const ReferenceHit expected = trace_reference_ray(reference, ray, 0.0, no_hit);
        const ObjectPrimitive expected_source = reference.source(expected);
        if (hits.object[k] == expected_source.object && hits.primitive[k] == expected_source.primitive &&
            hits.instance[k] != expected.instance) {
          ++instance_differs;
        }
        if (bool(blocked[k]) != std::isfinite(hits.t[k])) ++occlusion_differs;
        if (crossings[k] != count_reference_crossings(reference, ray, 0.0, no_hit)) ++crossings_differ;
        if (hits.object[k] == 1 || hits.object[k] == 2) ++instances_hit;
      }
      EXPECT_EQ(occlusion_differs, 0u);
      EXPECT_EQ(crossings_differ, 0u);
      EXPECT_EQ(instance_differs, 0u) << "the same triangle, another instance";
      EXPECT_GT(instances_hit, given->size() / 20) << "the rays must meet the instances";
    }
  }
}

// The instance-id output, and the surface outputs through the instance's transform: where a pixel
// names the reference's triangle, it names the reference's instance and faces as it does; a
// mirrored instance turns its winding over (its outside is its back, as the scene flattened would
// have it), and the shading normal lies on the ray's side.
TEST(GpuInstances, InstanceIdsAndFrontFacingThroughTheTransform) {
  const Scene scene = instanced_scene();
  const AovSet aovs{Aov::depth, Aov::mesh_id, Aov::primitive_id, Aov::instance_id, Aov::front_facing, Aov::shading_normal};
  Renderer renderer(device(), scene);
  const Frame frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
  const ReferenceScene reference(scene);
  const Frame expected = reference_frame(reference, scene, render_reference_hits(reference, scene.camera, scene.width, scene.height),
                                         scene.camera, scene.width, scene.height, aovs);
  size_t compared = 0, instance_differs = 0, facing_differs = 0, on_wrong_side = 0;
  std::set<std::pair<uint32_t, uint32_t>> instance_fronts;  // (instance, front-facing) seen
  const CameraBasis basis = make_camera_basis(scene.camera, scene.width, scene.height);
  for (size_t p = 0; p < frame.pixel_count(); ++p) {
    if (frame.mesh_id[p] == no_object) continue;
    const bool placed_mesh = frame.mesh_id[p] == 1 || frame.mesh_id[p] == 2;
    EXPECT_EQ(frame.instance_id[p] != no_object, placed_mesh) << "pixel " << p;
    if (frame.mesh_id[p] != expected.mesh_id[p] || frame.primitive_id[p] != expected.primitive_id[p]) continue;
    ++compared;
    instance_differs += frame.instance_id[p] != expected.instance_id[p];
    facing_differs += frame.front_facing[p] != expected.front_facing[p];
    const uint32_t i = uint32_t(p % scene.width), j = uint32_t(p / scene.width);
    const glm::dvec3 dir = basis.direction(pixel_uv(i, j, scene.width, scene.height));
    const glm::dvec3 shading(frame.shading_normal[p], frame.shading_normal[frame.pixel_count() + p],
                             frame.shading_normal[2 * frame.pixel_count() + p]);
    on_wrong_side += glm::dot(shading, dir) > 0.0;
    if (placed_mesh) instance_fronts.insert({frame.instance_id[p], frame.front_facing[p]});
  }
  EXPECT_GT(compared, frame.pixel_count() / 4);
  EXPECT_EQ(instance_differs, 0u);
  EXPECT_EQ(facing_differs, 0u);
  EXPECT_EQ(on_wrong_side, 0u) << "shading normals facing away from the ray";
  // Seen from outside: the turned and sheared balls' fronts, the mirrored one's back.
  EXPECT_TRUE(instance_fronts.count({0, 1}) && !instance_fronts.count({0, 0}));
  EXPECT_TRUE(instance_fronts.count({2, 0}) && !instance_fronts.count({2, 1}));
}

// set_transforms, in each search: every instance moved at once, twice (the second time far from where
// the scene was built, one instance mirrored now), renders as the reference of the moved scene; a
// refused call (an instance out of range, a map not affine or not invertible) changes nothing.
TEST(GpuInstances, SetTransformsMovesThemWithoutARebuild) {
  for (const RendererOptions& options : searches_with()) {
    SCOPED_TRACE(variant_name(options));
    Scene scene = instanced_scene();
    Renderer renderer(device(), scene, options);
    const std::vector<uint32_t> all{0, 1, 2, 3};
    for (const double shift : {0.4, 3.0}) {
      SCOPED_TRACE(testing::Message() << "shift " << shift);
      std::vector<glm::dmat4> transforms;
      for (const uint32_t k : all) {
        glm::dmat4 m(turned_about_y(0.5 * k + shift) * (k == 1 ? -0.7 : 0.7));
        m[3] = glm::dvec4(-1.5 + 1.1 * k, 0.2 * k - 0.4, shift - 2.0, 1.0);
        transforms.push_back(m);
        place_by(scene.instances[k], m);
      }
      // Rays cast in place before the move make the table that turns slots into ids on the device:
      // set_transforms keeps it right (or leaves it, where the world's slots did not move).
      const std::vector<GivenRay> rays = pixel_rays(scene);
      std::vector<float> t(rays.size()), normal(3 * rays.size());
      std::vector<uint32_t> object(rays.size()), primitive(rays.size());
      const HitArrays arrays{t.data(), normal.data(), object.data(), primitive.data()};
      const bool in_place = renderer.cast_rays_in_place(rays, arrays);
      renderer.set_transforms(all, transforms);
      EXPECT_GT(renderer.timings().scene_update_ms, 0.0);
      if (in_place) {
        ASSERT_TRUE(renderer.cast_rays_in_place(rays, arrays));
        const RayHits hits = renderer.cast_rays(rays);
        size_t ids_differ = 0;
        for (size_t k = 0; k < rays.size(); ++k) ids_differ += object[k] != hits.object[k] || primitive[k] != hits.primitive[k];
        EXPECT_EQ(ids_differ, 0u) << "ids cast in place after set_transforms";
      }
      const Frame frame = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal, Aov::mesh_id, Aov::primitive_id});
      const std::vector<ObjectPrimitive> ids = frame_ids(frame);
      const EnvelopeReport report = check_against_reference(scene, frame, 1, &ids);
      EXPECT_EQ(report.failures, 0u) << report.describe();
      std::set<uint32_t> objects(frame.mesh_id.begin(), frame.mesh_id.end());
      EXPECT_TRUE(objects.count(1) && objects.count(2)) << "the moved instances in view";
    }
    const std::vector<Instance> before = renderer.scene().instances;
    glm::dmat4 not_affine(1.0);
    not_affine[0][3] = 0.5;
    EXPECT_THROW(renderer.set_transforms(std::vector<uint32_t>{0}, std::vector<glm::dmat4>{not_affine}), InputError);
    EXPECT_THROW(renderer.set_transforms(std::vector<uint32_t>{0, 9}, std::vector<glm::dmat4>(2, glm::dmat4(1.0))), InputError);
    glm::dmat4 flattening(0.0);
    flattening[3][3] = 1.0;
    EXPECT_THROW(renderer.set_transforms(std::vector<uint32_t>{2}, std::vector<glm::dmat4>{flattening}), InputError);
    EXPECT_THROW(renderer.set_transforms(std::vector<uint32_t>{2}, std::vector<glm::dmat4>{}), InputError);
    for (size_t k = 0; k < before.size(); ++k) {
      EXPECT_EQ(renderer.scene().instances[k].translation, before[k].translation) << "a refused call moved instance " << k;
    }
  }
}

// The first four hits of rays through each instance, aimed a little off its centre from around it,
// and of what lies beyond: the reference's objects, triangles and instances in the same order, each
// distance and normal within the bounds of FirstHits.InOrderAsTheReference (a head-on hit's distance
// within 8 eps (t + 16), a normal within 32 eps) grown by the placing instance's kappa, the factor
// its transform puts on float32's errors (placement_condition), and twice for hits up to 60 degrees
// from head-on through the sheared instance; in every search.
TEST(GpuInstances, FirstHitsInOrderAsTheReference) {
  constexpr double eps = 0x1p-24;
  constexpr uint32_t count = 4;
  const Scene scene = instanced_scene(16, 16);
  std::vector<GivenRay> rays;
  for (const Instance& instance : scene.instances) {
    for (int k = 0; k < 24; ++k) {
      // Off every axis and plane of the mesh (a ray in its equator's plane would meet edges there,
      // which one triangle or the other claims by the rounding of the ray's frame).
      const double around = 0.2618 * k + 0.05 * instance.mesh + 0.0123, up = 0.3 * std::sin(1.7 * k) + 0.0271;
      const glm::dvec3 away(std::cos(around) * std::cos(up), std::sin(up), std::sin(around) * std::cos(up));
      const glm::dvec3 from = instance.translation + 6.0 * away;
      const glm::dvec3 aim = instance.translation + 0.0137 * glm::dvec3(1 + k % 5, 1 + k % 3, 1 + k % 7);
      const glm::dvec3 dir = glm::normalize(aim - from);
      rays.push_back({from.x, from.y, from.z, dir.x, dir.y, dir.z});
    }
  }
  for (const RendererOptions& options : searches_with()) {
    SCOPED_TRACE(variant_name(options));
    Renderer renderer(device(), scene, options);
    const ReferenceScene reference(scene);
    const RayHits hits = renderer.cast_rays(rays, {}, count);
    ASSERT_EQ(hits.count, rays.size() * count);
    ASSERT_EQ(hits.instance.size(), hits.count) << "a scene with instances names the instance of each hit";
    size_t wrong_ids = 0, wrong_t = 0, wrong_normals = 0, instance_hits = 0;
    std::string first;
    for (size_t k = 0; k < rays.size(); ++k) {
      const std::vector<ReferenceHit> expected = first_reference_hits(reference, rays[k], 0.0, no_hit, count);
      for (uint32_t layer = 0; layer < count; ++layer) {
        const size_t at = k * count + layer;
        const ReferenceHit& want = expected[layer];
        const ObjectPrimitive source = reference.source(want);
        const bool ids_differ = hits.object[at] != source.object || hits.primitive[at] != source.primitive ||
                                hits.instance[at] != (want.kind == PrimitiveKind::none ? no_object : want.instance);
        const double kappa = placement_condition(scene, want);
        const double t = hits.t[at];
        const bool t_differs =
            want.kind == PrimitiveKind::none ? !std::isinf(t) : !(std::abs(t - want.t) <= 2 * kappa * 8 * eps * (want.t + 16.0));
        const glm::dvec3 normal(hits.normal[at], hits.normal[hits.count + at], hits.normal[2 * hits.count + at]);
        const bool normal_differs =
            want.kind == PrimitiveKind::none ? normal != glm::dvec3(0.0) : !(angle_between(normal, want.normal) <= 2 * kappa * 32 * eps);
        wrong_ids += ids_differ, wrong_t += t_differs, wrong_normals += normal_differs;
        instance_hits += hits.instance[at] != no_object;
        if ((ids_differ || t_differs || normal_differs) && first.empty()) {
          first = "ray " + std::to_string(k) + " hit " + std::to_string(layer) + ": t " + std::to_string(t) + " (reference " +
                  std::to_string(want.t) + "), object " + std::to_string(hits.object[at]) + " (" + std::to_string(source.object) +
                  "), instance " + std::to_string(hits.instance[at]) + " (" + std::to_string(want.instance) + ")";
        }
      }
    }
    EXPECT_EQ(wrong_ids + wrong_t + wrong_normals, 0u)
        << wrong_ids << " ids, " << wrong_t << " distances, " << wrong_normals << " normals; first: " << first;
    EXPECT_GE(instance_hits, 2 * rays.size()) << "each ray goes in and out of the instance it aims at";
  }
}

// Brute force walks every placed triangle in its loops: where a device stops loops (llvmpipe,
// GpuDeviceInfo::max_loop_iterations), a scene whose instances need more is refused before anything is
// drawn, naming the count, rather than drawn with instances left out.
TEST(GpuInstances, BruteForceBeyondTheDevicesLoopsRefuses) {
  const uint64_t limit = device().info().max_loop_iterations;
  if (limit == 0) GTEST_SKIP() << device().info().name << " does not stop loops";
  Scene scene = instanced_scene(16, 16);
  const Instance placing = scene.instances[0];  // of the 1500-triangle mesh: 188 batches
  scene.instances.assign(limit / 188 + 1, placing);
  RendererOptions options;
  options.scene.search = PrimitiveSearch::brute_force;
  try {
    Renderer renderer(device(), scene, options);
    ADD_FAILURE() << "a scene beyond the device's loops was accepted";
  } catch (const GpuError& error) {
    EXPECT_NE(std::string(error.what()).find("shader loop iterations per pixel"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace vkray
