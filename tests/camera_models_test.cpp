// Cameras as vision code gives them: OpenCV's intrinsics in pixels and its world-to-camera matrix,
// orthographic and equirectangular ones (engine/scene/camera.hpp), on the device and in the
// reference; and one renderer serving cameras near and far with different outputs.
#include "engine/reference/reference.hpp"
#include "engine/scene/scene_loader.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <numbers>

namespace vkray {
namespace {

using namespace test;

// A camera given by fovy, and the same camera as its OpenCV intrinsics and [R t] (what the EXR
// header and a many-view manifest print for it), render the same pixels: every depth, normal and
// id bit for bit. The matrix gives from, to and up back within a few roundings of double, and the
// centred intrinsics the same image plane up to the rounding of its distance: none of which
// survives the float32 rounding of the basis the device takes.
TEST(CameraModels, IntrinsicsAndMatrixRenderTheLookAtCamerasPixels) {
  const Scene scene = sized(default_scene(), 64, 48);
  const Box box{{-3, -1, -3}, {3, 2, 3}};
  for (const Camera& look_at : cameras_around(box, 2026, 3)) {
    SCOPED_TRACE(testing::Message() << "fovy " << look_at.fovy_degrees);
    Camera given = look_at;
    given.intrinsics = pinhole_intrinsics(look_at, scene.width, scene.height);
    std::string fault;
    given = with_world_to_camera(given, world_to_camera(look_at, scene.width, scene.height), fault);
    ASSERT_EQ(fault, "");
    Renderer renderer(device(), scene);
    const AovSet aovs{Aov::depth, Aov::normal, Aov::mesh_id, Aov::primitive_id};
    const Frame a = renderer.render(look_at, scene.width, scene.height, aovs);
    const Frame b = renderer.render(given, scene.width, scene.height, aovs);
    EXPECT_EQ(std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(a.normal.data(), b.normal.data(), a.normal.size() * sizeof(float)), 0);
    EXPECT_EQ(a.mesh_id, b.mesh_id);
    EXPECT_EQ(a.primitive_id, b.primitive_id);
  }
}

// Focal lengths that differ and a principal point off the centre: the device's image is within the
// reference envelope, and every hit point the reference finds projects through the intrinsics
// and [R t] onto its own pixel's centre (u, v) = (i, j), within double's rounding of the hit.
TEST(CameraModels, OffCentreIntrinsicsProjectEachHitOntoItsPixel) {
  Scene scene = sized(default_scene(), 80, 50);
  scene.camera.intrinsics = PinholeIntrinsics{70.0, 55.0, 30.25, 31.5};
  expect_frame_matches_reference(scene, render(scene));

  const ReferenceScene reference(scene);
  const auto hits = render_reference_hits(reference, scene.camera,
                                          scene.width, scene.height);
  const Matrix4 rigid = world_to_camera(scene.camera, scene.width, scene.height);
  const PinholeIntrinsics& k = *scene.camera.intrinsics;
  const CameraBasis basis = make_camera_basis(scene.camera, scene.width, scene.height);
  size_t hit_count = 0;
  for (uint32_t j = 0; j < scene.height; ++j) {
    for (uint32_t i = 0; i < scene.width; ++i) {
      const ReferenceHit& hit = hits[size_t{j} * scene.width + i];
      if (hit.kind == PrimitiveKind::none) continue;
      ++hit_count;
      const glm::dvec3 p = basis.origin + hit.t * basis.direction(pixel_uv(i, j, scene.width, scene.height));
      glm::dvec3 c;
      for (int r = 0; r < 3; ++r) c[r] = rigid[r][0] * p.x + rigid[r][1] * p.y + rigid[r][2] * p.z + rigid[r][3];
      EXPECT_NEAR(k.fx * c.x / c.z + k.cx, i, 1e-9) << i << "," << j;
      EXPECT_NEAR(k.fy * c.y / c.z + k.cy, j, 1e-9) << i << "," << j;
    }
  }
  EXPECT_GT(hit_count, size_t{scene.width} * scene.height / 2);
}

// Orthographic and equirectangular images of the default scene (spheres, planes and meshes), its
// camera's placement kept: within the reference envelope, on the device as the reference traces
// each pixel's ray (pixel_ray).
TEST(CameraModels, OrthographicAndEquirectangularWithinTheEnvelope) {
  Scene scene = sized(default_scene(), 96, 48);
  scene.camera.projection = Projection::equirectangular;
  scene.camera.from = {0.3, 1.0, 1.5};  // among the objects: they surround it
  expect_frame_matches_reference(scene, render(scene));
  scene = sized(default_scene(), 64, 48);
  scene.camera.projection = Projection::orthographic;
  scene.camera.view_height = 3.0;
  expect_frame_matches_reference(scene, render(scene));
}

// Closed forms. Equirectangular from the centre of a sphere of radius 2: every pixel at depth 2,
// its normal against its ray, and the ray of pixel (i, j) at longitude 2 pi ((i + 1/2) / W - 1/2)
// east of the view direction and latitude pi (1/2 - (j + 1/2) / H): its position on the sphere
// says so. Orthographic facing a plane 5 away: every ray meets it at depth 5, from its pixel of
// the image plane, so that position minus the view direction's 5 spans view_height over the
// image's height. Depth and position within a few float32 roundings of 5 (1e-6); the direction's
// within the float32 rounding of its components (4e-7).
TEST(CameraModels, OrthographicAndEquirectangularClosedForms) {
  Scene inside;
  inside.spheres.push_back({{1, 2, 3}, 2});
  inside.camera = {{1, 2, 3}, {1, 2, 2}, {0, 1, 0}, 60};
  inside.camera.projection = Projection::equirectangular;
  inside = sized(inside, 32, 16);
  const Frame sphere = render(inside, {Aov::depth, Aov::normal, Aov::position});
  const size_t pixels = sphere.pixel_count();
  for (uint32_t j = 0; j < 16; ++j) {
    for (uint32_t i = 0; i < 32; ++i) {
      const size_t p = size_t{j} * 32 + i;
      EXPECT_NEAR(sphere.depth[p], 2.0, 1e-6);
      const double longitude = 2 * std::numbers::pi * ((i + 0.5) / 32 - 0.5), latitude = std::numbers::pi * (0.5 - (j + 0.5) / 16);
      // View direction -z, right +x, up +y.
      const glm::dvec3 dir(std::cos(latitude) * std::sin(longitude), std::sin(latitude), -std::cos(latitude) * std::cos(longitude));
      const glm::dvec3 position(sphere.position[p], sphere.position[pixels + p], sphere.position[2 * pixels + p]);
      EXPECT_LT(glm::distance(position, glm::dvec3(1, 2, 3) + 2.0 * dir), 4e-6) << i << "," << j;
      const glm::dvec3 normal(sphere.normal[p], sphere.normal[pixels + p], sphere.normal[2 * pixels + p]);
      EXPECT_LT(glm::distance(normal, -dir), 1e-6) << i << "," << j;
    }
  }

  Scene wall;
  wall.planes.push_back({{0, 0, -5}, {0, 0, 1}});
  wall.camera = {{0.5, 0.25, 0}, {0.5, 0.25, -1}, {0, 1, 0}, 60};
  wall.camera.projection = Projection::orthographic;
  wall.camera.view_height = 4.0;
  wall = sized(wall, 40, 20);
  const Frame plane = render(wall, {Aov::depth, Aov::planar_depth, Aov::position});
  const size_t wall_pixels = plane.pixel_count();
  for (uint32_t j = 0; j < 20; ++j) {
    for (uint32_t i = 0; i < 40; ++i) {
      const size_t p = size_t{j} * 40 + i;
      EXPECT_NEAR(plane.depth[p], 5.0, 1e-6);
      EXPECT_NEAR(plane.planar_depth[p], 5.0, 1e-6);
      // 4 world units over 20 rows: 0.2 a pixel, centred on the camera.
      EXPECT_NEAR(plane.position[p], 0.5 + 0.2 * (i + 0.5 - 20), 1e-6) << i << "," << j;
      EXPECT_NEAR(plane.position[wall_pixels + p], 0.25 + 0.2 * (9.5 - j), 1e-6) << i << "," << j;
      EXPECT_NEAR(plane.position[2 * wall_pixels + p], -5.0, 1e-6);
    }
  }
}

TEST(CameraModels, MatricesThatAreNoRigidMotionAreRefused) {
  std::string fault;
  const Camera camera;
  with_world_to_camera(camera, {{{2, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}, fault);
  EXPECT_NE(fault.find("must be a rotation"), std::string::npos) << fault;
  with_world_to_camera(camera, {{{-1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}, fault);
  EXPECT_NE(fault.find("mirrors"), std::string::npos) << fault;
  with_world_to_camera(camera, {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 1, 1}}}, fault);
  EXPECT_EQ(fault, "the last row must be 0, 0, 0, 1");
  // OpenCV's camera at (0, 1, 5) looking down -z, y down: R = diag(1, -1, -1), t = -R (0, 1, 5).
  const Camera placed = with_world_to_camera(camera, {{{1, 0, 0, 0}, {0, -1, 0, 1}, {0, 0, -1, 5}, {0, 0, 0, 1}}}, fault);
  EXPECT_EQ(fault, "");
  EXPECT_EQ(placed.from, glm::dvec3(0, 1, 5));
  EXPECT_EQ(placed.to, glm::dvec3(0, 1, 4));
  EXPECT_EQ(placed.up, glm::dvec3(0, 1, 0));
}

// A renderer keeps one pipeline per set of device outputs, lo parts (a camera near the scene) and
// mode: renders that differ in only one of them must not share one. Near (lo parts) with depth
// alone, then far with the ids (what each ray hit): the ids are a fresh renderer's.
TEST(CameraModels, PipelinesApartForEveryOutputSetAndCameraDistance) {
  const Scene scene = sized(default_scene(), 48, 36);
  Camera near = scene.camera;
  near.from = near.to + 0.2 * (near.from - near.to);  // among the objects, inside two radii: lo parts
  Camera far = scene.camera;
  far.from = far.to + 50.0 * (far.from - far.to);  // far outside them
  const AovSet with_ids{Aov::depth, Aov::mesh_id, Aov::primitive_id};
  Renderer shared(device(), scene);
  shared.render(near, scene.width, scene.height, {Aov::depth});
  const Frame after = shared.render(far, scene.width, scene.height, with_ids);
  Renderer fresh(device(), scene);
  const Frame alone = fresh.render(far, scene.width, scene.height, with_ids);
  EXPECT_EQ(after.mesh_id, alone.mesh_id);
  EXPECT_EQ(after.primitive_id, alone.primitive_id);
  size_t hits = 0;
  for (const uint32_t id : alone.mesh_id) hits += id != no_object;
  EXPECT_GT(hits, 0u);
}

}  // namespace
}  // namespace vkray
