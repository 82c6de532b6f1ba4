// PLY meshes (Greg Turk's polygon file format, as the Stanford 3D Scanning Repository ships its scans):
// ASCII, binary little- and big-endian. Read by hand: Debian 12's one PLY reader, assimp 5.2, hung on
// a header with one letter changed and rounds every coordinate to float32 (found in the first minute
// of fuzzing it), while the format is a header and fixed records.
//
// The "vertex" element gives x, y, z, and where present nx, ny, nz (shading normals) and u, v (or s, t,
// or texture_u, texture_v); the "face" element a list vertex_indices (or vertex_index) of three or more
// corners, polygons triangulated as OBJ's are (polygon_triangulation.hpp). Other elements and
// properties are read past. Numbers keep their precision: doubles stay doubles.
#pragma once

#include "engine/scene/scene.hpp"

#include <string>
#include <string_view>

namespace vkray {

// The mesh of the PLY `bytes`, `name` standing for the file in messages. Throws InputError
// "<name>:<line>: ..." (header, ASCII body) or "<name>: byte <offset>: ..." (binary body) for a
// malformed file: an unknown format or type, a missing x, y, z or face list, a count the file is too
// short to hold, a value that is not a number, a position not finite, an index out of range, a face
// of fewer than three or more than max_polygon_corners corners, or no face at all. Normals and
// texture coordinates are the caller's to check (check_mesh_values, model_loader.hpp).
Mesh read_ply(std::string_view bytes, const std::string& name);

}  // namespace vkray
