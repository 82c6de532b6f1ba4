#include "engine/scene/camera_description.hpp"

namespace vkray {
namespace {

nlohmann::ordered_json vector_json(const glm::dvec3& v) { return nlohmann::ordered_json::array({v.x, v.y, v.z}); }

}  // namespace

nlohmann::ordered_json camera_description(const Camera& camera, uint32_t width, uint32_t height) {
  nlohmann::ordered_json description;
  description["camera"] = nlohmann::ordered_json{{"from", vector_json(camera.from)},
                                                 {"to", vector_json(camera.to)},
                                                 {"up", vector_json(camera.up)}};
  const PinholeIntrinsics intrinsics = pinhole_intrinsics(camera, width, height);
  if (camera.projection != Projection::perspective) {
    description["camera"]["projection"] = projection_name(camera.projection);
    if (camera.projection == Projection::orthographic) description["camera"]["view_height"] = camera.view_height;
    description["world_to_camera"] = world_to_camera(camera, width, height);
    return description;  // no pinhole model: no intrinsics
  }
  if (camera.intrinsics) {
    description["camera"]["intrinsics"] =
        nlohmann::ordered_json{{"fx", intrinsics.fx}, {"fy", intrinsics.fy}, {"cx", intrinsics.cx}, {"cy", intrinsics.cy}};
  } else {
    description["camera"]["fovy"] = camera.fovy_degrees;
  }
  description["intrinsics"] =
      nlohmann::ordered_json{{"fx", intrinsics.fx}, {"fy", intrinsics.fy}, {"cx", intrinsics.cx}, {"cy", intrinsics.cy}};
  description["world_to_camera"] = world_to_camera(camera, width, height);
  return description;
}

}  // namespace vkray
