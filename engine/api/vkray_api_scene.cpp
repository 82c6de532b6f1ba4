// The C API's scenes: loaded, or built from arrays and finished (checked), then read-only.
#include "engine/api/vkray_api_common.hpp"

#include "engine/scene/camera_description.hpp"
#include "engine/scene/framing.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/scene/scene_or_model.hpp"

#include <cmath>
#include <cstring>

using namespace vkray;
using namespace vkray::api;

namespace {

// vkray_scene_describe's text: each thread's own, valid until its next call (vkray.h).
thread_local std::string returned_description;

}  // namespace

extern "C" {

vkray_status vkray_scene_load(const char* path, uint32_t width, uint32_t height, const char* view, const double* view_direction,
                              vkray_scene** scene) {
  return guarded([&] {
    require(path, "path");
    require(scene, "scene");
    *scene = nullptr;
    std::optional<FramingView> side;
    if (view) {
      side = framing_view_from_name(view);
      if (!side) throw InputError("view: unknown side '" + std::string(view) + "' (" + framing_view_names + ")");
    } else if (view_direction) {
      const glm::dvec3 direction(view_direction[0], view_direction[1], view_direction[2]);
      if (direction == glm::dvec3(0.0) || !std::isfinite(glm::length(direction))) {
        throw InputError("view: the direction from the centre to the eye must be finite and not 0");
      }
      side = FramingView{direction, {0.0, 1.0, 0.0}};
    }
    auto made = std::make_unique<vkray_scene>();
    made->scene = load_scene_or_model(path, size_or_default(width, "width"), size_or_default(height, "height"));
    if (side) made->scene.camera = frame_scene(made->scene, made->scene.width, made->scene.height, *side);
    made->camera_given = made->finished = true;
    *scene = made.release();
  });
}

vkray_status vkray_scene_new(uint32_t width, uint32_t height, vkray_scene** scene) {
  return guarded([&] {
    require(scene, "scene");
    *scene = nullptr;
    auto made = std::make_unique<vkray_scene>();
    made->scene.width = width;
    made->scene.height = height;
    *scene = made.release();
  });
}

vkray_status vkray_scene_add_mesh(vkray_scene* scene, const double* vertices, uint64_t vertex_count, const void* triangles,
                                  int triangles_unsigned, uint64_t triangle_count, const double* transform) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_mesh");
    const std::string path = "meshes[" + std::to_string(scene->scene.meshes.size()) + "]";
    if (vertex_count > 0) require(vertices, (path + ".vertices").c_str());
    if (triangle_count > 0) require(triangles, (path + ".triangles").c_str());
    Mesh mesh;
    mesh.source = path;
    mesh.positions.reserve(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) {
      mesh.positions.push_back(vec3_at(vertices, v, 3));
      check_coordinates(mesh.positions.back(), path + ".vertices[" + std::to_string(v) + "]");
    }
    mesh.triangles.reserve(triangle_count);
    for (size_t t = 0; t < triangle_count; ++t) {
      std::array<uint32_t, 3> triangle{};
      for (size_t c = 0; c < 3; ++c) {
        // Signed and unsigned indices each in their own width: an unsigned index past 2^63 must not wrap.
        const bool in_range = triangles_unsigned ? static_cast<const uint64_t*>(triangles)[3 * t + c] < vertex_count
                                                 : static_cast<const int64_t*>(triangles)[3 * t + c] >= 0 &&
                                                       static_cast<uint64_t>(static_cast<const int64_t*>(triangles)[3 * t + c]) < vertex_count;
        if (!in_range) {
          const std::string index = triangles_unsigned ? std::to_string(static_cast<const uint64_t*>(triangles)[3 * t + c])
                                                       : std::to_string(static_cast<const int64_t*>(triangles)[3 * t + c]);
          throw InputError(path + ".triangles[" + std::to_string(t) + "][" + std::to_string(c) + "]: vertex index " + index +
                           " is out of range (the mesh has " + std::to_string(vertex_count) + " vertices)");
        }
        triangle[c] = static_cast<uint32_t>(triangles_unsigned ? static_cast<const uint64_t*>(triangles)[3 * t + c]
                                                               : static_cast<uint64_t>(static_cast<const int64_t*>(triangles)[3 * t + c]));
      }
      mesh.triangles.push_back(triangle);
    }
    if (transform) {
      const glm::dmat4 affine = affine_matrix(transform, path + ".transform");
      for (glm::dvec3& p : mesh.positions) p = glm::dvec3(affine * glm::dvec4(p, 1.0));
    }
    scene->scene.meshes.push_back(std::move(mesh));
  });
}

