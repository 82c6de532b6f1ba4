#include "engine/scene/camera.hpp"

#include "engine/unit_vector.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace vkray {

glm::dvec2 pixel_uv(uint32_t i, uint32_t j, uint32_t width, uint32_t height) {
  const double shorter = std::min(width, height);
  return {(2.0 * (i + 0.5) - width) / shorter, (height - 2.0 * (j + 0.5)) / shorter};
}

glm::dvec3 CameraBasis::direction(glm::dvec2 uv) const {
  return glm::normalize(uv.x * right_step() + uv.y * up_step() + centre_direction());
}

std::optional<Projection> projection_from_name(std::string_view name) {
  for (const Projection projection : {Projection::perspective, Projection::orthographic, Projection::equirectangular}) {
    if (name == projection_name(projection)) return projection;
  }
  return std::nullopt;
}

const char* projection_name(Projection projection) {
  switch (projection) {
    case Projection::perspective: return "perspective";
    case Projection::orthographic: return "orthographic";
    case Projection::equirectangular: return "equirectangular";
  }
  return "?";
}

PixelRay pixel_ray(const Camera& camera, const CameraBasis& basis, uint32_t i, uint32_t j, uint32_t width, uint32_t height) {
  switch (camera.projection) {
    case Projection::perspective:
      break;
    case Projection::orthographic: {
      // The image plane's coordinates scaled so that its height, 2 H / min(W, H) of them, spans view_height.
      const glm::dvec2 uv = pixel_uv(i, j, width, height);
      const double world_per_unit = camera.view_height * std::min(width, height) / (2.0 * height);
      return {basis.origin + world_per_unit * (uv.x * basis.right + uv.y * basis.up), -basis.forward};
    }
    case Projection::equirectangular: {
      const double longitude = 2.0 * std::numbers::pi * ((i + 0.5) / width - 0.5);
      const double latitude = std::numbers::pi * (0.5 - (j + 0.5) / height);
      const glm::dvec3 direction = std::cos(latitude) * (std::sin(longitude) * basis.right - std::cos(longitude) * basis.forward) +
                                   std::sin(latitude) * basis.up;
      return {basis.origin, glm::normalize(direction)};
    }
  }
  return {basis.origin, basis.direction(pixel_uv(i, j, width, height))};
}

glm::dvec3 float32_ray_direction(const CameraBasis& camera, uint32_t i, uint32_t j, uint32_t width, uint32_t height) {
  const float shorter = static_cast<float>(std::min(width, height));
  const glm::vec2 uv = glm::vec2(static_cast<float>(2 * i + 1) - static_cast<float>(width),
                                 static_cast<float>(height) - static_cast<float>(2 * j + 1)) /
                       shorter;
  const glm::vec3 right(camera.right_step()), up(camera.up_step()), forward_scaled(camera.centre_direction());
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

// CameraBasis::step_scale for the basis's vectors.
double power_of_two_step_scale(const CameraBasis& basis) {
  const glm::dvec3 largest = glm::max(glm::max(glm::abs(basis.right_step()), glm::abs(basis.up_step())),
                                      glm::abs(basis.centre_direction()));
  int exponent = 0;
  std::frexp(std::max({largest.x, largest.y, largest.z}), &exponent);
  return std::ldexp(basis.step_scale, -exponent);
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
  if (!camera.intrinsics) {
    const double half_height = static_cast<double>(height) / std::min(width, height);
    const double half_fovy = camera.fovy_degrees * std::numbers::pi / 360.0;
    basis.plane_distance = half_height / std::tan(half_fovy);
    basis.step_scale = power_of_two_step_scale(basis);
    return basis;
  }
  // Pixel (i, j)'s centre has uv = (2 i + 1 - W, H - 2 j - 1) / S, S = min(W, H), and the pinhole
  // model sees it at (x, y) / z = ((i - cx) / fx, (j - cy) / fy) in its camera frame (right, -up,
  // -forward). Scaled by 2 fx / S: uv.x right + (uv.y fx / fy) up, shifted by
  // ((W - 1) / 2 - cx) 2 / S right and -((H - 1) / 2 - cy) 2 fx / (S fy) up, at distance 2 fx / S.
  // The centred square-pixel case (fx = fy, cx = (W - 1) / 2, cy = (H - 1) / 2) gives scale 1 and
  // shift 0 exactly, and the same plane as the fovy it stands for up to the distance's rounding.
  const PinholeIntrinsics& k = *camera.intrinsics;
  const double shorter = std::min(width, height);
  basis.plane_distance = 2.0 * k.fx / shorter;
  basis.scale = {1.0, k.fx / k.fy};
  basis.shift = {((width - 1.0) / 2.0 - k.cx) * 2.0 / shorter, -((height - 1.0) / 2.0 - k.cy) * 2.0 * k.fx / (shorter * k.fy)};
  basis.step_scale = power_of_two_step_scale(basis);
  return basis;
}

PinholeIntrinsics pinhole_intrinsics(const Camera& camera, uint32_t width, uint32_t height) {
  if (camera.intrinsics) return *camera.intrinsics;
  // A pixel is 2 / min(W, H) of the image plane at distance plane_distance: fx = plane_distance
  // min(W, H) / 2, which is H / (2 tan(fovy / 2)).
  const CameraBasis basis = make_camera_basis(camera, width, height);
  const double focal = basis.plane_distance * std::min(width, height) / 2.0;
  return {focal, focal, (width - 1.0) / 2.0, (height - 1.0) / 2.0};
}

Camera with_world_to_camera(Camera camera, const Matrix4& matrix, std::string& fault) {
  // How far R R^T may be from I: matrices written with float precision (1e-7) pass, a scale or
  // shear does not.
  constexpr double tolerance = 1e-6;
  fault.clear();
  if (matrix[3] != std::array<double, 4>{0.0, 0.0, 0.0, 1.0}) {
    fault = "the last row must be 0, 0, 0, 1";
    return camera;
  }
  glm::dvec3 rows[3];
  for (int r = 0; r < 3; ++r) rows[r] = {matrix[r][0], matrix[r][1], matrix[r][2]};
  double deviation = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) deviation = std::max(deviation, std::abs(glm::dot(rows[a], rows[b]) - (a == b ? 1.0 : 0.0)));
  }
  const double determinant = glm::dot(rows[0], glm::cross(rows[1], rows[2]));
  if (!(deviation <= tolerance) || !(determinant > 0.0)) {
    // The deviation in two digits, and only where it is over the tolerance: a mirror is exact.
    char off_by[32];
    std::snprintf(off_by, sizeof(off_by), "%.2g", deviation);
    fault = "the upper-left 3 x 3 part must be a rotation (R R^T = I within 1e-6, det R = 1): " +
            (deviation <= tolerance ? std::string("it mirrors (det R < 0)")
                                    : "R R^T is off by " + std::string(off_by) + (determinant > 0.0 ? "" : ", and it mirrors (det R < 0)"));
    return camera;
  }
  // p_camera = R p + t: the camera sits at -R^T t, looks along R's third row, and its up is -R's second.
  const glm::dvec3 t(matrix[0][3], matrix[1][3], matrix[2][3]);
  camera.from = -(t.x * rows[0] + t.y * rows[1] + t.z * rows[2]);
  camera.to = camera.from + rows[2];
  camera.up = -rows[1];
  return camera;
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
