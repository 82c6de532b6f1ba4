// What a glTF's JSON must be before tinygltf reads it: tinygltf turns `extras` and `extensions` into
// its own values one stack frame a nesting level (20,000 levels overflow the stack), and it drops a
// node's translation, rotation and scale beside a matrix, where glTF 2.0 (5.25) forbids the pair.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace vkray {

// Far deeper than glTF's own schema nests (6 levels) and any extras seen in real files.
inline constexpr size_t max_gltf_json_depth = 64;

// The JSON of a glTF: the whole .gltf, or a .glb's first chunk where its header is whole (else
// the bytes themselves, which tinygltf then refuses).
std::string_view gltf_json_text(std::string_view bytes, bool binary);

// What is wrong with the glTF JSON `json`, in words for a message after the file's name; none where
// it is well nested (max_gltf_json_depth), its asset.version is 2.x and no node has a matrix beside
// translation, rotation or scale. JSON syntax errors are tinygltf's to name.
std::optional<std::string> gltf_json_fault(std::string_view json);

}  // namespace vkray
