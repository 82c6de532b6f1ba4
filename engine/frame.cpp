#include "engine/frame.hpp"

#include "engine/parallel.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vkray {

namespace {
struct NamedAov {
  Aov aov;
  const char* name;
};
constexpr NamedAov named_aovs[] = {{Aov::depth, "depth"},
                                   {Aov::normal, "normal"},
                                   {Aov::uv, "uv"},
                                   {Aov::planar_depth, "planar-depth"},
                                   {Aov::position, "position"},
                                   {Aov::camera_position, "camera-position"},
                                   {Aov::mesh_id, "mesh-id"},
                                   {Aov::primitive_id, "primitive-id"},
                                   {Aov::barycentric, "barycentric"},
                                   {Aov::shading_normal, "shading-normal"},
                                   {Aov::texcoord, "texcoord"}};
}  // namespace

std::string AovSet::names() const {
  std::string list;
  for (const auto& entry : named_aovs) {
    if (!has(entry.aov)) continue;
    if (!list.empty()) list += ',';
    list += entry.name;
  }
  return list;
}

std::optional<Aov> aov_from_name(std::string_view name) {
  for (const auto& entry : named_aovs) {
    if (name == entry.name) return entry.aov;
  }
  return std::nullopt;
}

void Frame::allocate(bool doubles) {
  const AovSet device = aovs.on_device();
  depth.assign(device.has(Aov::depth) ? pixel_count() : 0, 0.0f);
  normal.assign(device.has(Aov::normal) ? 3 * pixel_count() : 0, 0.0f);
  uv.assign(device.has(Aov::uv) ? 2 * pixel_count() : 0, 0.0f);
  planar_depth.assign(aovs.has(Aov::planar_depth) ? pixel_count() : 0, 0.0f);
  position.assign(aovs.has(Aov::position) ? 3 * pixel_count() : 0, 0.0f);
  camera_position.assign(aovs.has(Aov::camera_position) ? 3 * pixel_count() : 0, 0.0f);
  // The surface outputs are found from both ids.
  mesh_id.assign(aovs.has(Aov::mesh_id) || aovs.has_surface_outputs() ? pixel_count() : 0, no_object);
  primitive_id.assign(aovs.has(Aov::primitive_id) || aovs.has_surface_outputs() ? pixel_count() : 0, no_object);
  barycentric.assign(aovs.has(Aov::barycentric) ? 2 * pixel_count() : 0, 0.0f);
  shading_normal.assign(aovs.has(Aov::shading_normal) ? 3 * pixel_count() : 0, 0.0f);
  texcoord.assign(aovs.has(Aov::texcoord) ? 2 * pixel_count() : 0, 0.0f);
  depth64.assign(doubles ? depth.size() : 0, 0.0);
  normal64.assign(doubles ? normal.size() : 0, 0.0);
}

void Frame::round_doubles() {
  if (!depth64.empty()) std::copy(depth64.begin(), depth64.end(), depth.begin());
  if (!normal64.empty()) std::copy(normal64.begin(), normal64.end(), normal.begin());
}

bool Frame::hit(size_t pixel) const {
  if (!depth.empty()) return std::isfinite(depth[pixel]);
  if (!normal.empty()) return normal_at(pixel) != glm::vec3(0.0f);
  return false;
}

void store_ids(Frame& frame, size_t pixel, ObjectPrimitive source) {
  if (!frame.mesh_id.empty()) frame.mesh_id[pixel] = source.object;
  if (!frame.primitive_id.empty()) frame.primitive_id[pixel] = source.primitive;
}

void add_camera_outputs(Frame& frame) {
  if (!frame.aovs.has_camera_outputs()) return;
  if (!frame.camera || frame.depth.empty()) throw std::logic_error("add_camera_outputs: the frame has no camera or no depth");
  const CameraBasis basis = make_camera_basis(*frame.camera, frame.width, frame.height);
  const size_t pixels = frame.pixel_count();
  auto store = [pixels](std::vector<float>& planes, size_t p, const glm::dvec3& value) {
    if (planes.empty()) return;
    for (int c = 0; c < 3; ++c) planes[c * pixels + p] = static_cast<float>(value[c]);
  };
  parallel_for_chunks(frame.height, [&](size_t first_row, size_t end_row) {
    for (auto j = static_cast<uint32_t>(first_row); j < end_row; ++j) {
      for (uint32_t i = 0; i < frame.width; ++i) {
        const size_t p = size_t{j} * frame.width + i;
        const double t = frame.depth64.empty() ? double{frame.depth[p]} : frame.depth64[p];
        if (!std::isfinite(t)) {
          if (!frame.planar_depth.empty()) frame.planar_depth[p] = INFINITY;
          store(frame.position, p, glm::dvec3(0.0));
          store(frame.camera_position, p, glm::dvec3(0.0));
          continue;
        }
        const PixelRay ray = pixel_ray(*frame.camera, basis, i, j, frame.width, frame.height);
        const glm::dvec3 offset = ray.origin + t * ray.direction - basis.origin;
        // OpenEXR's camera space (world_to_openexr_camera): x right, y up, z the view direction.
        const glm::dvec3 in_camera(glm::dot(offset, basis.right), glm::dot(offset, basis.up), -glm::dot(offset, basis.forward));
        if (!frame.planar_depth.empty()) frame.planar_depth[p] = static_cast<float>(in_camera.z);
        store(frame.position, p, basis.origin + offset);
        store(frame.camera_position, p, in_camera);
      }
    }
  }, 16);
}

DepthRange finite_depth_range(const Frame& frame) {
  DepthRange range;
  for (float z : frame.depth) {
    if (std::isfinite(z)) range.add(z);
  }
  return range;
}

}  // namespace vkray
