// The course's image-plane and camera model, in double precision. The GPU receives the basis
// computed here (see RayGenParams) and only evaluates the final linear combination per pixel.
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace vkray {

// OpenCV's pinhole model: camera coordinates x right, y down, z along the view direction; pixel
// coordinates (u, v) from the centre of the top-left pixel, u right and v down. A world point p is
// at (x, y, z) = R p + t, seen at (u, v) = (fx x / z + cx, fy y / z + cy), and z is its planar depth.
struct PinholeIntrinsics {
  double fx, fy, cx, cy;
  bool operator==(const PinholeIntrinsics&) const = default;
};

// How a camera's pixels map to rays (docs/outputs.md, "Output contract"):
// - perspective: every ray from `from` through its pixel of the image plane (fovy or intrinsics);
// - orthographic: every ray along the view direction, from its pixel of the image plane through
//   `from`, which spans `view_height` world units vertically;
// - equirectangular: every ray from `from`, longitude across the image (the view direction at its
//   centre, 360 degrees in all, east to the right) and latitude down it (+90 at the top, towards
//   the camera's up): a depth panorama.
enum class Projection { perspective, orthographic, equirectangular };

struct Camera {
  glm::dvec3 from{0.0, 0.0, 0.0};
  glm::dvec3 to{0.0, 0.0, -1.0};
  glm::dvec3 up{0.0, 1.0, 0.0};
  double fovy_degrees = 60.0;
  // The image plane given in pixels instead of by fovy (vision code's cameras): any focal lengths
  // and principal point, for whatever image size is rendered.
  std::optional<PinholeIntrinsics> intrinsics = std::nullopt;
  Projection projection = Projection::perspective;
  double view_height = 0.0;  // orthographic: the image's height in world units (> 0)
};

// "perspective", "orthographic" or "equirectangular"; none for another name.
std::optional<Projection> projection_from_name(std::string_view name);
const char* projection_name(Projection projection);

// UV of the centre of pixel (i, j), j counted from the top row: origin at the image centre, the
// shorter side spans [-1, 1], +y up.
glm::dvec2 pixel_uv(uint32_t i, uint32_t j, uint32_t width, uint32_t height);

// Orthonormal camera frame and image plane for one image size. The ray through image-plane point uv
// runs along (uv.x scale.x + shift.x) right + (uv.y scale.y + shift.y) up - plane_distance forward:
// scale (1, 1) and shift 0 for a camera given by fovy; intrinsics stretch and shift the plane.
struct CameraBasis {
  glm::dvec3 origin;
  glm::dvec3 right;
  glm::dvec3 up;
  glm::dvec3 forward;     // normalize(from - to): the camera looks along -forward
  double plane_distance;  // sy / tan(fovy / 2), sy = half-height of the image in UV; 2 fx / min(W, H)
  glm::dvec2 scale{1.0, 1.0};
  glm::dvec2 shift{0.0, 0.0};

  // The three vectors the ray direction combines (the shader's: see RayGenParams): uv.x times the
  // first plus uv.y times the second plus the third, then normalized. Right, up and -plane_distance
  // forward for a camera given by fovy, all times step_scale().
  glm::dvec3 right_step() const { return step_scale * scale.x * right; }
  glm::dvec3 up_step() const { return step_scale * scale.y * up; }
  glm::dvec3 centre_direction() const { return step_scale * (shift.x * right + shift.y * up - plane_distance * forward); }
  // The power of two that brings the vectors' largest component into [0.5, 1) (make_camera_basis
  // sets it). The direction is normalized, so it changes only their range: a fovy of 1e-18 degrees
  // puts plane_distance near 1e20, whose square overflows float32 (every GPU ray NaN, every pixel a
  // miss). A power of two moves only the exponent: float32 rounds an ordinary camera's vectors to
  // the same rays as without it.
  double step_scale = 1.0;
  // Unit direction of the primary ray through image-plane point uv.
  glm::dvec3 direction(glm::dvec2 uv) const;
};

// The direction of pixel (i, j)'s ray as the float32 shader computes it (shaders/raycast.comp):
// uv, the basis and the sum rounded to float32, then normalized. Tracing it in double separates the
// error a float32 ray brings in from the error of the intersection arithmetic.
glm::dvec3 float32_ray_direction(const CameraBasis& camera, uint32_t i, uint32_t j, uint32_t width, uint32_t height);

// A pixel's primary ray in double, for every projection: its origin and unit direction.
struct PixelRay {
  glm::dvec3 origin;
  glm::dvec3 direction;
};
PixelRay pixel_ray(const Camera& camera, const CameraBasis& basis, uint32_t i, uint32_t j, uint32_t width, uint32_t height);

// Builds the course's frame: right = normalize(up x forward), up' = forward x right. When `up` is
// parallel to the view direction (looking straight up or down) that cross product vanishes; the
// frame then uses the coordinate axis least aligned with the view direction as `up` (ties: +z,
// then +x), so the image is well defined instead of NaN. With intrinsics, the plane is put where
// pixel (i, j)'s centre is seen at (u, v) = (i, j) of the pinhole model.
CameraBasis make_camera_basis(const Camera& camera, uint32_t width, uint32_t height);

// The camera as OpenCV's pinhole model describes it (PinholeIntrinsics): its own intrinsics where
// it has them; for fovy and vkray's image plane (docs/outputs.md, "Output contract") fx = fy =
// H / (2 tan(fovy / 2)), cx = (W - 1) / 2, cy = (H - 1) / 2.
PinholeIntrinsics pinhole_intrinsics(const Camera& camera, uint32_t width, uint32_t height);

// A 4x4 matrix by rows, for column vectors (p' = M p).
using Matrix4 = std::array<std::array<double, 4>, 4>;

// [R t; 0 0 0 1] of the pinhole model above, by rows: rows of R are right, -up and -forward of the
// camera's basis, t = -R from.
Matrix4 world_to_camera(const Camera& camera, uint32_t width, uint32_t height);

// The look-at form (from, to = from + the view direction, up) of a camera given by OpenCV's [R t]
// (as world_to_camera writes it); `fault` receives what makes the matrix no rigid motion (a last row
// other than 0 0 0 1, R not a rotation within 1e-6: R R^T = I and det R = 1), and the camera is
// then unchanged. The image plane (fovy or intrinsics) is kept.
Camera with_world_to_camera(Camera camera, const Matrix4& matrix, std::string& fault);

// The camera as OpenEXR's standard attributes describe it (RenderMan's conventions), which the EXR
// header carries. worldToCamera: camera space x right, y up, z along the view direction (left-handed;
// points in front have z > 0, their planar depth): rows right, up, -forward.
Matrix4 world_to_openexr_camera(const Camera& camera, uint32_t width, uint32_t height);
// worldToNDC: a world point p goes to (X, Y, Z, W) = M (p, 1); (X / W, Y / W) is the point in the
// image with (0, 0) at the top-left corner of the top-left pixel and (1, 1) at the bottom-right
// corner of the bottom-right one, x right and y down: ((u + 0.5) / W, (v + 0.5) / H) in the pinhole
// model's pixel coordinates. W is the planar depth and Z = 1 (Z / W its reciprocal).
Matrix4 world_to_openexr_ndc(const Camera& camera, uint32_t width, uint32_t height);

}  // namespace vkray
