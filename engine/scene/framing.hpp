// A camera for a scene nobody wrote a camera for: `vkray render MODEL.obj` and the bench's models.
#pragma once

#include "engine/scene/scene.hpp"

#include <filesystem>
#include <optional>
#include <string_view>

namespace vkray {

// The vertical field of view of a framed camera, in degrees.
inline constexpr double framing_fovy_degrees = 40.0;

// The side a framed camera looks from: the direction from the centre to the eye (any length but
// 0), and its up.
struct FramingView {
  glm::dvec3 from_direction;
  glm::dvec3 up;
};
// The default: from the +z side and a little above (y-up models such as the Stanford scans face
// +z), y up.
inline const FramingView front_view{{0.0, 0.25, 1.0}, {0.0, 1.0, 0.0}};

// "front" (front_view), "back", "left", "right" (each from a little above too), "top" (looking
// down, -z up in the image) or "bottom" (looking up, +z up); none for another name.
std::optional<FramingView> framing_view_from_name(std::string_view name);
inline constexpr const char* framing_view_names = "front, back, left, right, top, bottom";

// A camera that sees the whole bounding sphere of the scene's meshes and spheres at width x
// height from `view`'s side: the sphere (centre of the bounding box, radius the largest distance
// from it) touches the shorter borders of the image. Planes alone: the first seen at a slant from
// one unit along its normal. Throws InputError when the scene has nothing at all.
Camera frame_scene(const Scene& scene, uint32_t width, uint32_t height, const FramingView& view = front_view);

// A scene holding the model file's meshes alone (model_loader.hpp), its camera from frame_scene at
// the default size (a glTF's own camera left out: the bench frames every model alike).
Scene load_model_file(const std::filesystem::path& path);

}  // namespace vkray
