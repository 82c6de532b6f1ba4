// What a user names on the command line: the scene to render and the camera to render it with.
#pragma once

#include "engine/scene/framing.hpp"
#include "engine/scene/scene.hpp"

#include <optional>
#include <string>
#include <utility>

namespace vkray::cli {

// engine's load_scene_or_model, with a note on stderr of the zero-area triangles it drops; with a
// --view value, the scene framed from that side (frame_scene), a scene file's camera replaced.
Scene load_scene_argument(const std::string& path, std::optional<uint32_t> width, std::optional<uint32_t> height,
                          const std::optional<std::string>& view = {});

// A --view value: a side's name (front, back, left, right, top, bottom) or the direction X,Y,Z
// from the scene's centre to the eye. Throws InputError with the forms that work.
FramingView parse_view_option(const std::string& text);

// A --size value "WIDTHxHEIGHT" (bench, view). Throws InputError for anything else or a size
// check_image_size refuses.
std::pair<uint32_t, uint32_t> parse_size(const std::string& text);

// Applies a --camera override: space- or semicolon-separated keys, each optional,
// "from=X,Y,Z to=[X,Y,Z] up=X,Y,Z fovy=DEGREES", or the scene file's camera object as JSON with
// every key optional. Checked as the scene file's camera is; throws InputError, with the forms
// that work when the text has none of them.
void apply_camera_option(const std::string& text, Camera& camera);

// Throws InputError, naming --camera or the scene file, where the scene's camera cannot render at
// the scene's size (check_camera_reach).
void check_scene_camera(const Scene& scene, bool camera_option_given, const std::string& scene_path);

// The camera as a --camera option, "--camera 'from=X,Y,Z to=X,Y,Z up=X,Y,Z fovy=DEGREES'", each
// number in the fewest digits that read back as the same double: pasted, it renders the same pixels.
std::string camera_option(const Camera& camera);

}  // namespace vkray::cli
