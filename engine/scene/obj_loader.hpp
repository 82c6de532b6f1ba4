// Wavefront OBJ meshes. Polygons are triangulated (polygon_triangulation.hpp), negative (relative)
// indices work, and every group and object merges into one mesh. One strict pass checks every
// statement (missing coordinates, NaN, bad or out-of-range indices, a face line cut off at the end of
// a truncated file), reports the line, and builds the mesh.
#pragma once

#include "engine/scene/scene.hpp"

#include <filesystem>
#include <string>
#include <string_view>

namespace vkray {

// Throws InputError "<path>: ..." or "<path>:<line>: ..." for unreadable or malformed files.
Mesh load_obj_file(const std::filesystem::path& path);

// The same for OBJ text already in memory; `name` stands for the file in error messages.
Mesh load_obj_text(std::string_view text, const std::string& name);

}  // namespace vkray
