#include "engine/bench/stiff_cases.hpp"

#include "engine/scene/camera.hpp"
#include "engine/scene/framing.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/scene_loader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace vkray {
namespace {

constexpr glm::dvec3 y_up(0.0, 1.0, 0.0);

double degrees(double radians) { return radians * 180.0 / std::numbers::pi; }

Scene empty_scene(uint32_t width, uint32_t height) {
  Scene scene;
  scene.width = width;
  scene.height = height;
  return scene;
}

Scene built_in(uint32_t width, uint32_t height) {
  Scene scene = default_scene();
  scene.width = width;
  scene.height = height;
  return scene;
}

Scene translated(Scene scene, const glm::dvec3& offset) {
  for (auto& sphere : scene.spheres) sphere.center += offset;
  for (auto& plane : scene.planes) plane.point += offset;
  for (auto& mesh : scene.meshes) {
    for (auto& position : mesh.positions) position += offset;
  }
  scene.camera.from += offset;
  scene.camera.to += offset;
  return scene;
}

std::string power_of_ten(int exponent) { return "1e" + std::to_string(exponent); }

// Spheres of radius r at distance D = 1000 from a camera looking straight down -z, under a field of
// view the sphere fills to 60%: axis-aligned, so the ray directions themselves are exact to float32
// and the case measures the intersection arithmetic alone.
void add_far_spheres(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  const glm::dvec3 camera(3.0, -2.0, 7.0);
  constexpr double distance = 1000.0;
  for (int exponent = 0; exponent >= -7; --exponent) {
    const double ratio = exponent == 0 ? 0.5 : std::pow(10.0, exponent);  // r/D = 1 puts the camera on the sphere
    const double radius = ratio * distance;
    Scene scene = empty_scene(width, height);
    scene.spheres.push_back({camera + glm::dvec3(0.3 * radius, 0.2 * radius, -distance), radius});
    scene.camera = {camera, camera - glm::dvec3(0.0, 0.0, 1.0), y_up, degrees(2.0 * std::atan(ratio / 0.6))};
    char name[40];
    std::snprintf(name, sizeof name, "far-sphere-%.0e", ratio);
    StiffCase entry{name, std::string("radius / distance = ") + (exponent == 0 ? "0.5" : power_of_ten(exponent)), scene,
                    "naive-sphere", ""};
    if (exponent > -4) {
      entry.fails_with.clear();
      entry.why = "b^2 - c keeps enough digits while r/D is above ~2e-4 (float32: the sphere's share of b^2 is r^2/D^2)";
    }
    cases.push_back(std::move(entry));
  }
}

// A unit sphere whose silhouette passes through the image centre, seen along -z from 10 away, under
// fields of view spanning impact parameters r(1 - s) to r(1 + s).
void add_silhouettes(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  for (int exponent : {-3, -6}) {
    const double span = std::pow(10.0, exponent);
    Scene scene = empty_scene(width, height);
    scene.spheres.push_back({glm::dvec3(1.0, 0.0, 0.0), 1.0});
    const glm::dvec3 from(0.0, 0.0, 10.0);
    const double half_width = span / 10.0;  // impact parameter changes by 10 per radian here
    const double aspect = static_cast<double>(std::min(width, height)) / width;
    scene.camera = {from, from - glm::dvec3(0.0, 0.0, 1.0), y_up, degrees(2.0 * std::atan(half_width * aspect))};
    StiffCase entry{"sphere-silhouette-" + power_of_ten(exponent),
                    "rays grazing a sphere at impact parameters r(1 +- " + power_of_ten(exponent) + ") and closer", scene,
                    "", ""};
    entry.why = exponent == -3
                    ? "1e-3 from the silhouette the textbook form's error (b^2 at 100 times the discriminant) stays "
                      "inside what float32 positions allow there, where depth and normal move like 1 / sqrt(1 - b/r)"
                    : "1e-6 r from the silhouette is within float32's resolution of the impact parameter "
                      "(2 eps |c - o| ~ 2.5e-6 r here): every pixel may legitimately hit or miss; the textbook form "
                      "still loses half the hits the stable one keeps (flips in docs/accuracy.md)";
    cases.push_back(std::move(entry));
  }
}

void add_planes(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  // A plane seen from 1e-3 above, out to the horizon, a sphere far off (the scene's centre is not
  // the camera): rays from 1e-1 down to ~1e-3 rad.
  Scene grazing = empty_scene(width, height);
  grazing.planes.push_back({glm::dvec3(0.0), y_up});
  grazing.spheres.push_back({glm::dvec3(0.0, 0.5, -20.0), 0.5});
  grazing.camera = {glm::dvec3(0.0, 1e-3, 0.0), glm::dvec3(0.0, 1e-3, -1.0), y_up, 30.0};
  cases.push_back({"grazing-plane", "a plane from 1e-3 above: angles 1e-1 rad down to the horizon", grazing,
                   "scene-anchor", ""});

  // The same at angles of 2e-6 rad and below, 1e4 from the origin along the normal.
  Scene shallow = empty_scene(width, height);
  shallow.planes.push_back({glm::dvec3(0.0, 1e4, 0.0), y_up});
  const glm::dvec3 eye(0.0, 1e4 + 1e-3, 0.0);
  shallow.camera = {eye, eye - glm::dvec3(0.0, 0.0, 1.0), y_up, degrees(4e-6)};
  cases.push_back({"grazing-plane-1e-6", "a plane at y = 1e4 from 1e-3 above, rays at 2e-6 rad and below", shallow, "",
                   "at 2e-6 rad a float32 direction's rounding (~1e-6 rad in general position) moves the hit by "
                   "half its distance, so the envelope cannot tell variants apart; the case checks for no NaN, no "
                   "huge finite depth and hits where the reference hits (docs/accuracy.md has the errors)"});

  // The middle row of an odd-height image is exactly parallel to the plane: a miss.
  Scene parallel = empty_scene(33, 33);
  parallel.planes.push_back({glm::dvec3(0.0), y_up});
  parallel.camera = {glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(0.0, 1.0, -1.0), y_up, 20.0};
  cases.push_back({"plane-parallel-rays", "a row of rays exactly parallel to a plane (33x33)", parallel, "",
                   "every variant tests n.d == 0 before dividing"});
}

void add_cameras_at_spheres(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  Scene planet = empty_scene(width, height);
  planet.spheres.push_back({glm::dvec3(0.0, -1e6, 0.0), 1e6});
  planet.spheres.push_back({glm::dvec3(0.61, 1.13, -5.27), 1.0});
  planet.camera = {glm::dvec3(0.37, 1.21, 3.11), glm::dvec3(0.5, 0.53, -5.0), y_up, 60.0};
  cases.push_back({"huge-sphere-ground", "a planet of radius 1e6 as the ground, the camera 1 above it", planet,
                   "scene-anchor", ""});

  Scene inside = empty_scene(width, height);
  const glm::dvec3 centre(0.3, -0.2, 0.1);
  inside.spheres.push_back({centre, 2.0});
  inside.camera = {centre + glm::dvec3(0.0, 0.0, 1.98), centre + glm::dvec3(0.1, 0.05, 3.0), y_up, 90.0};
  cases.push_back({"camera-inside-sphere", "inside a sphere, 0.02 from its surface, looking out", inside, "",
                   "the textbook far root -b + sqrt(disc) loses eps |b| <= eps (|c - o| + r), which float32 "
                   "positions relative to the camera lose anyway; the stable form is more accurate (ulps in "
                   "docs/accuracy.md) but the textbook one is not wrong beyond that"});

  Scene on_surface = empty_scene(width, height);
  on_surface.spheres.push_back({glm::dvec3(0.0), 5.0});
  on_surface.planes.push_back({glm::dvec3(0.0, -8.0, 0.0), y_up});
  on_surface.camera = {glm::dvec3(3.0, 4.0, 0.0), glm::dvec3(-3.0, -2.0, 1.0), y_up, 100.0};
  cases.push_back({"camera-on-sphere", "the camera exactly on a sphere's surface", on_surface, "",
                   "|f| = 5 is exact, so c = 0 exactly in float32 too, and neither form returns t <= 0"});
}

void add_translations(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  for (int exponent : {5, 6, 7}) {
    const double offset = std::pow(10.0, exponent);
    cases.push_back({"default-at-" + power_of_ten(exponent),
                     "the built-in scene, camera included, moved by " + power_of_ten(exponent),
                     translated(built_in(width, height), glm::dvec3(offset, offset, -offset)), "absolute", ""});
  }
}

void add_vertical_cameras(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  const std::string why =
      "the camera frame is built once, in double, on the host (engine/scene/camera.cpp), for every variant; the course "
      "formula without its fallback gives NaN (tests/camera_test.cpp)";
  Scene up = empty_scene(width, height);
  up.spheres = make_sphere_field(50, 3, {glm::dvec3(-3.0, 4.0, -3.0), glm::dvec3(3.0, 8.0, 3.0)});
  up.camera = {glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0), y_up, 70.0};
  cases.push_back({"camera-straight-up", "looking straight up, along the up vector", up, "", why});

