// The built-in course scene. It is written as a scene file and an OBJ file and goes through the
// same loaders as user files, so `vkray render` with no arguments exercises the whole input path.
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/scene_loader.hpp"

namespace vkray {
namespace {

constexpr const char* default_scene_json = R"({
  "camera": {"from": [0.0, 1.8, 6.0], "to": [0.0, 0.7, 0.0], "up": [0, 1, 0], "fovy": 45},
  "image": {"width": 800, "height": 600},
  "spheres": [{"center": [-1.4, 0.9, 0.0], "radius": 0.9}],
  "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0]}],
  "meshes": [
    {"positions": [[0.9, 0, 0.4], [2.1, 0, 0.4], [2.1, 0, 1.6], [0.9, 0, 1.6], [1.5, 1.3, 1.0]],
     "triangles": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 2, 1], [0, 3, 2]]},
    {"obj": "builtin-cube.obj",
     "transform": {"scale": 0.7, "rotate": {"axis": [0, 1, 0], "degrees": 30}, "translate": [0.4, 0.0, -1.6]}}
  ]
})";

// A unit cube on the ground, written the way many exporters do: quads and negative (relative)
// indices, so the triangulation and index resolution of the OBJ path are in every default render.
constexpr const char* builtin_cube_obj = R"(# vkray built-in cube
o cube
v -1 0 -1
v  1 0 -1
v  1 0  1
v -1 0  1
v -1 2 -1
v  1 2 -1
v  1 2  1
v -1 2  1
f -8 -7 -6 -5
f -4 -1 -2 -3
f -8 -4 -3 -7
f -7 -3 -2 -6
f -6 -2 -1 -5
f -5 -1 -4 -8
)";

}  // namespace

Scene default_scene() {
  return parse_scene(default_scene_json, "built-in scene", "", [](const std::filesystem::path& path) {
    Mesh cube = load_obj_text(builtin_cube_obj, "built-in " + path.string());
    cube.source = "built-in " + path.string();
    return std::vector<Mesh>{std::move(cube)};
  });
}

}  // namespace vkray
