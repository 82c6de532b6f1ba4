#include "engine/scene/scene_or_model.hpp"

#include "engine/scene/framing.hpp"
#include "engine/scene/model_loader.hpp"
#include "engine/scene/scene_loader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vkray {

Scene load_scene_or_model(const std::filesystem::path& path, std::optional<uint32_t> width, std::optional<uint32_t> height) {
  const std::string extension = lower_extension(path);
  const std::string name = path.string();
  if (!path.empty() && std::filesystem::is_directory(path)) {
    throw InputError(name + ": is a folder, not a scene file (.json) or a model (" + model_extension_list() + ")");
  }
  if (!path.empty() && extension != ".json" && !is_model_extension(extension)) {
    throw InputError(name + ": unknown kind of file '" + extension + "' (a scene is .json, a model " + model_extension_list() + ")");
  }
  if (path.empty() || extension == ".json") {
    Scene scene = path.empty() ? default_scene() : load_scene_file(path);
    if (width) scene.width = *width;
    if (height) scene.height = *height;
    check_scene(scene);  // what the file's parser left (it names each item by file and place first)
    return scene;
  }
  Model model = load_model(path);
  Scene scene;
  scene.meshes = std::move(model.meshes);
  if (width) scene.width = *width;
  if (height) scene.height = *height;
  // A glTF camera's aspect ratio gives the side not given (the width of the default height).
  if (model.aspect_ratio && !(width && height)) {
    const double ratio = *model.aspect_ratio;
    const double pixels = width ? *width / ratio : scene.height * ratio;
    if (!(pixels >= 0.5 && pixels < max_image_side + 0.5)) {
      char text[160];
      std::snprintf(text, sizeof text, ": its camera's aspect ratio %.6g makes the image %.6g pixels %s, outside 1 to %u: give --width and --height",
                    ratio, pixels, width ? "high" : "wide", max_image_side);
      throw InputError(name + text);
    }
    (width ? scene.height : scene.width) = static_cast<uint32_t>(std::lround(pixels));
  }
  check_image_size(scene.width, scene.height);
  if (model.camera) {
    scene.camera = *model.camera;
    scene.camera.fovy_degrees = fovy_degrees_from_vertical(model.camera->fovy_degrees, scene.width, scene.height);
  } else {
    scene.camera = frame_scene(scene, scene.width, scene.height);
  }
  check_scene(scene);
  return scene;
}

}  // namespace vkray
