// A camera for a scene nobody wrote a camera for: `vkray render MODEL.obj` and the bench's models.
#pragma once

#include "engine/scene/scene.hpp"

#include <filesystem>

namespace vkray {

// The default view of a model: from the +z side and a little above (y-up models such as the
// Stanford scans face +z), looking at the centre of its bounding sphere, with this vertical field
// of view in degrees.
inline constexpr double framing_fovy_degrees = 40.0;
inline const glm::dvec3 framing_view_from{0.0, 0.25, 1.0};  // direction from the centre to the eye

// A camera that sees the whole bounding sphere of the scene's meshes and spheres at width x
// height: the sphere (centre of the bounding box, radius the largest distance from it) touches the
// shorter borders of the image. Throws InputError when the scene has no finite geometry.
Camera frame_scene(const Scene& scene, uint32_t width, uint32_t height);

// A scene holding the OBJ file's mesh alone, its camera from frame_scene at the default size.
Scene load_model_file(const std::filesystem::path& path);

}  // namespace vkray