  Scene down = built_in(width, height);
  down.camera = {glm::dvec3(0.3, 6.0, 0.2), glm::dvec3(0.3, 0.0, 0.2), y_up, 60.0};
  cases.push_back({"camera-straight-down", "the built-in scene from straight above", down, "", why});

  Scene near_vertical = built_in(width, height);
  near_vertical.camera = {glm::dvec3(0.3, 6.0, 0.2), glm::dvec3(0.3 + 6e-7, 0.0, 0.2), y_up, 60.0};
  cases.push_back({"camera-1e-7-off-vertical", "the built-in scene from above, 1e-7 rad off the up vector",
                   near_vertical, "", why});
}

// An octahedron's vertices on the axes, seen along -z: the middle row and column of an odd image
// are rays in the planes of its edges, the central ray goes through a vertex.
Mesh octahedron() {
  Mesh mesh;
  mesh.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  mesh.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return mesh;
}

// A grid mesh in the plane z = `z` with a vertex where each pixel centre's ray of `scene`'s camera
// (looking down -z) meets that plane, and a ring of vertices around them.
Mesh pixel_grid(const Scene& scene, double z) {
  const CameraBasis camera = make_camera_basis(scene.camera, scene.width, scene.height);
  Mesh mesh;
  const int columns = static_cast<int>(scene.width) + 2, rows = static_cast<int>(scene.height) + 2;
  for (int j = -1; j <= static_cast<int>(scene.height); ++j) {
    for (int i = -1; i <= static_cast<int>(scene.width); ++i) {
      const glm::dvec2 uv((2.0 * (i + 0.5) - scene.width) / std::min(scene.width, scene.height),
                          (scene.height - 2.0 * (j + 0.5)) / std::min(scene.width, scene.height));
      const glm::dvec3 dir = camera.direction(uv);
      mesh.positions.push_back(camera.origin + ((z - camera.origin.z) / dir.z) * dir);
    }
  }
  for (int j = 0; j + 1 < rows; ++j) {
    for (int i = 0; i + 1 < columns; ++i) {
      const auto corner = [&](int di, int dj) { return static_cast<uint32_t>((j + dj) * columns + i + di); };
      mesh.triangles.push_back({corner(0, 0), corner(1, 0), corner(1, 1)});
      mesh.triangles.push_back({corner(0, 0), corner(1, 1), corner(0, 1)});
    }
  }
  return mesh;
}

