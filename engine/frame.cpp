#include "engine/frame.hpp"

#include "engine/typed_names.hpp"
#include "engine/parallel.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vkray {

namespace {

// The outputs, in the order files and dicts list them. EXR channel names: Z and N for depth and
// normal, as OpenEXR's standard names them; U and V the image plane's coordinates; the camera
// outputs as layers ("layer.channel"), P for positions as pbrt-v4 names them; the ids as Python's
// cast_rays names them; Ns, pbrt-v4's name for the shading normal; texcoord and barycentric in
// layers of their own, apart from U and V (a texture's coordinates, not the image plane's).
const OutputInfo output_table[] = {
    {Aov::depth, "depth", "distance along the ray", 1, false, OutputSource::device, {"Z"}, true, OutputError::none, "", "",
     &Frame::depth},
    {Aov::normal, "normal", "unit geometric normal facing the ray", 3, false, OutputSource::device, {"N.X", "N.Y", "N.Z"},
     false, OutputError::none, "", "", &Frame::normal},
    {Aov::uv, "uv", "the pixel centre on the image plane", 2, false, OutputSource::device, {"U", "V"}, false,
     OutputError::none, "", "", &Frame::uv},
    {Aov::planar_depth, "planar-depth", "distance from the image plane", 1, false, OutputSource::camera, {"planar.Z"},
     true, OutputError::relative_p99, "planar_depth_rel_p99", "planar", &Frame::planar_depth},
    {Aov::position, "position", "hit point, world", 3, false, OutputSource::camera, {"P.X", "P.Y", "P.Z"}, false,
     OutputError::over_depth_p99, "position_rel_p99", "P", &Frame::position},
    {Aov::camera_position, "camera-position", "hit point, camera space", 3, false, OutputSource::camera,
     {"camera.P.X", "camera.P.Y", "camera.P.Z"}, false, OutputError::over_depth_p99, "position_rel_p99", "P",
     &Frame::camera_position},
    {Aov::mesh_id, "mesh-id", "mesh, sphere or plane hit", 1, true, OutputSource::ids, {"mesh_id"}, false,
     OutputError::mismatches, "id_mismatches", "ids", nullptr, &Frame::mesh_id},
    {Aov::primitive_id, "primitive-id", "triangle hit, in its file", 1, true, OutputSource::ids, {"primitive_id"}, false,
     OutputError::mismatches, "id_mismatches", "ids", nullptr, &Frame::primitive_id},
    {Aov::instance_id, "instance-id", "instance placing the mesh hit", 1, true, OutputSource::ids, {"instance_id"}, false,
     OutputError::mismatches, "id_mismatches", "ids", nullptr, &Frame::instance_id},
    {Aov::barycentric, "barycentric", "weights of the triangle's second and third vertices", 2, false,
     OutputSource::surface, {"barycentric.U", "barycentric.V"}, false, OutputError::absolute_max, "barycentric_max",
     "bary", &Frame::barycentric},
    {Aov::shading_normal, "shading-normal", "interpolated vertex normal facing the ray", 3, false,
     OutputSource::surface, {"Ns.X", "Ns.Y", "Ns.Z"}, false, OutputError::degrees_p99, "shading_normal_deg_p99",
     "Ns", &Frame::shading_normal},
    {Aov::texcoord, "texcoord", "interpolated texture coordinates", 2, false, OutputSource::surface,
     {"texcoord.U", "texcoord.V"}, false, OutputError::absolute_max, "texcoord_max", "uv", &Frame::texcoord},
    {Aov::front_facing, "front-facing", "1 where the ray meets the primitive's front", 1, true, OutputSource::surface,
     {"front_facing"}, false, OutputError::mismatches, "front_facing_mismatches", "front", nullptr,
     &Frame::front_facing},
};

// The name with every '_' read as '-'.
std::string dashed(std::string_view name) {
  std::string text(name);
  std::replace(text.begin(), text.end(), '_', '-');
  return text;
}

}  // namespace

std::span<const OutputInfo> outputs() { return output_table; }

const OutputInfo& output_info(Aov aov) {
  for (const auto& output : output_table) {
    if (output.aov == aov) return output;
  }
  throw std::logic_error("no output " + std::to_string(static_cast<uint32_t>(aov)));
}

