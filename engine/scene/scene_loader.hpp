// Scene files: JSON (format in docs/scene-format.md) parsed with nlohmann::json and checked strictly. Every
// error names the file and the JSON path of the offending value, e.g. "a.json: spheres[2].radius:
// must be > 0, got -1".
#pragma once

#include "engine/scene/scene.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// Loads the meshes of the model file a mesh entry names ("model", or "obj", its older name); the path
// is already resolved against the scene's folder.
using ModelFileLoader = std::function<std::vector<Mesh>(const std::filesystem::path&)>;

Scene load_scene_file(const std::filesystem::path& path);

// Throws InputError unless `path` is a regular file: "<path>: no such <what>" or "<path>: is not a
// regular file".
void check_input_file(const std::filesystem::path& path, const std::string& what);

// The whole of an input file, `what` naming it in messages ("scene file": "a.json: no such scene
// file"). Throws InputError.
std::string read_input_file(const std::filesystem::path& path, const std::string& what);

// Throws InputError naming the line and column of the first NUL byte in JSON `text`: nlohmann's
// parser takes a NUL for the end of the text, so what follows would be dropped unread. `text` starts
// on line `first_line` of the file `name` (a line of JSON Lines starts further down).
void refuse_nul_bytes(std::string_view text, const std::string& name, size_t first_line = 1);

// Throws InputError "<name>:<line>:<column>: invalid JSON: <reason>" where `text` is no JSON (a NUL
// byte included), saying so where the reason is a NaN or Infinity, which JSON has not.
void refuse_invalid_json(std::string_view text, const std::string& name, size_t first_line = 1);

// Parses scene JSON held in memory. `name` stands for the file in messages; relative model paths
// resolve against `base_dir` and load through `load_model`.
Scene parse_scene(std::string_view json_text, const std::string& name, const std::filesystem::path& base_dir,
                  const ModelFileLoader& load_model);

// A camera object in the scene-file form whose keys are all optional ({"from": [0, 1, 5]}): each
// replaces that part of `base`, checked as the scene file checks it. `name` stands for the source in
// messages ("--camera"). Throws InputError.
Camera parse_camera_override(std::string_view json_text, const std::string& name, const Camera& base);

// A whole camera object in the scene-file form ("from" and "to" required), as a views file holds
// them. `name` stands for the source in messages ("views.jsonl:57"). With `poses`, the object may
// also hold "instances": [{"instance": k, "transform": {the scene file's transform object}}, ...],
// instances placed for this view alone, added to `poses`. Throws InputError.
Camera parse_camera_object(std::string_view json_text, const std::string& name, InstancePoses* poses = nullptr);

// The built-in scene: a camera, a sphere, a ground plane, a handcrafted triangle mesh and
// a mesh that goes through the OBJ loader (from an OBJ text compiled into the binary).
Scene default_scene();

}  // namespace vkray
