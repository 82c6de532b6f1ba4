// A rendered image's camera as JSON, for readers outside vkray: the scene file's camera (from, to,
// up, and fovy or the intrinsics it was given: pasted into a scene file or given to --camera it
// renders the same pixels), and OpenCV's
// intrinsics and world-to-camera matrix (engine/scene/camera.hpp) at the image's size:
//
//   {"camera": {"from": [...], "to": [...], "up": [...], "fovy": 40},
//    "intrinsics": {"fx": ..., "fy": ..., "cx": ..., "cy": ...},
//    "world_to_camera": [[...], [...], [...], [0, 0, 0, 1]]}
//
// Each record of a many-view manifest holds these keys, and the EXR header's vkray:camera attribute
// holds the object. An orthographic or equirectangular camera has "projection" (and "view_height")
// in place of fovy, and no intrinsics.
#pragma once

#include "engine/scene/camera.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>

namespace vkray {

nlohmann::ordered_json camera_description(const Camera& camera, uint32_t width, uint32_t height);

}  // namespace vkray