bool AovSet::has_source(OutputSource source) const {
  return std::any_of(std::begin(output_table), std::end(output_table),
                     [&](const OutputInfo& output) { return output.source == source && has(output.aov); });
}

AovSet AovSet::on_device() const {
  AovSet device;
  for (const auto& output : output_table) {
    if (output.source == OutputSource::device && has(output.aov)) device.add(output.aov);
  }
  if (has(Aov::hit)) device.add(Aov::hit);
  if (has_camera_outputs() || has_ids() || has_surface_outputs()) device.add(Aov::depth);
  if (has_ids() || has_surface_outputs()) device.add(Aov::hit);
  return device;
}

std::string AovSet::names() const {
  std::string list;
  for (const auto& output : output_table) {
    if (!has(output.aov)) continue;
    if (!list.empty()) list += ',';
    list += output.name;
  }
  return list;
}

std::optional<Aov> aov_from_name(std::string_view name) {
  const std::string wanted = dashed(name);
  for (const auto& output : output_table) {
    if (wanted == output.name) return output.aov;
  }
  return std::nullopt;
}

std::string output_names() {
  std::string list;
  for (const auto& output : output_table) list += (list.empty() ? "" : ", ") + std::string(output.name);
  return list;
}

std::string unknown_output_message(std::string_view name) {
  std::vector<std::string> names;
  for (const auto& output : output_table) names.emplace_back(output.name);
  const std::optional<std::string> nearest = nearest_name(dashed(name), names);
  return "unknown output '" + std::string(name) + "'" +
         (nearest ? "; did you mean '" + *nearest + "'?" : " (choose from " + output_names() + ")");
}

std::string python_key(const OutputInfo& output) {
  std::string key = output.name;
  std::replace(key.begin(), key.end(), '-', '_');
  return key;
}

namespace {

// What a frame of `aovs` computes and holds: the outputs asked for, what the device computes for
// them, and both ids, from which the surface outputs are found.
AovSet computed_outputs(AovSet aovs) {
  AovSet computed = aovs;
  for (const auto& output : output_table) {
    if (aovs.on_device().has(output.aov)) computed.add(output.aov);
  }
  if (aovs.has_surface_outputs()) computed.add(Aov::mesh_id), computed.add(Aov::primitive_id), computed.add(Aov::instance_id);
  return computed;
}

}  // namespace

size_t Frame::bytes(uint32_t width, uint32_t height, AovSet aovs, bool doubles) {
  const AovSet computed = computed_outputs(aovs);
  size_t components = 0;
  for (const auto& output : output_table) {
    if (computed.has(output.aov)) components += output.components;
  }
  const size_t pixels = size_t{width} * height;
  const size_t double_components = doubles ? (computed.has(Aov::depth) ? 1 : 0) + (computed.has(Aov::normal) ? 3 : 0) : 0;
  return pixels * (components * sizeof(float) + double_components * sizeof(double));
}

void Frame::allocate(bool doubles) {
  const AovSet computed = computed_outputs(aovs);
  for (const auto& output : output_table) {
    const size_t size = computed.has(output.aov) ? output.components * pixel_count() : 0;
    if (output.floats) (this->*output.floats).assign(size, 0.0f);
    // Ids name no primitive until one is stored.
    if (output.integers) (this->*output.integers).assign(size, output.source == OutputSource::ids ? no_object : 0u);
  }
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

void fill_pixel_uv(Frame& frame) {
  const size_t pixels = frame.pixel_count();
  parallel_for_chunks(frame.height, [&](size_t first_row, size_t end_row) {
    for (auto j = static_cast<uint32_t>(first_row); j < end_row; ++j) {
      for (uint32_t i = 0; i < frame.width; ++i) {
        const glm::dvec2 uv = pixel_uv(i, j, frame.width, frame.height);
        frame.uv[size_t{j} * frame.width + i] = static_cast<float>(uv.x);
        frame.uv[pixels + size_t{j} * frame.width + i] = static_cast<float>(uv.y);
      }
    }
  }, 16);
}

void store_ids(Frame& frame, size_t pixel, ObjectPrimitive source, uint32_t instance) {
  if (!frame.mesh_id.empty()) frame.mesh_id[pixel] = source.object;
  if (!frame.primitive_id.empty()) frame.primitive_id[pixel] = source.primitive;
  if (!frame.instance_id.empty()) frame.instance_id[pixel] = instance;
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
