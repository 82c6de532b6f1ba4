#include "engine/scene/scene_or_model.hpp"

#include "engine/scene/framing.hpp"
#include "engine/scene/scene_loader.hpp"

#include <algorithm>
#include <cctype>

namespace vkray {

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

Scene load_scene_or_model(const std::filesystem::path& path, std::optional<uint32_t> width, std::optional<uint32_t> height) {
  const std::string extension = lower_extension(path);
  const std::string name = path.string();
  if (!path.empty() && std::filesystem::is_directory(path)) {
    throw InputError(name + ": is a folder, not a scene file (.json) or a model (.obj)");
  }
  if (!path.empty() && extension != ".json" && extension != ".obj") {
    throw InputError(name + ": unknown kind of file '" + extension + "' (a scene is .json, a model .obj)");
  }
  Scene scene = path.empty() ? default_scene() : extension == ".obj" ? load_model_file(path) : load_scene_file(path);
  if (width) scene.width = *width;
  if (height) scene.height = *height;
  check_image_size(scene.width, scene.height);
  if (extension == ".obj") scene.camera = frame_scene(scene, scene.width, scene.height);
  return scene;
}

}  // namespace vkray
