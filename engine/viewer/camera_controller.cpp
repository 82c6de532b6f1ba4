#include "engine/viewer/camera_controller.hpp"

#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>

namespace vkray {
namespace {

// Any unit vector perpendicular to the unit vector `axis`.
glm::dvec3 perpendicular(const glm::dvec3& axis) {
  const glm::dvec3 other = std::abs(axis.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  return glm::normalize(glm::cross(axis, other));
}

// Shortest text that reads back as the same double.
std::string number(double value) {
  char text[32];
  const auto result = std::to_chars(std::begin(text), std::end(text), value);
  return std::string(text, result.ptr);
}

std::string vector_json(const glm::dvec3& v) {
  return "[" + number(v.x) + ", " + number(v.y) + ", " + number(v.z) + "]";
}

}  // namespace

CameraController::CameraController(const Camera& home) : home_(home), camera_(home) {}

void CameraController::set_home(const Camera& home) {
  const bool moved = camera_.from != home_.from || camera_.to != home_.to || camera_.up != home_.up ||
                     camera_.fovy_degrees != home_.fovy_degrees;
  home_ = home;
  if (!moved) camera_ = home_;
}

void CameraController::orbit(double azimuth, double elevation) {
  // Spherical coordinates of from - to around the up axis, with a frame (east, north) of the
  // plane perpendicular to it. The polar angle comes from atan2, accurate at the poles too.
  const glm::dvec3 axis = unit_vector(home_.up);
  const glm::dvec3 offset = camera_.from - camera_.to;
  const double distance = glm::length(offset);
  const glm::dvec3 east = perpendicular(axis);
  const glm::dvec3 north = glm::cross(axis, east);
  const double along = glm::dot(offset, axis);
  const glm::dvec3 across = offset - along * axis;
  const double across_length = glm::length(across);
  const double polar = std::atan2(across_length, along);
  // On the axis itself the azimuth is undefined: the one that keeps the screen's up direction
  // (the camera sits on the side opposite to it) avoids a spin.
  const glm::dvec3 toward = across_length > 0.0 ? across : -make_camera_basis(camera_, 1, 1).up;
  const double current_azimuth = std::atan2(glm::dot(toward, north), glm::dot(toward, east));
  const double new_polar = std::clamp(polar - elevation, min_polar, std::numbers::pi - min_polar);
  const double new_azimuth = current_azimuth + azimuth;
  const glm::dvec3 direction = std::sin(new_polar) * (std::cos(new_azimuth) * east + std::sin(new_azimuth) * north) +
                               std::cos(new_polar) * axis;
  camera_.from = camera_.to + distance * direction;
  camera_.up = axis;
}

void CameraController::pan(double du, double dv, uint32_t width, uint32_t height) {
  const CameraBasis basis = make_camera_basis(camera_, width, height);
  // A point at distance D ahead moves D / plane_distance world units per image-plane unit.
  const double scale = glm::length(camera_.from - camera_.to) / basis.plane_distance;
  const glm::dvec3 shift = -scale * (du * basis.right + dv * basis.up);
  camera_.from += shift;
  camera_.to += shift;
}

void CameraController::zoom(double steps) {
  camera_.from = camera_.to + std::pow(zoom_factor, steps) * (camera_.from - camera_.to);
}

void CameraController::fly(double right, double up, double ahead) {
  const CameraBasis basis = make_camera_basis(camera_, 1, 1);
  const double distance = glm::length(camera_.from - camera_.to);
  const glm::dvec3 shift = distance * (right * basis.right + up * basis.up - ahead * basis.forward);
  camera_.from += shift;
  camera_.to += shift;
}

std::string CameraController::json() const {
  return "\"camera\": {\"from\": " + vector_json(camera_.from) + ", \"to\": " + vector_json(camera_.to) +
         ", \"up\": " + vector_json(camera_.up) + ", \"fovy\": " + number(camera_.fovy_degrees) + "}";
}

}  // namespace vkray
