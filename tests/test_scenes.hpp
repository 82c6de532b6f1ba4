// Scenes and cameras shared by the tests: sizes, a grid of quads, the shared models framed or seen
// from random cameras. Host only (no Vulkan).
#pragma once

#include "engine/scene/bvh.hpp"
#include "engine/scene/camera.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/scene.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

namespace vkray::test {

inline const std::filesystem::path models_dir = VKRAY_MODELS_DIR;

#define VKRAY_SKIP_WITHOUT_MODELS()                                                                            \
  if (!std::filesystem::is_directory(::vkray::test::models_dir)) {                                             \
    GTEST_SKIP() << "shared models folder " << ::vkray::test::models_dir                                        \
                 << " is absent (set VKRAY_MODELS_DIR to use it)";                                              \
  }

inline Scene sized(Scene scene, uint32_t width, uint32_t height) {
  scene.width = width;
  scene.height = height;
  return scene;
}

// The scene moved by `offset`, camera included.
inline Scene translated(Scene scene, const glm::dvec3& offset) {
  scene.camera.from += offset;
  scene.camera.to += offset;
  for (auto& sphere : scene.spheres) sphere.center += offset;
  for (auto& plane : scene.planes) plane.point += offset;
  for (auto& mesh : scene.meshes) {
    if (mesh.instanced) continue;  // placed by its instances, moved below
    for (auto& p : mesh.positions) p += offset;
  }
  for (auto& instance : scene.instances) instance.translation += offset;
  return scene;
}

// The scene camera's pixel rays, row by row (an image's rows: the packet walk takes them in place).
inline std::vector<GivenRay> pixel_rays(const Scene& scene) {
  const CameraBasis basis = make_camera_basis(scene.camera, scene.width, scene.height);
  std::vector<GivenRay> rays;
  for (uint32_t j = 0; j < scene.height; ++j) {
    for (uint32_t i = 0; i < scene.width; ++i) {
      const glm::dvec3 d = basis.direction(pixel_uv(i, j, scene.width, scene.height));
      rays.push_back({basis.origin.x, basis.origin.y, basis.origin.z, d.x, d.y, d.z});
    }
  }
  return rays;
}

// A spinning sensor at `scene`'s camera: 16 rings of 1024 azimuths all the way round, 0.03 radians
// of elevation apart about the view direction, listed ring by ring.
inline std::vector<GivenRay> sensor_rings(const Scene& scene) {
  const CameraBasis basis = make_camera_basis(scene.camera, 1, 1);
  std::vector<GivenRay> rays;
  for (int ring = 0; ring < 16; ++ring) {
    const double elevation = (ring - 7.5) * 0.03;
    for (int a = 0; a < 1024; ++a) {
      const double azimuth = 2.0 * M_PI * a / 1024.0;
      const glm::dvec3 d = std::cos(elevation) * (std::cos(azimuth) * -basis.forward + std::sin(azimuth) * basis.right) +
                           std::sin(elevation) * basis.up;
      rays.push_back({basis.origin.x, basis.origin.y, basis.origin.z, d.x, d.y, d.z});
    }
  }
  return rays;
}

inline Mesh quad_grid(glm::dvec3 corner, glm::dvec3 edge_u, glm::dvec3 edge_v, int cells) {
  Mesh mesh;
  for (int j = 0; j <= cells; ++j) {
    for (int i = 0; i <= cells; ++i) mesh.positions.push_back(corner + (double(i) / cells) * edge_u + (double(j) / cells) * edge_v);
  }
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      const uint32_t a = uint32_t(j * (cells + 1) + i), b = a + 1, c = a + uint32_t(cells) + 1, d = c + 1;
      mesh.triangles.push_back({a, b, d});
      mesh.triangles.push_back({a, d, c});
    }
  }
  return mesh;
}

inline Box mesh_bounds(const Mesh& mesh) {
  Box box{glm::dvec3(std::numeric_limits<double>::infinity()), glm::dvec3(-std::numeric_limits<double>::infinity())};
  for (const auto& p : mesh.positions) box.lower = glm::min(box.lower, p), box.upper = glm::max(box.upper, p);
  return box;
}

// A mesh from ../shared/models seen from above the front, filling most of the image.
inline Scene framed_model(const char* name, uint32_t width, uint32_t height) {
  Scene scene;
  scene.meshes.push_back(load_obj_file(models_dir / name));
  const Box box = mesh_bounds(scene.meshes[0]);
  const glm::dvec3 centre = 0.5 * (box.lower + box.upper);
  const double radius = 0.5 * glm::length(box.upper - box.lower);
  scene.camera = {centre + radius * glm::dvec3(0.9, 1.1, 2.6), centre, {0, 1, 0}, 45};
  return sized(scene, width, height);
}

