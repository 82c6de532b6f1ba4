// Writing render results: OpenEXR with the output contract's channels, and a PNG preview.
#pragma once

#include "engine/frame.hpp"

#include <filesystem>

namespace vkray {

// float32 channels, by output: depth -> Z; normal -> N.X N.Y N.Z; uv -> U V; and A (1 on a hit,
// 0 on a miss) whenever depth or normal is present. Throws std::runtime_error naming the file.
void write_exr(const std::filesystem::path& path, const Frame& frame);

// 8-bit RGB preview, one panel per output side by side in the order depth, normal, uv: depth as
// grey (near bright, far dark, misses black), normals as (N+1)/2, uv as (u+1)/2, (v+1)/2 with the
// unit disk drawn brighter (it must touch the shorter borders).
void write_preview_png(const std::filesystem::path& path, const Frame& frame);

}  // namespace vkray
