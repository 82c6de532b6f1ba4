// The viewer's camera moves (engine/viewer/camera_controller.hpp), checked against the camera
// model's own projection: no window involved.
#include "engine/viewer/camera_controller.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>

namespace vkray {
namespace {

const Camera course_camera{{0, 1.8, 6}, {0, 0.7, 0}, {0, 1, 0}, 45};

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Image-plane coordinates where `point` appears, through the camera model of engine/scene/camera.hpp.
glm::dvec2 project(const Camera& camera, const glm::dvec3& point, uint32_t width, uint32_t height) {
  const CameraBasis basis = make_camera_basis(camera, width, height);
  const glm::dvec3 offset = point - basis.origin;
  const double ahead = -glm::dot(offset, basis.forward);
  return glm::dvec2(glm::dot(offset, basis.right), glm::dot(offset, basis.up)) * (basis.plane_distance / ahead);
}

TEST(CameraController, OrbitKeepsTheTargetAndTheDistance) {
  CameraController controller(course_camera);
  controller.orbit(0.7, 0.3);
  EXPECT_EQ(controller.camera().to, course_camera.to);
  EXPECT_NEAR(glm::length(controller.camera().from - controller.camera().to),
              glm::length(course_camera.from - course_camera.to), 1e-12);
  EXPECT_GT(controller.camera().from.y, course_camera.from.y);  // elevation > 0 rises towards up
}

TEST(CameraController, OrbitOverThePolesNeverGivesNaN) {
  for (double step : {0.5, 3.0, 1e3, -1e3}) {
    CameraController controller(course_camera);
    for (int k = 0; k < 50; ++k) {
      controller.orbit(0.3, step);
      const Camera& camera = controller.camera();
      ASSERT_TRUE(finite(camera.from)) << step;
      const CameraBasis basis = make_camera_basis(camera, 64, 48);
      ASSERT_TRUE(finite(basis.right) && finite(basis.up) && finite(basis.forward)) << step;
      // Stopped short of the pole: the view is never parallel to up.
      const double polar = std::acos(glm::dot(glm::normalize(camera.from - camera.to), glm::dvec3(0, 1, 0)));
      EXPECT_GE(polar, CameraController::min_polar * 0.999);
      EXPECT_LE(polar, std::numbers::pi - CameraController::min_polar * 0.999);
    }
  }
}

TEST(CameraController, OrbitFromACameraLookingStraightDown) {
  // The scene file's camera may look along up itself (make_camera_basis then picks a fallback).
  CameraController controller({{0, 5, 0}, {0, 0, 0}, {0, 1, 0}, 60});
  controller.orbit(0.0, -0.2);
  EXPECT_TRUE(finite(controller.camera().from));
  EXPECT_NEAR(glm::length(controller.camera().from), 5.0, 1e-12);
  EXPECT_LT(controller.camera().from.y, 5.0);
}

TEST(CameraController, PanMovesTheTargetOnScreenByThePannedAmount) {
  for (auto [width, height] : {std::pair{640u, 480u}, std::pair{300u, 600u}}) {
    CameraController controller(course_camera);
    controller.pan(0.25, -0.1, width, height);
    const glm::dvec2 seen = project(controller.camera(), course_camera.to, width, height);
    EXPECT_NEAR(seen.x, 0.25, 1e-12);
    EXPECT_NEAR(seen.y, -0.1, 1e-12);
    EXPECT_NEAR(glm::length(controller.camera().from - controller.camera().to),
                glm::length(course_camera.from - course_camera.to), 1e-12);
  }
}

TEST(CameraController, ZoomScalesTheDistanceToTheTarget) {
  CameraController controller(course_camera);
  const double distance = glm::length(course_camera.from - course_camera.to);
  controller.zoom(3);
  EXPECT_EQ(controller.camera().to, course_camera.to);
  EXPECT_NEAR(glm::length(controller.camera().from - controller.camera().to), distance * std::pow(0.9, 3), 1e-12);
  controller.zoom(-3);
  EXPECT_NEAR(glm::length(controller.camera().from - course_camera.from), 0.0, 1e-12);
}

TEST(CameraController, FlyMovesEyeAndTargetTogetherAlongTheView) {
  CameraController controller(course_camera);
  const glm::dvec3 view = course_camera.to - course_camera.from;
  controller.fly(0, 0, 0.5);
  EXPECT_NEAR(glm::length(controller.camera().from - (course_camera.from + 0.5 * view)), 0.0, 1e-12);
  EXPECT_NEAR(glm::length(controller.camera().to - (course_camera.to + 0.5 * view)), 0.0, 1e-12);
  controller.fly(1, 0, 0);  // sideways, along +x for this camera
  EXPECT_NEAR(controller.camera().from.x, glm::length(view), 1e-12);
}

TEST(CameraController, ResetAndNewHome) {
  CameraController controller(course_camera);
  controller.orbit(1, 1);
  controller.reset();
  EXPECT_EQ(controller.camera().from, course_camera.from);
  Camera moved_home = course_camera;
  moved_home.from.z = 9;
  controller.set_home(moved_home);  // not moved by the user: follows the file
  EXPECT_EQ(controller.camera().from, moved_home.from);
  controller.zoom(1);
  const Camera user_view = controller.camera();
  controller.set_home(course_camera);  // moved: stays where the user put it
  EXPECT_EQ(controller.camera().from, user_view.from);
  controller.reset();
  EXPECT_EQ(controller.camera().from, course_camera.from);
}

TEST(CameraController, JsonIsASceneFileCameraThatReadsBackExactly) {
  CameraController controller(course_camera);
  controller.orbit(0.123, 0.456);
  const auto camera = nlohmann::json::parse("{" + controller.json() + "}").at("camera");
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(camera.at("from")[k].get<double>(), controller.camera().from[k]);
    EXPECT_EQ(camera.at("to")[k].get<double>(), controller.camera().to[k]);
    EXPECT_EQ(camera.at("up")[k].get<double>(), controller.camera().up[k]);
  }
  EXPECT_EQ(camera.at("fovy").get<double>(), 45.0);
}

}  // namespace
}  // namespace vkray
