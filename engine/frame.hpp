// Per-pixel outputs ("AOVs") of one render, on the host, row-major from the top row.
#pragma once

#include "engine/scene/camera.hpp"
#include "engine/scene/scene.hpp"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// depth, normal and uv come from the device; planar_depth, position and camera_position are the
// camera outputs, computed on the host from the depth and the camera (add_camera_outputs);
// mesh_id and primitive_id are the host's names for the primitive the device says each ray hit
// (hit, which only the device computes and no user names); barycentric, shading_normal and
// texcoord are the surface outputs, computed on the host from that primitive and the pixel's ray
// (add_surface_outputs).
enum class Aov : uint32_t {
  depth = 1,
  normal = 2,
  uv = 4,
  planar_depth = 8,
  position = 16,
  camera_position = 32,
  mesh_id = 64,
  primitive_id = 128,
  hit = 256,
  barycentric = 512,
  shading_normal = 1024,
  texcoord = 2048
};

// A set of outputs as a bit mask of Aov values.
class AovSet {
 public:
  constexpr AovSet() = default;
  constexpr AovSet(std::initializer_list<Aov> aovs) {
    for (Aov aov : aovs) bits_ |= static_cast<uint32_t>(aov);
  }
  constexpr bool has(Aov aov) const { return (bits_ & static_cast<uint32_t>(aov)) != 0; }
  constexpr void add(Aov aov) { bits_ |= static_cast<uint32_t>(aov); }
  constexpr bool empty() const { return bits_ == 0; }
  constexpr uint32_t bits() const { return bits_; }
  constexpr bool has_camera_outputs() const {
    return has(Aov::planar_depth) || has(Aov::position) || has(Aov::camera_position);
  }
  constexpr bool has_ids() const { return has(Aov::mesh_id) || has(Aov::primitive_id); }
  constexpr bool has_surface_outputs() const {
    return has(Aov::barycentric) || has(Aov::shading_normal) || has(Aov::texcoord);
  }
  // Depth, normal, a camera, id or surface output need a ray cast; uv alone does not.
  constexpr bool needs_rays() const {
    return has(Aov::depth) || has(Aov::normal) || has_camera_outputs() || has_ids() || has_surface_outputs();
  }
  // What the device computes for these outputs: the camera outputs need its depth, the ids what
  // each ray hit, and its depth too (which pixels hit: the A channel); the surface outputs both.
  constexpr AovSet on_device() const {
    AovSet device;
    device.bits_ = bits_ & (static_cast<uint32_t>(Aov::depth) | static_cast<uint32_t>(Aov::normal) |
                            static_cast<uint32_t>(Aov::uv) | static_cast<uint32_t>(Aov::hit));
    if (has_camera_outputs() || has_ids() || has_surface_outputs()) device.add(Aov::depth);
    if (has_ids() || has_surface_outputs()) device.add(Aov::hit);
    return device;
  }
  // What `vkray view` and Python show: depth, normal and uv.
  constexpr bool device_outputs_only() const { return (bits_ & ~on_device().bits_) == 0 && !has(Aov::hit); }
  std::string names() const;  // "depth,normal"

 private:
  uint32_t bits_ = 0;
};

// "depth", "normal", "uv", "planar-depth", "position", "camera-position", "mesh-id",
// "primitive-id", "barycentric", "shading-normal" or "texcoord"; nullopt for anything else.
std::optional<Aov> aov_from_name(std::string_view name);
inline constexpr const char* aov_names_help =
    "depth, normal, uv, planar-depth, position, camera-position, mesh-id, primitive-id, barycentric, shading-normal, "
    "texcoord";

// Multi-component outputs are stored as planes (all x, then all y, ...), the layout the shader
// writes: neighbouring invocations then store to neighbouring addresses.
struct Frame {
  Frame() = default;
  Frame(uint32_t frame_width, uint32_t frame_height, AovSet frame_aovs)
      : width(frame_width), height(frame_height), aovs(frame_aovs) {}

  uint32_t width = 0;
  uint32_t height = 0;
  AovSet aovs;
  // The camera whose primary rays made the frame (none for given rays): the EXR header describes it.
  std::optional<Camera> camera;
  std::vector<float> depth;   // distance along the primary ray, +inf on a miss; also for the camera outputs
  std::vector<float> normal;  // 3 planes: unit geometric normal facing the ray, 0 on a miss
  std::vector<float> uv;      // 2 planes: image-plane coordinates of the pixel centre
  // The camera outputs (README, "Output contract"): the hit point's distance to the image plane
  // (+inf on a miss), and the hit point in world space and in OpenEXR's camera space (3 planes each,
  // 0 on a miss).
  std::vector<float> planar_depth;
  std::vector<float> position;
  std::vector<float> camera_position;
  // What each ray hit (ObjectPrimitive in engine/scene/scene.hpp): the mesh, sphere or plane, and
  // the primitive within it; no_object on a miss.
  std::vector<uint32_t> mesh_id;
  std::vector<uint32_t> primitive_id;
  // The surface outputs (README, "Output contract"), 0 where nothing or no triangle gives them: the
  // hit's weights of its triangle's second and third vertices (2 planes), the shading normal (3
  // planes) and the texture coordinates (2 planes).
  std::vector<float> barycentric;
  std::vector<float> shading_normal;
  std::vector<float> texcoord;
  // The float64 shader's depth and normals before rounding (empty otherwise): what its agreement
  // with the reference is measured on. depth and normal then hold them rounded.
  std::vector<double> depth64;
  std::vector<double> normal64;

  size_t pixel_count() const { return size_t{width} * height; }
  // Sizes the buffers of the outputs in `aovs` for width x height (depth also for the camera
  // outputs), with the double ones if asked.
  void allocate(bool doubles = false);
  // depth and normal from depth64 and normal64, where those are there.
  void round_doubles();
  glm::vec3 normal_at(size_t pixel) const {
    return {normal[pixel], normal[pixel_count() + pixel], normal[2 * pixel_count() + pixel]};
  }
  glm::vec2 uv_at(size_t pixel) const { return {uv[pixel], uv[pixel_count() + pixel]}; }
  // A hit is known from depth (finite) or, when only normals were asked for, from a non-zero normal.
  bool hit(size_t pixel) const;
};

// mesh_id and primitive_id of `pixel`, where the frame has them (for the ids or the surface outputs).
void store_ids(Frame& frame, size_t pixel, ObjectPrimitive source);

// Fills the camera outputs `frame.aovs` asks for from its depth (depth64 where the float64 shader or
// the reference left it: the hit point then rounds to float once) and its camera, in double:
// the hit point is o + t d with o and d the pixel's ray in double (pixel_ray), whose difference
// from the float32 shader's (a few float32 roundings) is within the error of t.
void add_camera_outputs(Frame& frame);

// The nearest and farthest finite depth of an image; far is 0 when nothing was hit.
struct DepthRange {
  float near = INFINITY;
  float far = 0.0f;
  void add(float depth) {
    if (depth < near) near = depth;
    if (depth > far) far = depth;
  }
};
DepthRange finite_depth_range(const Frame& frame);

}  // namespace vkray