void add_meshes(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  Scene origin_mesh = empty_scene(width, height);
  origin_mesh.meshes.push_back(make_sphere_mesh(20'000));
  origin_mesh.camera = frame_scene(origin_mesh, width, height);
  cases.push_back({"closed-mesh-at-origin", "a closed 20k-triangle mesh: rays must not leak between triangles",
                   origin_mesh, "",
                   "at test sizes no ray comes close enough to a shared edge for Moeller-Trumbore to leak (at "
                   "1920x1080 it does: docs/accuracy.md); grid-at-pixel-rays aims every ray at one"});

  Scene offset_mesh = empty_scene(width, height);
  offset_mesh.meshes.push_back(make_sphere_mesh(20'000, glm::dvec3(1e5, 0.0, 0.0)));
  offset_mesh.camera = frame_scene(offset_mesh, width, height);
  cases.push_back({"closed-mesh-at-1e5", "the same mesh 1e5 from the origin", offset_mesh, "absolute", ""});

  // A grid whose vertices lie where the pixel rays of a 64x48 image meet z = 0: every ray aims at a
  // vertex shared by six triangles (up to the rounding of the vertex itself), in front of a plane
  // that a leaking ray would hit instead.
  Scene grid = empty_scene(64, 48);
  grid.camera = {glm::dvec3(0.0, 0.0, 4.0), glm::dvec3(0.0), y_up, 40.0};
  grid.planes.push_back({glm::dvec3(0.0, 0.0, -1.0), glm::dvec3(0.0, 0.0, 1.0)});
  grid.meshes.push_back(pixel_grid(grid, 0.0));
  cases.push_back({"grid-at-pixel-rays", "every ray aimed at a vertex shared by six triangles (64x48)", grid,
                   "moller-trumbore", ""});

  Scene edges = empty_scene(65, 65);
  edges.meshes.push_back(octahedron());
  edges.camera = {glm::dvec3(0.0, 0.0, 5.0), glm::dvec3(0.0), y_up, 30.0};
  cases.push_back({"octahedron-edges", "rays exactly through shared edges and a shared vertex (65x65)", edges, "",
                   "with vertices on the axes every edge function is exact in float32, so Moeller-Trumbore's "
                   "u, v >= 0 tests hold on the edges too"});

  // Degenerate triangles in front of a plane: none may be hit, none may give NaN.
  Scene degenerate = empty_scene(width, height);
  degenerate.planes.push_back({glm::dvec3(0.0, 0.0, -5.0), glm::dvec3(0.0, 0.0, 1.0)});
  Mesh junk;
  junk.positions = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0},          // one point three times
                    {-1, -1, 1}, {1, 1, 1}, {1, 1, 1},        // a repeated vertex
                    {-1, 1, 0.5}, {0, 0, 0.5}, {1, -1, 0.5},  // collinear
                    {-1, 0, 0.2}, {1, 0, 0.2}, {0, 1e-21, 0.2}};  // a needle of area 1e-21: hit by no ray
  junk.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9, 10, 11}};
  degenerate.meshes.push_back(junk);
  degenerate.camera = {glm::dvec3(0.0, 0.0, 5.0), glm::dvec3(0.0), y_up, 40.0};
  cases.push_back({"degenerate-triangles", "zero-area, repeated-vertex, collinear and 1e-21-area triangles", degenerate,
                   "", "both triangle tests reject a zero determinant, and the host drops zero-area triangles first"});
}

