#include "engine/scene.hpp"

#include <glm/geometric.hpp>

#include <string>

namespace vkray {

size_t Scene::triangle_count() const {
  size_t count = 0;
  for (const auto& mesh : meshes) count += mesh.triangles.size();
  return count;
}

size_t Scene::zero_area_triangle_count() const {
  size_t count = 0;
  for (const auto& mesh : meshes) {
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3& v0 = mesh.positions[corners[0]];
      count += glm::cross(mesh.positions[corners[1]] - v0, mesh.positions[corners[2]] - v0) == glm::dvec3(0.0);
    }
  }
  return count;
}

void check_image_size(uint32_t width, uint32_t height) {
  if (width < 1 || height < 1 || width > max_image_side || height > max_image_side ||
      uint64_t{width} * height > max_image_pixels) {
    throw InputError("image size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1x1 .. " + std::to_string(max_image_side) + " per side and " +
                     std::to_string(max_image_pixels) + " pixels");
  }
}

}  // namespace vkray
