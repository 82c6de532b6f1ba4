#include "engine/scene/camera.hpp"

#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vkray {

glm::dvec2 pixel_uv(uint32_t i, uint32_t j, uint32_t width, uint32_t height) {
  const double shorter = std::min(width, height);
  return {(2.0 * (i + 0.5) - width) / shorter, (height - 2.0 * (j + 0.5)) / shorter};
}

glm::dvec3 CameraBasis::direction(glm::dvec2 uv) const {
  return glm::normalize(uv.x * right + uv.y * up - plane_distance * forward);
}

glm::dvec3 float32_ray_direction(const CameraBasis& camera, uint32_t i, uint32_t j, uint32_t width, uint32_t height) {
  const float shorter = static_cast<float>(std::min(width, height));
  const glm::vec2 uv = glm::vec2(static_cast<float>(2 * i + 1) - static_cast<float>(width),
                                 static_cast<float>(height) - static_cast<float>(2 * j + 1)) /
                       shorter;
  const glm::vec3 right(camera.right), up(camera.up), forward_scaled(-camera.plane_distance * camera.forward);
  return glm::dvec3(glm::normalize(uv.x * right + uv.y * up + forward_scaled));
}

namespace {

// Below this sine of the angle between `up` and the view direction the two are taken as parallel.
// normalize(up x forward) is still accurate to ~1e-7 at this angle in double, far better than the
// float32 the GPU receives, so the fallback only replaces frames that are truly undefined.
constexpr double parallel_sine = 1e-9;

glm::dvec3 least_aligned_axis(const glm::dvec3& direction) {
  const glm::dvec3 axes[] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  const glm::dvec3* best = &axes[0];
  for (const auto& axis : axes) {
    if (std::abs(glm::dot(axis, direction)) < std::abs(glm::dot(*best, direction))) best = &axis;
  }
  return *best;
}

}  // namespace

CameraBasis make_camera_basis(const Camera& camera, uint32_t width, uint32_t height) {
  CameraBasis basis;
  basis.origin = camera.from;
  basis.forward = unit_vector(camera.from - camera.to);
  glm::dvec3 side = glm::cross(unit_vector(camera.up), basis.forward);
  if (glm::length(side) <= parallel_sine) side = glm::cross(least_aligned_axis(basis.forward), basis.forward);
  basis.right = glm::normalize(side);
  basis.up = glm::cross(basis.forward, basis.right);
  const double half_height = static_cast<double>(height) / std::min(width, height);
  const double half_fovy = camera.fovy_degrees * std::numbers::pi / 360.0;
  basis.plane_distance = half_height / std::tan(half_fovy);
  return basis;
}

PinholeIntrinsics pinhole_intrinsics(const Camera& camera, uint32_t width, uint32_t height) {
  // A pixel is 2 / min(W, H) of the image plane at distance plane_distance: fx = plane_distance
  // min(W, H) / 2, which is H / (2 tan(fovy / 2)).
  const CameraBasis basis = make_camera_basis(camera, width, height);
  const double focal = basis.plane_distance * std::min(width, height) / 2.0;
  return {focal, focal, (width - 1.0) / 2.0, (height - 1.0) / 2.0};
}

Matrix4 world_to_camera(const Camera& camera, uint32_t width, uint32_t height) {
  const CameraBasis basis = make_camera_basis(camera, width, height);
  const glm::dvec3 rows[3] = {basis.right, -basis.up, -basis.forward};
  Matrix4 matrix{};
  for (int r = 0; r < 3; ++r) matrix[r] = {rows[r].x, rows[r].y, rows[r].z, -glm::dot(rows[r], basis.origin)};
  matrix[3] = {0.0, 0.0, 0.0, 1.0};
  return matrix;
}

Matrix4 world_to_openexr_camera(const Camera& camera, uint32_t width, uint32_t height) {
  Matrix4 matrix = world_to_camera(camera, width, height);
  for (double& entry : matrix[1]) entry = -entry;  // y up, not down
  return matrix;
}

Matrix4 world_to_openexr_ndc(const Camera& camera, uint32_t width, uint32_t height) {
  // The pinhole model's (u + 0.5) / W = (fx x + (cx + 0.5) z) / (W z), and so for y, with (x, y, z)
  // its camera coordinates: P [R t] with P's rows giving X, Y, then Z = 1 and W = z.
  const PinholeIntrinsics k = pinhole_intrinsics(camera, width, height);
  const Matrix4 projection = {{{k.fx / width, 0.0, (k.cx + 0.5) / width, 0.0},
                               {0.0, k.fy / height, (k.cy + 0.5) / height, 0.0},
                               {0.0, 0.0, 0.0, 1.0},
                               {0.0, 0.0, 1.0, 0.0}}};
  const Matrix4 rigid = world_to_camera(camera, width, height);
  Matrix4 matrix{};
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      for (int k_index = 0; k_index < 4; ++k_index) matrix[r][c] += projection[r][k_index] * rigid[k_index][c];
    }
  }
  return matrix;
}

}  // namespace vkray