void add_coincident(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  const std::string why = "the tie-break for coincident surfaces (VKRAY_COINCIDENT_GAP) is part of every variant";
  const Camera camera{glm::dvec3(0.5, 3.0, 6.0), glm::dvec3(0.0, 0.0, 0.0), y_up, 50.0};

  Scene in_plane = empty_scene(width, height);
  in_plane.planes.push_back({glm::dvec3(0.0), y_up});
  Mesh floor;
  floor.positions = {{-3, 0, -3}, {3, 0, -2}, {0, 0, 3}};
  floor.triangles = {{0, 1, 2}};
  in_plane.meshes.push_back(floor);
  in_plane.camera = camera;
  cases.push_back({"triangle-in-plane", "a triangle lying in a plane", in_plane, "", why});

  Scene twins = empty_scene(width, height);
  Mesh twin;
  twin.positions = {{-3, 0, -3}, {3, 0.5, -2}, {0, -0.5, 3}};
  twin.triangles = {{0, 1, 2}, {0, 2, 1}, {0, 1, 2}};  // the same triangle three times, once flipped
  twins.meshes.push_back(twin);
  twins.planes.push_back({glm::dvec3(0.0, -2.0, 0.0), y_up});
  twins.camera = camera;
  cases.push_back({"identical-triangles", "the same triangle three times, once with the other winding", twins, "", why});

  Scene touching = empty_scene(width, height);
  touching.planes.push_back({glm::dvec3(0.0), y_up});
  touching.spheres.push_back({glm::dvec3(0.0, 1.0, 0.0), 1.0});
  touching.camera = {glm::dvec3(0.0, 0.05, 6.0), glm::dvec3(0.0, 0.0, 0.0), y_up, 10.0};
  cases.push_back({"sphere-touching-plane", "a sphere resting on a plane, seen at the contact", touching, "", why});
}

void add_extremes(std::vector<StiffCase>& cases, uint32_t width, uint32_t height) {
  const std::string why = "these check limits (no NaN, tiling, sizes); no textbook variant differs there";
  Scene narrow = built_in(width, height);
  narrow.camera.fovy_degrees = 1e-4;
  cases.push_back({"fovy-1e-4", "the built-in scene under a 1e-4 degree field of view", narrow, "", why});

  Scene wide = built_in(width, height);
  wide.camera.fovy_degrees = 179.9;
  cases.push_back({"fovy-179.9", "the built-in scene under a 179.9 degree field of view", wide, "", why});

  for (const auto& [w, h] : {std::pair<uint32_t, uint32_t>{1, 1}, {1, 4096}, {4096, 1}, {7680, 4320}}) {
    Scene sized = built_in(w, h);
    cases.push_back({"image-" + std::to_string(w) + "x" + std::to_string(h),
                     "the built-in scene at " + std::to_string(w) + "x" + std::to_string(h), sized, "", why});
  }
}

}  // namespace

std::vector<StiffCase> stiff_cases(uint32_t width, uint32_t height) {
  std::vector<StiffCase> cases;
  add_far_spheres(cases, width, height);
  add_silhouettes(cases, width, height);
  add_cameras_at_spheres(cases, width, height);
  add_planes(cases, width, height);
  add_translations(cases, width, height);
  add_vertical_cameras(cases, width, height);
  add_meshes(cases, width, height);
  add_coincident(cases, width, height);
  add_extremes(cases, width, height);
  return cases;
}

}  // namespace vkray
