#include "engine/scene/model_loader.hpp"

#include "engine/scene/gltf_loader.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/ply_loader.hpp"
#include "engine/scene/scene_loader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

namespace vkray {
namespace {

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

bool is_model_extension(std::string_view lower_extension) {
  return std::any_of(model_kinds.begin(), model_kinds.end(), [&](const ModelKind& kind) { return lower_extension == kind.extension; });
}

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

std::string model_extension_list() {
  std::string list;
  for (size_t i = 0; i < model_kinds.size(); ++i) {
    list += (i == 0 ? "" : i + 1 == model_kinds.size() ? " or " : ", ") + std::string(model_kinds[i].extension);
  }
  return list;
}

void check_mesh_values(const Mesh& mesh, size_t first_vertex) {
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const glm::dvec3& p = mesh.positions[i];
    if (!within_coordinate_bound(p)) {
      throw InputError(mesh.source + ": vertex " + std::to_string(i + first_vertex) +
                       (finite(p) ? " lies beyond the supported coordinate magnitude 1e15" : " is not finite"));
    }
  }
  for (size_t i = 0; i < mesh.normals.size(); ++i) {
    if (!finite(mesh.normals[i])) throw InputError(mesh.source + ": vertex normal " + std::to_string(i + first_vertex) + " is not finite");
  }
  for (size_t i = 0; i < mesh.texcoords.size(); ++i) {
    const glm::dvec2& uv = mesh.texcoords[i];
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
      throw InputError(mesh.source + ": texture coordinate " + std::to_string(i + first_vertex) + " is not finite");
    }
  }
}

Model read_model_bytes(std::string_view bytes, std::string_view extension, const std::string& name,
                       const std::filesystem::path& folder) {
  Model model;
  if (extension == ".ply") {
    model.meshes.push_back(read_ply(bytes, name));
    model.meshes[0].source = name;
    check_mesh_values(model.meshes[0], 0);  // its normals and texture coordinates (read_ply checks positions where it reads them)
  } else if (extension == ".gltf" || extension == ".glb") {
    model = read_gltf(bytes, extension == ".glb", folder, name);
  } else {
    model.meshes.push_back(load_obj_text(bytes, name));
    model.meshes[0].source = name;
    check_mesh_values(model.meshes[0], 1);
  }
  return model;
}

Model load_model(const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::string extension = lower_extension(path);
  if (extension == ".obj") {  // read line by line, never whole (text_lines.hpp)
    Model model;
    model.meshes.push_back(load_obj_file(path));
    model.meshes[0].source = name;
    check_mesh_values(model.meshes[0], 1);
    return model;
  }
  return read_model_bytes(read_input_file(path, "model file"), extension, name, path.parent_path());
}

double fovy_degrees_from_vertical(double yfov_degrees, uint32_t width, uint32_t height) {
  if (width >= height) return yfov_degrees;
  const double half = 0.5 * yfov_degrees * std::numbers::pi / 180.0;
  return 2.0 * std::atan(std::tan(half) * width / height) * 180.0 / std::numbers::pi;
}

}  // namespace vkray
