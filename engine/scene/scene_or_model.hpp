// What a user names as a scene: a scene file, a model, or nothing (the built-in scene), as the
// command line and Python's vkray.load take it.
#pragma once

#include "engine/scene/model_loader.hpp"
#include "engine/scene/scene.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace vkray {

// A scene file (.json), or a model (engine/scene/model_loader.hpp) alone in a scene, seen from the
// model's own camera (a glTF's) or else a camera that frames it (engine/scene/framing.hpp); the
// built-in scene for an empty path. `width`/`height` override the image
// size, and the framing is done at the final size. Throws InputError naming the file.
Scene load_scene_or_model(const std::filesystem::path& path, std::optional<uint32_t> width = {},
                          std::optional<uint32_t> height = {});

}  // namespace vkray
