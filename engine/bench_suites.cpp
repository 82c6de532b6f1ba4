#include "engine/bench_suites.hpp"

#include "engine/framing.hpp"
#include "engine/mesh_generators.hpp"
#include "engine/scene_loader.hpp"

#include <algorithm>

namespace vkray {
namespace {

Scene empty_scene(uint32_t width, uint32_t height) {
  Scene scene;
  scene.width = width;
  scene.height = height;
  return scene;
}

// A scene of finite geometry, framed the way `vkray render MODEL.obj` frames a model.
BenchScene framed(std::string name, Scene scene) {
  scene.camera = frame_scene(scene, scene.width, scene.height);
  return {std::move(name), std::move(scene)};
}

std::vector<BenchScene> basic_suite(uint32_t width, uint32_t height) {
  std::vector<BenchScene> scenes;
  Scene built_in = default_scene();
  built_in.width = width;
  built_in.height = height;
  scenes.push_back({"default", std::move(built_in)});

  Scene sphere = empty_scene(width, height);
  sphere.spheres.push_back({glm::dvec3(0.0), 1.0});
  scenes.push_back(framed("one-sphere", std::move(sphere)));

  Scene field = empty_scene(width, height);
  field.spheres = make_sphere_field(100, 7, {glm::dvec3(-4.0, 0.5, -4.0), glm::dvec3(4.0, 2.5, 4.0)});
  field.planes.push_back({glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0)});
  field.camera = {glm::dvec3(0.0, 4.0, 9.0), glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(0.0, 1.0, 0.0), 50.0};
  scenes.push_back({"spheres-on-plane", std::move(field)});

  Scene mesh = empty_scene(width, height);
  mesh.meshes.push_back(make_sphere_mesh(80'000));
  scenes.push_back(framed("sphere-mesh-80k", std::move(mesh)));
  return scenes;
}

std::vector<BenchScene> scaling_suite(uint32_t width, uint32_t height) {
  std::vector<BenchScene> scenes;
  for (const size_t triangles : {1'000, 10'000, 100'000, 1'000'000, 4'000'000}) {
    Scene scene = empty_scene(width, height);
    scene.meshes.push_back(make_sphere_mesh(triangles));
    scenes.push_back(framed("sphere-mesh-" + std::to_string(scene.triangle_count()), std::move(scene)));
  }
  for (const size_t spheres : {1, 10, 100, 1'000, 10'000}) {
    Scene scene = empty_scene(width, height);
    scene.spheres = make_sphere_field(spheres, 11);
    scenes.push_back(framed("sphere-field-" + std::to_string(spheres), std::move(scene)));
  }
  return scenes;
}

// The numerically hard cases of the robustness work, one representative each.
std::vector<BenchScene> stiff_suite(uint32_t width, uint32_t height) {
  std::vector<BenchScene> scenes;
  const glm::dvec3 y_up(0.0, 1.0, 0.0);

  // radius / distance = 1e-4 under a field of view that makes it fill the image: b^2 - c cancels.
  Scene far_sphere = empty_scene(width, height);
  far_sphere.spheres.push_back({glm::dvec3(0.0, 0.0, -1e4), 1.0});
  far_sphere.camera = {glm::dvec3(0.0), glm::dvec3(0.0, 0.0, -1.0), y_up, 0.0125};
  scenes.push_back({"small-sphere-far-away", std::move(far_sphere)});

  // A planet of radius 1e6 as the ground, the camera one unit above it, a unit sphere beside it.
  Scene planet = empty_scene(width, height);
  planet.spheres.push_back({glm::dvec3(0.0, -1e6, 0.0), 1e6});
  planet.spheres.push_back({glm::dvec3(0.0, 1.0, -5.0), 1.0});
  planet.camera = {glm::dvec3(0.0, 1.0, 3.0), glm::dvec3(0.0, 0.5, -5.0), y_up, 60.0};
  scenes.push_back({"huge-sphere-ground", std::move(planet)});

  // A plane seen from 1e-3 above, out to the horizon: ever more grazing rays.
  Scene grazing = empty_scene(width, height);
  grazing.planes.push_back({glm::dvec3(0.0), y_up});
  grazing.spheres.push_back({glm::dvec3(0.0, 0.5, -20.0), 0.5});
  grazing.camera = {glm::dvec3(0.0, 1e-3, 0.0), glm::dvec3(0.0, 1e-3, -1.0), y_up, 30.0};
  scenes.push_back({"grazing-plane", std::move(grazing)});

  // The built-in scene moved 1e6 away from the origin, camera included.
  Scene far_away = default_scene();
  far_away.width = width;
  far_away.height = height;
  const glm::dvec3 offset(1e6, 1e6, -1e6);
  for (auto& sphere : far_away.spheres) sphere.center += offset;
  for (auto& plane : far_away.planes) plane.point += offset;
  for (auto& mesh : far_away.meshes) {
    for (auto& position : mesh.positions) position += offset;
  }
  far_away.camera.from += offset;
  far_away.camera.to += offset;
  scenes.push_back({"default-at-1e6", std::move(far_away)});

  // Looking straight up (the up vector is parallel to the view) at spheres overhead.
  Scene looking_up = empty_scene(width, height);
  looking_up.spheres = make_sphere_field(50, 3, {glm::dvec3(-3.0, 4.0, -3.0), glm::dvec3(3.0, 8.0, 3.0)});
  looking_up.camera = {glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0), y_up, 70.0};
  scenes.push_back({"camera-straight-up", std::move(looking_up)});

  // A closed mesh 1e5 from the origin: rays through shared edges and vertices must not leak.
  Scene offset_mesh = empty_scene(width, height);
  offset_mesh.meshes.push_back(make_sphere_mesh(20'000, glm::dvec3(1e5, 0.0, 0.0)));
  scenes.push_back(framed("closed-mesh-at-1e5", std::move(offset_mesh)));
  return scenes;
}

std::vector<BenchScene> models_suite(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                     std::vector<std::string>* skipped) {
  std::vector<std::filesystem::path> files;
  std::error_code listing_error;
  for (const auto& entry : std::filesystem::directory_iterator(models_dir, listing_error)) {
    if (entry.path().extension() == ".obj") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<BenchScene> scenes;
  for (const auto& file : files) {
    try {
      Scene scene = load_model_file(file);
      scene.width = width;
      scene.height = height;
      scenes.push_back(framed(file.filename().string(), std::move(scene)));
    } catch (const InputError& error) {  // one broken file does not end the suite
      if (skipped) skipped->push_back(error.what());
    }
  }
  return scenes;
}

}  // namespace

std::vector<BenchScene> bench_suite(const std::string& suite, uint32_t width, uint32_t height,
                                    const std::filesystem::path& models_dir, std::vector<std::string>* skipped) {
  if (suite == "basic") return basic_suite(width, height);
  if (suite == "scaling") return scaling_suite(width, height);
  if (suite == "stiff") return stiff_suite(width, height);
  if (suite == "models") return models_suite(width, height, models_dir, skipped);
  throw InputError("--suite: unknown suite '" + suite + "' (choose from " + bench_suite_names + ")");
}

}  // namespace vkray
