// The 8-bit picture of one output, shared by the PNG preview (image_io.cpp) and the viewer, so
// that what the viewer shows is byte for byte the panel `vkray render` writes.
#pragma once

#include "engine/frame.hpp"

#include <cstdint>
#include <vector>

namespace vkray {

// `aov` of `frame` (which must hold it) as 8-bit RGB, 3 bytes a pixel, row-major from the top row:
// depth as grey from inverse depth (near bright, far dark, misses black), normals as (N+1)/2
// (misses black), uv as (u+1)/2, (v+1)/2 with the unit disk drawn brighter.
std::vector<uint8_t> preview_rgb(const Frame& frame, Aov aov);

}  // namespace vkray
