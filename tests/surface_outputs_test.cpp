// The surface outputs (barycentric, shading-normal, texcoord: engine/surface_outputs.hpp) against
// closed forms and against the reference's, from the device's ids and from the reference's own.
#include "engine/reference/reference.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/surface_outputs.hpp"
#include "tests/gpu_test_support.hpp"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>

namespace vkray {
namespace {

using namespace test;

constexpr AovSet surface_aovs{Aov::depth,          Aov::normal,   Aov::mesh_id,     Aov::primitive_id, Aov::barycentric,
                              Aov::shading_normal, Aov::texcoord, Aov::front_facing};

glm::dvec3 plane3(const std::vector<float>& planes, size_t pixels, size_t p) {
  return {planes[p], planes[pixels + p], planes[2 * pixels + p]};
}
glm::dvec2 plane2(const std::vector<float>& planes, size_t pixels, size_t p) { return {planes[p], planes[pixels + p]}; }

// The square [-1, 1]^2 in z = 0 as two triangles, from OBJ text with vt = ((x + 1) / 2, (y + 1) / 2)
// and vn = (x / 2, 0, 1) at its corners: both linear in the point, so that their interpolation is
// exact anywhere on the square, vt at (x, y) is ((x + 1) / 2, (y + 1) / 2) and the shading normal
// normalize(x / 2, 0, 1). Counter-clockwise seen from +z.
Scene attributed_square(const glm::dvec3& from) {
  const char* obj =
      "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "vn -0.5 0 1\nvn 0.5 0 1\nvn 0.5 0 1\nvn -0.5 0 1\n"
      "f 1/1/1 2/2/2 3/3/3\nf 1/1/1 3/3/3 4/4/4\n";
  Scene scene;
  scene.meshes.push_back(load_obj_text(obj, "square.obj"));
  scene.camera = {from, {0.1, -0.05, 0}, {0, 1, 0}, 50};
  return sized(scene, 41, 31);
}

// Every hit pixel against the closed form at the point where the pixel's ray in double meets the
// plane z = 0. The outputs are that closed form rounded to float once, the weights from double
// arithmetic a few ulps of double off: within half a float32 ulp of values below 2 and 1e-12.
void expect_square_closed_form(const Scene& scene, const Frame& frame) {
  const CameraBasis basis = make_camera_basis(scene.camera, scene.width, scene.height);
  const size_t pixels = frame.pixel_count();
  const double tolerance = 0x1p-24 * 2.0 + 1e-12;
  const bool from_front = scene.camera.from.z > 0.0;
  size_t hits = 0;
  for (uint32_t j = 0; j < frame.height; ++j) {
    for (uint32_t i = 0; i < frame.width; ++i) {
      const size_t p = size_t{j} * frame.width + i;
      if (!frame.hit(p)) continue;
      ++hits;
      const glm::dvec3 dir = basis.direction(pixel_uv(i, j, frame.width, frame.height));
      const glm::dvec3 point = basis.origin - basis.origin.z / dir.z * dir;
      const glm::dvec2 texcoord = 0.5 * (glm::dvec2(point) + 1.0);
      EXPECT_NEAR(glm::distance(plane2(frame.texcoord, pixels, p), texcoord), 0.0, tolerance) << i << "," << j;
      const glm::dvec3 normal = (from_front ? 1.0 : -1.0) * glm::normalize(glm::dvec3(point.x / 2.0, 0.0, 1.0));
      EXPECT_NEAR(glm::distance(plane3(frame.shading_normal, pixels, p), normal), 0.0, tolerance) << i << "," << j;
      // The weights of the triangle the ids name: (1 2 3) or (1 3 4), vertices a, b, c.
      ASSERT_EQ(frame.mesh_id[p], 0u);
      const glm::dvec2 w = plane2(frame.barycentric, pixels, p);
      const glm::dvec2 a(-1, -1), b = frame.primitive_id[p] == 0 ? glm::dvec2(1, -1) : glm::dvec2(1, 1),
                       c = frame.primitive_id[p] == 0 ? glm::dvec2(1, 1) : glm::dvec2(-1, 1);
      EXPECT_NEAR(glm::distance(a + w.x * (b - a) + w.y * (c - a), glm::dvec2(point)), 0.0, 4.0 * tolerance) << i << "," << j;
      EXPECT_GE(w.x, 0.0);
      EXPECT_GE(w.y, 0.0);
      EXPECT_LE(w.x + w.y, 1.0);
      // Counter-clockwise seen from +z: the front from there, the back from -z.
      EXPECT_EQ(frame.front_facing[p], from_front ? 1u : 0u) << i << "," << j;
    }
  }
  EXPECT_GT(hits, pixels / 4);
}

// Seen from the front and from behind (the shading normal turns to the ray's side, front-facing
// says which side), on the device and in the reference.
TEST(SurfaceOutputs, SquareMatchesTheClosedForm) {
  for (const glm::dvec3 from : {glm::dvec3(0.3, 0.2, 2.5), glm::dvec3(-0.2, 0.1, -2.5)}) {
    SCOPED_TRACE(testing::Message() << "camera at z = " << from.z);
    const Scene scene = attributed_square(from);
    expect_square_closed_form(scene, render(scene, surface_aovs));
    const ReferenceScene reference(scene);
    const auto hits = render_reference_hits(reference, scene.camera,
                                            scene.width, scene.height);
    expect_square_closed_form(scene, reference_frame(reference, scene, hits, scene.camera, scene.width, scene.height, surface_aovs));
  }
}

// Without vn and vt, and on spheres and planes: the shading normal is the geometric normal facing
// the ray (the normal output, which the device computes in float32 from its own data: within a few
// float32 roundings of a unit vector), and the weights and texture coordinates 0 where no triangle
// gives them. The default scene has all three kinds.
TEST(SurfaceOutputs, WithoutAttributesTheGeometricNormal) {
  const Scene scene = sized(default_scene(), 64, 48);
  const Frame frame = render(scene, surface_aovs);
  const size_t pixels = frame.pixel_count();
  size_t hits = 0;
  for (size_t p = 0; p < pixels; ++p) {
    if (!frame.hit(p)) {
      EXPECT_EQ(plane3(frame.shading_normal, pixels, p), glm::dvec3(0.0));
      continue;
    }
    ++hits;
    EXPECT_LT(glm::distance(plane3(frame.shading_normal, pixels, p), plane3(frame.normal, pixels, p)), 1e-5) << p;
    EXPECT_EQ(plane2(frame.texcoord, pixels, p), glm::dvec2(0.0));
    if (frame.mesh_id[p] >= scene.meshes.size()) {
      EXPECT_EQ(plane2(frame.barycentric, pixels, p), glm::dvec2(0.0));
    }
  }
  EXPECT_GT(hits, pixels / 2);
}

// The shared models with vt (spot) and vn (teapot-vn): every new channel is written, and wherever
// the device and the reference name the same triangle the surface outputs are the reference's
// exactly (both evaluate that triangle at the pixel's ray in double); the ids agree on most hits.
TEST(SurfaceOutputs, SharedModelsAgreeWithTheReference) {
  VKRAY_SKIP_WITHOUT_MODELS();
  for (const char* name : {"spot.obj", "teapot-vn.obj"}) {
    SCOPED_TRACE(name);
    const Scene scene = framed_model(name, 96, 72);
    const Frame frame = render(scene, surface_aovs);
    const ReferenceScene reference(scene);
    const auto hits = render_reference_hits(reference, scene.camera,
                                            scene.width, scene.height);
    const Frame expected = reference_frame(reference, scene, hits, scene.camera, scene.width, scene.height, surface_aovs);
    const size_t pixels = frame.pixel_count();
    size_t both_hit = 0, same_triangle = 0, attributed = 0;
    for (size_t p = 0; p < pixels; ++p) {
      if (!frame.hit(p) || !expected.hit(p)) continue;
      ++both_hit;
      if (frame.mesh_id[p] != expected.mesh_id[p] || frame.primitive_id[p] != expected.primitive_id[p]) continue;
      ++same_triangle;
      EXPECT_EQ(plane2(frame.barycentric, pixels, p), plane2(expected.barycentric, pixels, p)) << p;
      EXPECT_EQ(plane3(frame.shading_normal, pixels, p), plane3(expected.shading_normal, pixels, p)) << p;
      EXPECT_EQ(plane2(frame.texcoord, pixels, p), plane2(expected.texcoord, pixels, p)) << p;
      // The file's attributes are there: texture coordinates on spot, normals apart from the faces' on the teapot.
      const bool has_texcoord = plane2(frame.texcoord, pixels, p) != glm::dvec2(0.0);
      const bool smooth = glm::distance(plane3(frame.shading_normal, pixels, p), plane3(frame.normal, pixels, p)) > 1e-3;
      attributed += std::string(name) == "spot.obj" ? has_texcoord : smooth;
    }
    EXPECT_GT(both_hit, pixels / 20);  // the framed view (framed_model) leaves 90% of the image empty
    EXPECT_GT(same_triangle, both_hit * 9 / 10);
    EXPECT_GT(attributed, same_triangle / 2);
  }
}

// front-facing for a sphere seen from outside and from inside, and a plane from each side: the
// outside and the side the normal points to are the front; misses are 0.
TEST(SurfaceOutputs, FrontFacingOfSpheresAndPlanes) {
  struct Case {
    const char* what;
    glm::dvec3 from;
    uint32_t expected;
  };
  for (const Case& sides : {Case{"outside the sphere, above the plane", {0, 0.5, 6}, 1u},
                            Case{"inside the sphere, below the plane", {0, -0.5, 0.2}, 0u}}) {
    SCOPED_TRACE(sides.what);
    Scene scene;
    scene.spheres.push_back({{0, 0, 0}, 2.0});
    scene.planes.push_back({{0, 0, 0}, {0, 1, 0}});  // the plane y = 0, normal up: inside the sphere too
    scene.camera = {sides.from, sides.from + glm::dvec3(0, 0, -1), {0, 1, 0}, 60};
    scene = sized(scene, 24, 18);
    const Frame frame = render(scene, AovSet{Aov::depth, Aov::mesh_id, Aov::front_facing});
    size_t sphere_pixels = 0, plane_pixels = 0;
    for (size_t p = 0; p < frame.pixel_count(); ++p) {
      if (!frame.hit(p)) {
        EXPECT_EQ(frame.front_facing[p], 0u);
        continue;
      }
      const bool plane = frame.mesh_id[p] == 1;  // spheres, then planes
      (plane ? plane_pixels : sphere_pixels) += 1;
      EXPECT_EQ(frame.front_facing[p], sides.expected) << (plane ? "plane" : "sphere") << " pixel " << p;
    }
    EXPECT_GT(sphere_pixels, 0u);
    EXPECT_GT(plane_pixels, 0u);
  }
}

}  // namespace
}  // namespace vkray
