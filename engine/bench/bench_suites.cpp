#include "engine/bench/bench_suites.hpp"

#include "engine/scene/framing.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/bench/stiff_cases.hpp"

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

}  // namespace

std::vector<BenchScene> basic_scenes(uint32_t width, uint32_t height, const std::filesystem::path&, std::vector<std::string>*) {
  std::vector<BenchScene> scenes;
  Scene built_in = default_scene();
  built_in.width = width;
  built_in.height = height;
  scenes.push_back({"built-in", std::move(built_in)});

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

std::vector<BenchScene> scaling_scenes(uint32_t width, uint32_t height, const std::filesystem::path&, std::vector<std::string>*) {
  std::vector<BenchScene> scenes;
  for (const size_t triangles : {1'000, 10'000, 100'000, 1'000'000, 4'000'000}) {
    Scene scene = empty_scene(width, height);
    scene.meshes.push_back(make_sphere_mesh(triangles));
    // Named before the call: its arguments are evaluated in no set order, and the scene moves.
    const std::string name = "sphere-mesh-" + std::to_string(scene.triangle_count());
    scenes.push_back(framed(name, std::move(scene)));
  }
  for (const size_t spheres : {1, 10, 100, 1'000, 10'000}) {
    Scene scene = empty_scene(width, height);
    scene.spheres = make_sphere_field(spheres, 11);
    scenes.push_back(framed("sphere-field-" + std::to_string(spheres), std::move(scene)));
  }
  return scenes;
}

std::vector<BenchScene> stiff_scenes(uint32_t width, uint32_t height, const std::filesystem::path&, std::vector<std::string>*) {
  std::vector<BenchScene> scenes;
  for (auto& stiff : stiff_cases(width, height)) scenes.push_back({std::move(stiff.name), std::move(stiff.scene)});
  return scenes;
}

std::vector<BenchScene> model_folder_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
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

namespace {

// `name` from `models_dir`, framed at width x height; a line in `skipped` where it is not there.
void add_model(std::vector<BenchScene>& scenes, const char* name, uint32_t width, uint32_t height,
               const std::filesystem::path& models_dir, std::vector<std::string>* skipped) {
  const std::filesystem::path model = models_dir / name;
  if (!std::filesystem::exists(model)) {
    if (skipped) skipped->push_back(std::string(name) + ": not in the models folder '" + models_dir.string() + "' (name it with --models)");
    return;
  }
  try {
    Scene scene = load_model_file(model);
    scene.width = width;
    scene.height = height;
    scenes.push_back(framed(name, std::move(scene)));
  } catch (const InputError& error) {  // one broken file does not end the suite
    if (skipped) skipped->push_back(error.what());
  }
}

std::vector<BenchScene> named_models(std::initializer_list<const char*> names, uint32_t width, uint32_t height,
                                     const std::filesystem::path& models_dir, std::vector<std::string>* skipped) {
  std::vector<BenchScene> scenes;
  for (const char* name : names) add_model(scenes, name, width, height, models_dir, skipped);
  return scenes;
}

}  // namespace

std::vector<BenchScene> accuracy_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                        std::vector<std::string>* skipped) {
  // The stiff cases, then ordinary scenes to show what the robust default costs there.
  std::vector<BenchScene> scenes = stiff_scenes(width, height);
  for (auto& scene : basic_scenes(width, height)) scenes.push_back(std::move(scene));
  add_model(scenes, accuracy_model, width, height, models_dir, skipped);
  return scenes;
}

std::vector<BenchScene> given_rays_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                          std::vector<std::string>* skipped) {
  return named_models({"teapot.obj", "stanford-bunny.obj", "stanford-dragon-100k.obj"}, width, height, models_dir, skipped);
}

std::vector<BenchScene> moving_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                      std::vector<std::string>* skipped) {
  return named_models({"stanford-bunny.obj", "stanford-dragon-100k.obj"}, width, height, models_dir, skipped);
}

std::vector<BenchScene> instances_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                         std::vector<std::string>* skipped) {
  return named_models({"stanford-bunny.obj", "stanford-dragon-100k.obj", "armadillo-50k.obj", "spot.obj", "teapot.obj"}, width,
                      height, models_dir, skipped);
}

std::vector<BenchScene> points_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                      std::vector<std::string>* skipped) {
  return named_models({"stanford-bunny.obj", "stanford-dragon-100k.obj", "armadillo-50k.obj"}, width, height, models_dir, skipped);
}

}  // namespace vkray
