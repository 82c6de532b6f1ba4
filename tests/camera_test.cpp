// The course's image-plane and camera model (engine/scene/camera.hpp) against hand-computed values.
#include "engine/scene/camera.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace vkray {
namespace {

constexpr double tight = 1e-15;

void expect_vec_near(const glm::dvec3& actual, const glm::dvec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_orthonormal_right_handed(const CameraBasis& basis) {
  EXPECT_NEAR(glm::length(basis.right), 1.0, tight);
  EXPECT_NEAR(glm::length(basis.up), 1.0, tight);
  EXPECT_NEAR(glm::length(basis.forward), 1.0, tight);
  EXPECT_NEAR(glm::dot(basis.right, basis.up), 0.0, tight);
  EXPECT_NEAR(glm::dot(basis.right, basis.forward), 0.0, tight);
  EXPECT_NEAR(glm::dot(basis.up, basis.forward), 0.0, tight);
  expect_vec_near(glm::cross(basis.right, basis.up), basis.forward, tight);
}

TEST(PixelUv, CentresOfALandscapeImage) {
  // 4x2: the shorter side (2 pixels) spans [-1, 1], so a pixel is 1 unit wide.
  EXPECT_EQ(pixel_uv(0, 0, 4, 2), glm::dvec2(-1.5, 0.5));
  EXPECT_EQ(pixel_uv(3, 0, 4, 2), glm::dvec2(1.5, 0.5));
  EXPECT_EQ(pixel_uv(1, 1, 4, 2), glm::dvec2(-0.5, -0.5));
}

TEST(PixelUv, CentresOfAPortraitImageAndOnePixel) {
  EXPECT_EQ(pixel_uv(0, 0, 2, 4), glm::dvec2(-0.5, 1.5));
  EXPECT_EQ(pixel_uv(1, 3, 2, 4), glm::dvec2(0.5, -1.5));
  EXPECT_EQ(pixel_uv(0, 0, 1, 1), glm::dvec2(0.0, 0.0));
}

// The course's debug check: the unit disk touches the two shorter borders whatever the aspect.
// The pixel edges (not centres) of the shorter side lie at exactly +-1.
TEST(PixelUv, UnitDiskTouchesTheShorterBorders) {
  for (auto [width, height] : {std::pair{640u, 480u}, std::pair{480u, 640u}, std::pair{101u, 37u}, std::pair{8u, 8u}}) {
    const double shorter = std::min(width, height);
    const glm::dvec2 half_pixel(1.0 / shorter, 1.0 / shorter);
    const glm::dvec2 top_left = pixel_uv(0, 0, width, height) + glm::dvec2(-half_pixel.x, half_pixel.y);
    const glm::dvec2 bottom_right = pixel_uv(width - 1, height - 1, width, height) + glm::dvec2(half_pixel.x, -half_pixel.y);
    EXPECT_DOUBLE_EQ(std::min(top_left.y, bottom_right.x), 1.0) << width << "x" << height;
    EXPECT_DOUBLE_EQ(std::max(-top_left.x, top_left.y), double(std::max(width, height)) / shorter);
    EXPECT_DOUBLE_EQ(top_left.y, -bottom_right.y);
    EXPECT_DOUBLE_EQ(-top_left.x, bottom_right.x);
  }
}

TEST(CameraBasis, CourseFrameLookingDownMinusZ) {
  const CameraBasis basis = make_camera_basis({{1, 2, 3}, {1, 2, -7}, {0, 1, 0}, 90}, 800, 600);
  expect_vec_near(basis.forward, {0, 0, 1}, tight);  // normalize(from - to)
  expect_vec_near(basis.right, {1, 0, 0}, tight);    // normalize(up x forward)
  expect_vec_near(basis.up, {0, 1, 0}, tight);       // forward x right
  EXPECT_NEAR(basis.plane_distance, 1.0, tight);     // sy = 1 for landscape, tan(45 deg) = 1
  expect_orthonormal_right_handed(basis);
}

TEST(CameraBasis, PlaneDistanceUsesTheHalfHeightInUv) {
  // Portrait: sy = H / min(W, H) = 2, so the plane distance doubles at the same fovy.
  const CameraBasis basis = make_camera_basis({{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60}, 300, 600);
  EXPECT_NEAR(basis.plane_distance, 2.0 / std::tan(std::numbers::pi / 6), 1e-14);
}

// fovy is the vertical field of view: the ray through the middle of the top border makes an angle
// of fovy/2 with the view direction.
TEST(CameraBasis, TopBorderRayIsHalfFovyFromTheAxis) {
  for (double fovy : {1.0, 45.0, 90.0, 170.0}) {
    for (auto [width, height] : {std::pair{640u, 480u}, std::pair{480u, 640u}}) {
      const CameraBasis basis = make_camera_basis({{0, 0, 0}, {3, -1, 2}, {0, 1, 0}, fovy}, width, height);
      const double sy = double(height) / std::min(width, height);
      const glm::dvec3 top = basis.direction({0.0, sy});
      const double angle = std::acos(glm::dot(top, -basis.forward)) * 180 / std::numbers::pi;
      EXPECT_NEAR(angle, fovy / 2, 1e-10) << fovy << " " << width << "x" << height;
    }
  }
}

TEST(CameraBasis, CentreRayLooksAtTheTarget) {
  const Camera camera{{1, 5, -2}, {-3, 0.5, 4}, {0, 1, 0}, 50};
  const CameraBasis basis = make_camera_basis(camera, 33, 21);
  expect_vec_near(basis.direction(pixel_uv(16, 10, 33, 21)), glm::normalize(camera.to - camera.from), 1e-15);
  expect_orthonormal_right_handed(basis);
}

// up parallel to the view direction: the course formula gives 0/0; the fallback up is the axis
// least aligned with the view (+z for a vertical view), so the frame stays orthonormal and finite.
TEST(CameraBasis, LookingStraightDownOrUpFallsBackToAnotherUp) {
  const CameraBasis down = make_camera_basis({{0, 10, 0}, {0, 0, 0}, {0, 1, 0}, 60}, 64, 48);
  expect_orthonormal_right_handed(down);
  expect_vec_near(down.forward, {0, 1, 0}, tight);
  expect_vec_near(down.up, {0, 0, 1}, tight);
  const CameraBasis up = make_camera_basis({{0, 0, 0}, {0, 5, 0}, {0, 2, 0}, 60}, 64, 48);
  expect_orthonormal_right_handed(up);
  expect_vec_near(up.forward, {0, -1, 0}, tight);
  expect_vec_near(up.up, {0, 0, 1}, tight);
  // Nearly but not exactly parallel keeps the course formula.
  const CameraBasis tilted = make_camera_basis({{0, 10, 0}, {1e-6, 0, 0}, {0, 1, 0}, 60}, 64, 48);
  expect_orthonormal_right_handed(tilted);
  EXPECT_NEAR(std::abs(tilted.up.x), 1.0, 1e-9);
}

// View directions and up vectors far outside [1e-154, 1e154] in length still give a finite frame.
TEST(CameraBasis, ExtremeMagnitudes) {
  expect_orthonormal_right_handed(make_camera_basis({{0, 0, 1e-170}, {0, 0, 0}, {0, 1e-300, 0}, 45}, 8, 8));
  expect_orthonormal_right_handed(make_camera_basis({{1e14, 0, 0}, {-1e14, 0, 1}, {0, 1e200, 0}, 45}, 8, 8));
}

}  // namespace
}  // namespace vkray
