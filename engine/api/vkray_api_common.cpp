// The checks and conversions every call of the C API makes (vkray_api_common.hpp), and the calls that
// describe the library: its version, its last error, its outputs and traversals.
#include "engine/api/vkray_api_common.hpp"

#include "engine/render/search.hpp"
#include "engine/scene/scene_loader.hpp"

#include <glm/gtc/type_ptr.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>

#ifndef VKRAY_VERSION
#error "VKRAY_VERSION comes from CMake"
#endif

using namespace vkray;

namespace vkray::api {

thread_local std::string last_error;

void require(const void* pointer, const char* what) {
  if (!pointer) throw InputError(std::string(what) + ": NULL");
}

void require_unfinished(const vkray_scene& scene, const char* call) {
  if (scene.finished) {
    throw InputError(std::string(call) + ": the scene is finished (vkray_scene_finish, or loaded): it is read-only; "
                     "build another with vkray_scene_new");
  }
}

std::optional<uint32_t> size_or_default(uint32_t given, const char* what) {
  if (given == 0) return std::nullopt;
  if (given > max_image_side) {
    throw InputError(std::string(what) + ": must be in 1 .. " + std::to_string(max_image_side) + ", got " + std::to_string(given));
  }
  return given;
}

const OutputInfo& output_named(const char* name, bool rays) {
  const char* what = rays ? "outputs" : "aovs";
  require(name, what);
  const std::string_view given(name);
  const auto aov = aov_from_name(rays && given == "t" ? "depth" : given);
  if (!aov) throw InputError(std::string(what) + ": " + unknown_output_message(std::string(given)));
  const OutputInfo& output = output_info(*aov);
  if (rays && (output.source == OutputSource::camera && output.aov != Aov::position)) {
    throw InputError(std::string("outputs: '") + name + "' belongs to a camera's image; given rays have t, normal, primitive-id, mesh-id, "
                     "instance-id, position, barycentric, front-facing, shading-normal and texcoord");
  }
  if (rays && (output.aov == Aov::uv || output.aov == Aov::depth) && given != "t") {
    throw InputError(std::string("outputs: '") + name + "' belongs to a camera's image; a given ray's distance is 't'");
  }
  return output;
}

Camera camera_over(const char* camera_json, const Camera& base) {
  return camera_json ? parse_camera_override(camera_json, "camera", base) : base;
}

nlohmann::json timings_json(const RenderTimings& t, bool constructor) {
  nlohmann::json json;
  if (constructor) {
    json["upload_ms"] = t.upload_ms;
    json["bvh_build_ms"] = t.bvh_build_ms;
    json["pipeline_ms"] = t.pipeline_ms;  // after the upload (one made beside it is in upload_ms)
    return json;
  }
  json["pipeline_ms"] = t.pipeline_ms;
  if (t.has_gpu_times) json["dispatch_gpu_ms"] = t.dispatch_gpu_ms;
  json["readback_ms"] = t.readback_ms;
  json["rays_ms"] = t.rays_ms;
  if (t.given_walk != GivenRayWalk::none) {
    json["rays_walk"] = given_ray_walk_name(t.given_walk);
    json["rays_in_place"] = t.rays_in_place;
    if (t.order_gpu_ms > 0.0) json["order_gpu_ms"] = t.order_gpu_ms;
  }
  json["dispatches"] = t.tiles;
  json["cpu_finished_rays"] = t.unfinished_rays;
  if (t.scene_update_ms > 0.0) {  // set_vertices
    json["scene_update_ms"] = t.scene_update_ms;
    json["tree_refitted"] = t.tree_refitted;
    json["refit_mesh_alone"] = t.refit_mesh_alone;
    json["bvh_build_ms"] = t.bvh_build_ms;
  }
  return json;
}

glm::dmat4 affine_matrix(const double* rows, const std::string& path) {
  const std::string affine = path + ": expected a 4 x 4 affine matrix of finite numbers (last row 0, 0, 0, 1)";
  if (!std::all_of(rows, rows + 16, [](double v) { return std::isfinite(v); })) throw InputError(affine);
  if (rows[12] != 0.0 || rows[13] != 0.0 || rows[14] != 0.0 || rows[15] != 1.0) throw InputError(affine);
  return glm::transpose(glm::make_mat4(rows));
}

Mask object_mask_argument(uint32_t mask) {
  if (mask > every_mask_bit) throw InputError("mask: " + std::to_string(mask) + " is no mask of 8 bits (0..255)");
  return static_cast<Mask>(mask);
}

void use_ray_mask(vkray_renderer& renderer, uint32_t mask) {
  if (mask == 0 || mask > every_mask_bit) {
    throw InputError("mask: " + std::to_string(mask) + " is no ray mask (1..255; 0 would hit nothing)");
  }
  const auto ray_mask = static_cast<Mask>(mask);
  if (renderer.renderer) {
    renderer.renderer->set_ray_mask(ray_mask);
  } else if (ray_mask != renderer.ray_mask) {
    renderer.reference = std::make_unique<ReferenceScene>(renderer.scene, ray_mask);
  }
  renderer.ray_mask = ray_mask;
}

}  // namespace vkray::api

extern "C" {

uint32_t vkray_api_version(void) { return VKRAY_API_VERSION; }

const char* vkray_version(void) { return VKRAY_VERSION; }

const char* vkray_last_error(void) { return vkray::api::last_error.c_str(); }

int vkray_output(uint32_t index, vkray_output_info* info) {
  const auto all = outputs();
  if (index >= all.size() || !info) return 0;
  const OutputInfo& output = all[index];
  info->name = output.name;
  info->description = output.description;
  info->components = output.components;
  info->is_integer = output.integer ? 1 : 0;
  for (size_t c = 0; c < 3; ++c) info->channels[c] = c < output.components ? output.channels[c] : nullptr;
  return 1;
}

const char* vkray_traversal(uint32_t index) {
  const auto all = searches();
  return index < all.size() ? all[index].name : nullptr;
}

}  // extern "C"