vkray_status vkray_scene_add_instance(vkray_scene* scene, uint32_t mesh, const double* transform, uint32_t mask) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_instance");
    const std::string path = "instances[" + std::to_string(scene->scene.instances.size()) + "]";
    if (mesh >= scene->scene.meshes.size()) {
      throw InputError(path + ".mesh: " + std::to_string(mesh) + " is not a mesh_id of the " +
                       std::to_string(scene->scene.meshes.size()) + " meshes added so far");
    }
    Instance instance;
    instance.mesh = mesh;
    if (transform) place_by(instance, affine_matrix(transform, path + ".transform"));
    instance.mask = object_mask_argument(mask);
    scene->scene.meshes[mesh].instanced = true;  // drawn only where instances place it
    scene->scene.instances.push_back(instance);
  });
}

vkray_status vkray_scene_add_spheres(vkray_scene* scene, const double* spheres, uint64_t count) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_spheres");
    if (count > 0) require(spheres, "spheres");
    for (size_t k = 0; k < count; ++k) scene->scene.spheres.push_back({vec3_at(spheres, k, 4), spheres[4 * k + 3]});
  });
}

vkray_status vkray_scene_add_planes(vkray_scene* scene, const double* planes, uint64_t count) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_planes");
    if (count > 0) require(planes, "planes");
    for (size_t k = 0; k < count; ++k) scene->scene.planes.push_back({vec3_at(planes, k, 6), vec3_at(planes, k, 6, 3)});
  });
}

vkray_status vkray_scene_set_mask(vkray_scene* scene, uint32_t object, uint32_t mask) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_set_mask");
    set_object_mask(scene->scene, object, object_mask_argument(mask));
  });
}

vkray_status vkray_scene_set_camera(vkray_scene* scene, const char* camera_json) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_set_camera");
    require(camera_json, "camera");
    scene->scene.camera = parse_camera_override(camera_json, "camera", Camera{});
    scene->camera_given = true;
  });
}

vkray_status vkray_scene_finish(vkray_scene* scene) {
  return guarded([&] {
    require(scene, "scene");
    if (scene->finished) return;
    check_scene(scene->scene);
    if (!scene->camera_given) scene->scene.camera = frame_scene(scene->scene, scene->scene.width, scene->scene.height);
    scene->finished = true;
  });
}

const char* vkray_scene_describe(vkray_scene* scene) {
  if (!scene) return "";
  const Scene& s = scene->scene;
  nlohmann::ordered_json json;
  json["width"] = s.width;
  json["height"] = s.height;
  json["meshes"] = s.meshes.size();
  json["triangles"] = s.triangle_count();
  json["spheres"] = s.spheres.size();
  json["planes"] = s.planes.size();
  json["camera"] = camera_description(s.camera, s.width, s.height)["camera"];
  json["object_names"] = object_names(s);
  std::vector<uint32_t> masks;
  for (uint32_t object = 0; object < s.object_count(); ++object) masks.push_back(object_mask(s, object));
  json["masks"] = masks;
  returned_description = json.dump();
  return returned_description.c_str();
}

vkray_status vkray_scene_mesh(const vkray_scene* scene, uint32_t mesh, double* positions, uint32_t* triangles,
                              uint64_t* vertex_count, uint64_t* triangle_count) {
  return guarded([&] {
    require(scene, "scene");
    if (!scene->finished) throw InputError("scene: not finished (vkray_scene_finish)");
    const std::vector<Mesh>& meshes = scene->scene.meshes;
    if (mesh >= meshes.size()) {
      throw InputError("mesh " + std::to_string(mesh) + ": the scene has " + std::to_string(meshes.size()) + " meshes");
    }
    const Mesh& given = meshes[mesh];
    if (vertex_count) *vertex_count = given.positions.size();
    if (triangle_count) *triangle_count = given.triangles.size();
    static_assert(sizeof(glm::dvec3) == 3 * sizeof(double) && sizeof(given.triangles[0]) == 3 * sizeof(uint32_t));
    if (positions) std::memcpy(positions, given.positions.data(), given.positions.size() * sizeof(glm::dvec3));
    if (triangles) std::memcpy(triangles, given.triangles.data(), given.triangles.size() * sizeof(given.triangles[0]));
  });
}

void vkray_scene_free(vkray_scene* scene) { delete scene; }

}  // extern "C"
