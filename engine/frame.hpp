// Per-pixel outputs ("AOVs") of one render, on the host, row-major from the top row.
#pragma once

#include "engine/scene/camera.hpp"
#include "engine/scene/scene.hpp"

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// Every output a render can write, as a bit of AovSet. Each is described once, in outputs()
// below: adding one takes its bit here, its planes in Frame, its row in output_table, its
// computation and its test.
enum class Aov : uint32_t {
  depth = 1,
  normal = 2,
  uv = 4,
  planar_depth = 8,
  position = 16,
  camera_position = 32,
  mesh_id = 64,
  primitive_id = 128,
  hit = 256,  // what each ray hit, as the device numbers it: computed for the ids, named by no user
  barycentric = 512,
  shading_normal = 1024,
  texcoord = 2048,
  front_facing = 4096,
  instance_id = 8192,
};

// Where an output is computed: on the device (depth, normal, uv); on the host from the depth and
// the camera (add_camera_outputs); the host's names for what each ray hit (store_ids); on the host
// from what each ray hit and the pixel's ray (add_surface_outputs).
enum class OutputSource { device, camera, ids, surface };

// How the bench measures an output against the reference's (measure_output_errors), where both
// hit: the relative error, its 99th percentile; the distance over the pixel's depth, p99; pixels
// that differ (surface outputs: where both name the same primitive); the largest absolute
// difference; the angle in degrees, p99. none: the device outputs, measured by FrameError.
enum class OutputError { none, relative_p99, over_depth_p99, mismatches, absolute_max, degrees_p99 };

struct Frame;

// One output as every part of vkray sees it: the CLI's --aov, the EXR's channels, Python's dict
// and the reference's frame, the bench's error report.
struct OutputInfo {
  Aov aov;
  const char* name;         // --aov, vkray:outputs and the manifest; Python's key with '_' for '-'
  const char* description;  // a few words, for the help texts
  uint32_t components;
  bool integer;             // 32-bit unsigned planes (ids, flags); float32 otherwise
  OutputSource source;
  std::array<const char*, 3> channels;  // the EXR's channel of each component
  bool takes_miss_value;    // --miss sets it where the ray missed (a depth)
  OutputError error;
  const char* error_field;  // the bench's figure (JSON, CSV); outputs measured together share one
  const char* error_label;  // and its label in the bench's table
  std::vector<float> Frame::*floats = nullptr;     // its planes in a Frame, by type
  std::vector<uint32_t> Frame::*integers = nullptr;
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
  // Whether it holds an output computed from `source`.
  bool has_source(OutputSource source) const;
  bool has_camera_outputs() const { return has_source(OutputSource::camera); }
  bool has_ids() const { return has_source(OutputSource::ids); }
  bool has_surface_outputs() const { return has_source(OutputSource::surface); }
  // Every output but uv needs a ray cast.
  bool needs_rays() const { return (bits_ & ~static_cast<uint32_t>(Aov::uv)) != 0; }
  // What the device computes for these outputs: the camera outputs need its depth, the ids what
  // each ray hit, and its depth too (which pixels hit: the A channel); the surface outputs both.
  AovSet on_device() const;
  // What `vkray view` and Python's Reference show in double: depth, normal and uv.
  bool device_outputs_only() const { return (bits_ & ~on_device().bits_) == 0 && !has(Aov::hit); }
  std::string names() const;  // "depth,normal"

 private:
  uint32_t bits_ = 0;
};

// Every output, in the order files and dicts list them.
std::span<const OutputInfo> outputs();
const OutputInfo& output_info(Aov aov);

// The output named `name`, with '-' or '_' between words ("planar-depth", "planar_depth"); none
// for any other name.
std::optional<Aov> aov_from_name(std::string_view name);
// Every output's name, comma-separated, for help texts; and the error for an unknown name, with the
// nearest known one where it is close ("unknown output 'planer-depth'; did you mean 'planar-depth'?").
std::string output_names();
std::string unknown_output_message(std::string_view name);
// Python's key for an output: its name with '_' for '-'.
std::string python_key(const OutputInfo& output);

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
  // What each mesh_id stands for (object_names, engine/scene/scene.hpp), where the frame has mesh_id.
  std::vector<std::string> object_names;
  std::vector<float> depth;   // distance along the primary ray, +inf on a miss; also for the camera outputs
  std::vector<float> normal;  // 3 planes: unit geometric normal facing the ray, 0 on a miss
  std::vector<float> uv;      // 2 planes: image-plane coordinates of the pixel centre
  // The camera outputs (docs/outputs.md, "Output contract"): the hit point's distance to the image plane
  // (+inf on a miss), and the hit point in world space and in OpenEXR's camera space (3 planes each,
  // 0 on a miss).
  std::vector<float> planar_depth;
  std::vector<float> position;
  std::vector<float> camera_position;
  // What each ray hit (ObjectPrimitive in engine/scene/scene.hpp): the mesh, sphere or plane, and
  // the primitive within it; no_object on a miss.
  std::vector<uint32_t> mesh_id;
  std::vector<uint32_t> primitive_id;
  // The instance placing the mesh hit (Scene::instances), no_object for anything else and a miss.
  std::vector<uint32_t> instance_id;
  // The surface outputs (docs/outputs.md, "Output contract"), 0 where nothing or no triangle gives them: the
  // hit's weights of its triangle's second and third vertices (2 planes), the shading normal (3
  // planes), the texture coordinates (2 planes) and the side of the primitive the ray meets.
  std::vector<float> barycentric;
  std::vector<float> shading_normal;
  std::vector<float> texcoord;
  // 1 where the ray meets its primitive's front: a triangle whose vertices run counter-clockwise
  // as the ray sees them, a sphere from outside, a plane from the side its normal points to; 0 at
  // the back and on a miss.
  std::vector<uint32_t> front_facing;
  // The float64 shader's depth and normals before rounding (empty otherwise): what its agreement
  // with the reference is measured on. depth and normal then hold them rounded.
  std::vector<double> depth64;
  std::vector<double> normal64;

  size_t pixel_count() const { return size_t{width} * height; }
  // Sizes the planes of the outputs in `aovs` and of what the device computes for them, for
  // width x height (outputs()), with the double ones if asked.
  void allocate(bool doubles = false);
  // The bytes allocate() gives width x height pixels of `aovs`: what a frame held on the host costs.
  static size_t bytes(uint32_t width, uint32_t height, AovSet aovs, bool doubles);
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
// `instance`: the instance placing the mesh hit, or no_object.
void store_ids(Frame& frame, size_t pixel, ObjectPrimitive source, uint32_t instance = no_object);

// The uv output: every pixel's image-plane coordinates (pixel_uv).
void fill_pixel_uv(Frame& frame);

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
