// glTF 2.0 scenes (.gltf with its buffers beside it or embedded, .glb) through tinygltf 2.7 (Debian's
// libtinygltf-dev), compiled into vkray: the fuzzers instrument it with the rest of the parsers.
// Every buffer read goes through accessor_values' bounds checks, which tinygltf leaves to its user.
//
// The default scene's nodes are walked from its roots; each node with a mesh gives one vkray mesh, its
// primitives merged (triangles, strips and fans; points and lines have no area and are left out),
// through the node's world transform in double. NORMAL and TEXCOORD_0 become shading normals and
// texture coordinates, v turned to OBJ's convention (v = 0 at the bottom of the image). The first
// camera met places the view: perspective or orthographic.
#pragma once

#include "engine/scene/model_loader.hpp"

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace vkray {

// A glTF's nodes may place at most this many triangle corners and vertices for each byte of the mesh
// data they come from (one mesh named by 256 nodes, reached along 256 paths of the node graph, or
// its accessors shared by 256 primitives, each carries at most that): vkray stores each placement as
// a copy, so what a file makes stays within this factor of what it holds.
inline constexpr size_t max_gltf_instancing = 256;

// The model of the glTF `bytes` (JSON, or binary when `binary`), its external buffers found in
// `folder`; `name` stands for the file in messages and sources ("scene.gltf#Wheel"). Throws
// InputError "<name>: ..." naming the node, mesh or accessor at fault.
Model read_gltf(std::string_view bytes, bool binary, const std::filesystem::path& folder, const std::string& name);

}  // namespace vkray
