// What a user names as a scene: a scene file, a model, or nothing (the built-in scene), as the
// command line and Python's vkray.load take it.
#pragma once

#include "engine/scene/scene.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace vkray {

// A path's extension in lower case, with its dot (".exr"); empty when it has none.
std::string lower_extension(const std::filesystem::path& path);

// A scene file (.json), or a model (.obj) alone in a scene with a camera that frames it
// (engine/scene/framing.hpp); the built-in scene for an empty path. `width`/`height` override the image
// size, and the framing is done at the final size. Throws InputError naming the file.
Scene load_scene_or_model(const std::filesystem::path& path, std::optional<uint32_t> width = {},
                          std::optional<uint32_t> height = {});

}  // namespace vkray