// `count` cameras from a fixed seed, each outside the bounding sphere of `box` (1.3 to 2.5 of its
// radius from the centre, in a random direction), looking at a point near the centre with a
// random up vector and a view angle of 25 to 55 degrees, so the box fills much of the image. Then
// one camera on the +z axis looking down -z with up +y: with an odd image size its middle row and
// column have exactly zero direction components (the slab tests' 0 * inf case).
inline std::vector<Camera> cameras_around(const Box& box, uint64_t seed, int count) {
  PortableRandom random(seed);
  const glm::dvec3 centre = 0.5 * (box.lower + box.upper);
  const double radius = std::max(0.5 * glm::length(box.upper - box.lower), 1e-300);
  std::vector<Camera> cameras;
  for (int k = 0; k < count; ++k) {
    Camera camera;
    camera.from = centre + random.uniform(1.3, 2.5) * radius * random.unit_vector();
    camera.to = centre + 0.2 * radius * random.unit_vector();
    camera.up = random.unit_vector();
    camera.fovy_degrees = random.uniform(25.0, 55.0);
    cameras.push_back(camera);
  }
  cameras.push_back({centre + glm::dvec3(0, 0, 2.5 * radius), centre, {0, 1, 0}, 45});
  return cameras;
}

// `count` cameras from a fixed seed, each looking at the centre of a random triangle of `mesh` from
// `distance` away in a random direction, with a 30 degree view: close-ups of soups whose triangles
// fill only parts of their bounding box (clusters).
inline std::vector<Camera> cameras_at_triangles(const Mesh& mesh, uint64_t seed, int count, double distance) {
  PortableRandom random(seed);
  std::vector<Camera> cameras;
  for (int k = 0; k < count; ++k) {
    const auto& t = mesh.triangles[random.below(mesh.triangles.size())];
    const glm::dvec3 centre = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    cameras.push_back({centre + distance * random.unit_vector(), centre, random.unit_vector(), 30});
  }
  return cameras;
}

// Soup options with the default box and triangle size.
inline SoupOptions soup(size_t triangles, uint64_t seed) {
  SoupOptions options;
  options.triangles = triangles;
  options.seed = seed;
  return options;
}

inline Scene mesh_scene(Mesh mesh) {
  Scene scene;
  scene.meshes.push_back(std::move(mesh));
  return scene;
}

// The closed cube [-1, 1]^3 as 12 triangles (6 quads).
inline Scene cube_scene() {
  return mesh_scene(load_obj_text("v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
                                  "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n",
                                  "cube.obj"));
}

// `count` points uniform in `box` grown by `margin` on every side.
inline std::vector<glm::dvec3> points_in(const Box& box, double margin, int count, uint32_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<glm::dvec3> points;
  for (int k = 0; k < count; ++k) {
    const glm::dvec3 t(unit(random), unit(random), unit(random));
    points.push_back(box.lower - margin + t * (box.upper - box.lower + 2.0 * margin));
  }
  return points;
}

// An ordinary closed mesh, an open grid, a sphere, a plane and the closed mesh placed four ways:
// turned, sheared and unevenly scaled, mirrored, and at a thousandth of its size.
inline Scene placed_shapes_scene() {
  Scene scene;
  scene.meshes.push_back(make_sphere_mesh(300, glm::dvec3(-2.5, 0.5, 0.0), 0.7));
  Mesh placed = make_sphere_mesh(500);
  placed.instanced = true;
  scene.meshes.push_back(placed);
  scene.meshes.push_back(quad_grid({-3, -1, -3}, {6, 0, 0}, {0, 0.3, 6}, 6));
  scene.spheres.push_back({glm::dvec3(2.5, 0.4, -1.0), 0.6});
  scene.planes.push_back({glm::dvec3(0.0, -1.5, 0.0), glm::dvec3(0.0, 1.0, 0.0)});
  const double c = std::cos(0.7), s = std::sin(0.7);
  const glm::dmat3 turned(glm::dvec3(c, 0.0, -s), glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(s, 0.0, c));
  const glm::dmat3 sheared(glm::dvec3(0.5, 0.0, 0.0), glm::dvec3(0.4 * 1.3, 1.3, 0.0), glm::dvec3(0.0, 0.0, 0.8));
  const glm::dmat3 mirrored(glm::dvec3(-0.6, 0.0, 0.0), glm::dvec3(0.0, 0.6, 0.0), glm::dvec3(0.0, 0.0, 0.6));
  scene.instances = {Instance{1, turned, {0.0, 0.0, 0.0}}, Instance{1, sheared, {0.3, 1.4, 1.5}},
                     Instance{1, mirrored, {1.0, -0.6, 2.2}}, Instance{1, glm::dmat3(1e-3), {1.0, 1.0, -2.0}}};
  check_scene(scene);
  return scene;
}

// Its box, the plane aside.
inline Box placed_shapes_box() { return {glm::dvec3(-3.5, -1.6, -3.5), glm::dvec3(3.5, 2.5, 3.5)}; }

}  // namespace vkray::test
