// The viewer's camera moves, as plain math on a Camera in double precision: no window, no input
// device, so every move is unit-tested (tests/camera_controller_test.cpp).
#pragma once

#include "engine/scene/camera.hpp"

#include <string>

namespace vkray {

class CameraController {
 public:
  // `home` is the scene's camera: where reset() returns.
  explicit CameraController(const Camera& home);

  const Camera& camera() const { return camera_; }
  const Camera& home() const { return home_; }
  // A new scene camera (the scene file was reloaded); the view follows it unless it was moved.
  void set_home(const Camera& home);
  void reset() { camera_ = home_; }

  // Turns `from` around `to`: `azimuth` radians about the home camera's up axis, `elevation`
  // radians towards it. The angle from the up axis stays within [min_polar, pi - min_polar], so
  // orbiting over a pole stops short of it and the view never becomes parallel to `up`.
  void orbit(double azimuth, double elevation);
  // Moves `from` and `to` together in the image plane by (du, dv) image-plane units (the shorter
  // side of the image spans 2): the point at `to` moves by that much on screen.
  void pan(double du, double dv, uint32_t width, uint32_t height);
  // Moves `from` towards `to` (steps > 0) or away, by zoom_factor per step; `to` stays.
  void zoom(double steps);
  // Moves `from` and `to` together: `right`, `up` and `ahead` in units of the distance between
  // them, along the view's own axes.
  void fly(double right, double up, double ahead);

  // The current camera as a scene-file snippet: "camera": {"from": [...], "to": [...], ...}.
  std::string json() const;

  // Closest the view comes to the up axis when orbiting, in radians (about 0.06 degrees).
  static constexpr double min_polar = 1e-3;
  // Distance factor of one zoom step (a mouse-wheel notch): 10% closer.
  static constexpr double zoom_factor = 0.9;

 private:
  Camera home_;
  Camera camera_;
};

}  // namespace vkray
