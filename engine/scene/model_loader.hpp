// Model files, of every kind vkray reads: Wavefront OBJ (obj_loader.hpp), PLY (ply_loader.hpp) and
// glTF 2.0 (gltf_loader.hpp), chosen by the file's extension.
#pragma once

#include "engine/scene/scene.hpp"

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace vkray {

// Every kind of model file, by its extension (lower case): the one list the loaders, the command
// line's messages and the table of docs/scene-format.md follow.
struct ModelKind {
  const char* extension;
  const char* description;
};
inline constexpr std::array model_kinds{
    ModelKind{".obj", "Wavefront OBJ"},
    ModelKind{".ply", "PLY, ASCII or binary"},
    ModelKind{".gltf", "glTF 2.0"},
    ModelKind{".glb", "glTF 2.0, binary"},
};
bool is_model_extension(std::string_view lower_extension);
// A path's extension in lower case, with its dot (".exr"); empty when it has none.
std::string lower_extension(const std::filesystem::path& path);
// ".obj, .ply, .gltf or .glb", for messages.
std::string model_extension_list();

// What a model file holds. An OBJ and a PLY are one mesh each; a glTF has a mesh for each node that
// holds one. Each mesh's `source` is the file, and for a glTF "file#node name".
struct Model {
  std::vector<Mesh> meshes;
  // A glTF's first camera, placed by its node. A perspective one's fovy is the glTF's yfov, across
  // the height; the scene using it turns that to vkray's shorter side (fovy_degrees_from_vertical).
  std::optional<Camera> camera;
  std::optional<double> aspect_ratio;  // width / height, where the glTF's camera gives it
};

// Throws InputError "<path>: ..." for a missing, unreadable or malformed file, or one without a
// triangle, a non-finite value or a coordinate beyond max_coordinate.
Model load_model(const std::filesystem::path& path);

// A model held in memory, `extension` (".obj", ".ply", ".gltf", ".glb") saying which kind; `name`
// stands for the file in messages, and a .gltf's external buffers are looked for in `folder`.
Model read_model_bytes(std::string_view bytes, std::string_view extension, const std::string& name,
                       const std::filesystem::path& folder = {});

// Throws InputError naming `mesh.source` where a coordinate is not finite or beyond max_coordinate,
// or a normal or texture coordinate is not finite. `first_vertex` numbers the first vertex (OBJ: 1).
void check_mesh_values(const Mesh& mesh, size_t first_vertex);

// The fovy vkray's camera takes for a vertical field of view (a glTF's yfov) at width x height:
// vkray's fovy spans the shorter side, which for a portrait image is the horizontal one.
double fovy_degrees_from_vertical(double yfov_degrees, uint32_t width, uint32_t height);

}  // namespace vkray
