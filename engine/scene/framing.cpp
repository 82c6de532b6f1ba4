#include "engine/scene/framing.hpp"

#include "engine/scene/obj_loader.hpp"
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
  if (finite_bounds(scene).empty()) throw InputError("nothing to frame: the scene has no mesh or sphere");
  const glm::dvec3 centre = scene_anchor(scene);
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
  scene.meshes.push_back(load_obj_file(path));
  if (scene.meshes[0].triangles.empty()) throw InputError(path.string() + ": no faces to render");
  // The same bound a scene file's meshes get (engine/scene/scene.hpp, max_coordinate).
  const auto& positions = scene.meshes[0].positions;
  for (size_t i = 0; i < positions.size(); ++i) {
    const glm::dvec3& p = positions[i];
    if (!(std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) <= max_coordinate)) {
      throw InputError(path.string() + ": vertex " + std::to_string(i + 1) +
                       " lies beyond the supported coordinate magnitude 1e15");
    }
  }
  scene.camera = frame_scene(scene, scene.width, scene.height);
  return scene;
}

}  // namespace vkray
