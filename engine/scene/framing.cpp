#include "engine/scene/framing.hpp"

#include "engine/scene/model_loader.hpp"
#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace vkray {

std::optional<FramingView> framing_view_from_name(std::string_view name) {
  if (name == "front") return front_view;
  if (name == "back") return FramingView{{0.0, 0.25, -1.0}, {0.0, 1.0, 0.0}};
  if (name == "left") return FramingView{{-1.0, 0.25, 0.0}, {0.0, 1.0, 0.0}};
  if (name == "right") return FramingView{{1.0, 0.25, 0.0}, {0.0, 1.0, 0.0}};
  if (name == "top") return FramingView{{0.0, 1.0, 0.0}, {0.0, 0.0, -1.0}};
  if (name == "bottom") return FramingView{{0.0, -1.0, 0.0}, {0.0, 0.0, 1.0}};
  return std::nullopt;
}

Camera frame_scene(const Scene& scene, uint32_t width, uint32_t height, const FramingView& view) {
  if (finite_bounds(scene).empty()) {
    if (scene.planes.empty()) throw InputError("nothing to frame: the scene has no mesh, sphere or plane");
    // Planes alone have no extent to fit: the first is seen from one unit along its normal, looking
    // 14 degrees below its horizon (atan 1/4, within half the field of view: the plane and the sky
    // above it), so that a scene made only to cast rays at a ground plane needs no camera (issue 64).
    const Plane& plane = scene.planes.front();
    const glm::dvec3 normal = unit_vector(plane.normal);
    const glm::dvec3 across = unit_vector(std::abs(normal.y) < 0.9 ? glm::cross(normal, glm::dvec3(0.0, 1.0, 0.0))
                                                                    : glm::cross(normal, glm::dvec3(1.0, 0.0, 0.0)));
    const glm::dvec3 along = glm::cross(across, normal);
    return {plane.point + normal + 4.0 * along, plane.point, normal, framing_fovy_degrees};
  }
  const glm::dvec3 centre = scene_centre(scene);
  double radius = scene_radius(scene, centre);
  // A single point still needs a camera somewhere: one unit away.
  if (radius == 0.0) radius = 0.5;

  // Half the field of view across the shorter side: the vertical one, or the horizontal one of a
  // portrait image, tan(h) = tan(fovy / 2) * width / height. At distance r / sin(half) the sphere's
  // silhouette cone has exactly that half-angle.
  const double half_fovy = framing_fovy_degrees * std::numbers::pi / 360.0;
  const double half = width >= height ? half_fovy : std::atan(std::tan(half_fovy) * width / height);
  const double distance = radius / std::sin(half);
  return {centre + distance * unit_vector(view.from_direction), centre, view.up, framing_fovy_degrees};
}

Scene load_model_file(const std::filesystem::path& path) {
  Scene scene;
  scene.meshes = load_model(path).meshes;
  scene.camera = frame_scene(scene, scene.width, scene.height);
  return scene;
}

}  // namespace vkray
