#include "engine/scene/gltf_loader.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

// tinygltf's implementation, without its image decoders and file-path expansion: vkray reads no
// textures, and a file names its buffers beside itself.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace vkray {
namespace {

// Past these a file is refused rather than the stack or the memory: nodes nested deeper than any
// real scene graph, and node instances (a node named as a child of many) beyond any real scene.
constexpr int max_node_depth = 256;
constexpr size_t max_node_instances = size_t{1} << 20;

class GltfReader {
 public:
  GltfReader(const tinygltf::Model& gltf, std::string name) : gltf_(gltf), name_(std::move(name)) {}

  Model read() {
    if (gltf_.scenes.empty()) fail("no scene in the file");
    const int scene = gltf_.defaultScene >= 0 ? gltf_.defaultScene : 0;
    if (static_cast<size_t>(scene) >= gltf_.scenes.size()) fail("the default scene " + std::to_string(scene) + " does not exist");
    for (const int root : gltf_.scenes[static_cast<size_t>(scene)].nodes) read_node(root, glm::dmat4(1.0), 0);
    if (model_.meshes.empty()) fail("no faces to render (no triangle in the scene's meshes)");
    return std::move(model_);
  }

 private:
  [[noreturn]] void fail(const std::string& message) const { throw InputError(name_ + ": " + message); }

  const tinygltf::Node& node_at(int index) const {
    if (index < 0 || static_cast<size_t>(index) >= gltf_.nodes.size()) fail("node " + std::to_string(index) + " does not exist");
    return gltf_.nodes[static_cast<size_t>(index)];
  }

  glm::dmat4 local_transform(const tinygltf::Node& node, int index) const {
    if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());  // column-major, as glm's
    glm::dmat4 transform(1.0);
    if (node.translation.size() == 3) transform = glm::translate(transform, glm::make_vec3(node.translation.data()));
    if (node.rotation.size() == 4) {
      const glm::dquat rotation(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // x, y, z, w
      const double length = glm::length(rotation);
      if (!(length > 0.0) || !std::isfinite(length)) fail("node " + std::to_string(index) + " has a zero or non-finite rotation");
      transform *= glm::mat4_cast(rotation / length);
    }
    if (node.scale.size() == 3) transform = glm::scale(transform, glm::make_vec3(node.scale.data()));
    return transform;
  }

  void read_node(int index, const glm::dmat4& parent, int depth) {
    if (depth > max_node_depth) fail("nodes nested deeper than " + std::to_string(max_node_depth) + " (a node its own ancestor?)");
    if (++instances_ > max_node_instances) fail("more than " + std::to_string(max_node_instances) + " node instances");
    const tinygltf::Node& node = node_at(index);
    const glm::dmat4 transform = parent * local_transform(node, index);
    const std::string node_name = node.name.empty() ? "nodes[" + std::to_string(index) + "]" : node.name;
    if (node.mesh >= 0) {
      if (static_cast<size_t>(node.mesh) >= gltf_.meshes.size()) fail("node '" + node_name + "' names a missing mesh");
      Mesh mesh;
      mesh.source = name_ + "#" + node_name;
      for (const tinygltf::Primitive& primitive : gltf_.meshes[static_cast<size_t>(node.mesh)].primitives) {
        add_primitive(primitive, transform, mesh);
      }
      if (!mesh.triangles.empty()) {
        check_mesh_values(mesh, 0);
        model_.meshes.push_back(std::move(mesh));
      }
    }
    if (node.camera >= 0 && !model_.camera) read_camera(node, node_name, transform);
    for (const int child : node.children) read_node(child, transform, depth + 1);
  }

  // An accessor's values, `components` a record, as doubles: every byte it names checked to lie in
  // its buffer view and buffer. Integers (indices, normalized texture coordinates) as integers.
  std::vector<double> accessor_values(int index, int components, const char* what, bool integers) const {
    const std::string where = std::string(what) + " accessor " + std::to_string(index);
    if (index < 0 || static_cast<size_t>(index) >= gltf_.accessors.size()) fail(where + " does not exist");
    const tinygltf::Accessor& accessor = gltf_.accessors[static_cast<size_t>(index)];
    const int expected_type = components == 1 ? TINYGLTF_TYPE_SCALAR : components == 2 ? TINYGLTF_TYPE_VEC2 : TINYGLTF_TYPE_VEC3;
    if (accessor.type != expected_type) fail(where + " has the wrong type (expected " + std::to_string(components) + " components)");
    if (accessor.sparse.isSparse) fail(where + " is sparse, which vkray does not read");
    const int component = accessor.componentType;
    const bool floats = component == TINYGLTF_COMPONENT_TYPE_FLOAT;
    const bool allowed = integers ? component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                                        component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT
                                  : floats || (accessor.normalized && (component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                                                        component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
    if (!allowed) fail(where + " has a component type vkray does not read here (" + std::to_string(component) + ")");
    const size_t component_size = component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ? 1 : component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2 : 4;
    const size_t record_size = component_size * static_cast<size_t>(components);
    // Without a buffer view an accessor is all zeros (glTF 2.0, 3.6.2.1), a base for sparse values,
    // which vkray does not read: as it is, its count alone would set what is allocated.
    if (accessor.bufferView < 0) fail(where + " has no buffer view (zeros for sparse values, which vkray does not read)");
    std::vector<double> values;
    if (static_cast<size_t>(accessor.bufferView) >= gltf_.bufferViews.size()) fail(where + " names a missing buffer view");
    const tinygltf::BufferView& view = gltf_.bufferViews[static_cast<size_t>(accessor.bufferView)];
    if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= gltf_.buffers.size()) fail(where + "'s buffer view names a missing buffer");
    const std::vector<unsigned char>& buffer = gltf_.buffers[static_cast<size_t>(view.buffer)].data;
    const size_t stride = view.byteStride == 0 ? record_size : view.byteStride;
    const bool fits = view.byteOffset <= buffer.size() && view.byteLength <= buffer.size() - view.byteOffset &&
                      stride >= record_size && accessor.byteOffset <= view.byteLength &&
                      (accessor.count == 0 || (accessor.count - 1 <= (view.byteLength - accessor.byteOffset) / stride &&
                                               (accessor.count - 1) * stride + record_size <= view.byteLength - accessor.byteOffset));
    if (!fits) fail(where + " reaches past its buffer view or buffer");
    const unsigned char* start = buffer.data() + view.byteOffset + accessor.byteOffset;
    values.reserve(accessor.count * static_cast<size_t>(components));
    for (size_t i = 0; i < accessor.count; ++i) {
      for (int k = 0; k < components; ++k) {
        const unsigned char* at = start + i * stride + static_cast<size_t>(k) * component_size;
        double value = 0.0;
        if (floats) {
          float f;
          std::memcpy(&f, at, sizeof f);
          value = f;
        } else if (component_size == 1) {
          value = at[0];
        } else if (component_size == 2) {
          uint16_t u;
          std::memcpy(&u, at, sizeof u);
          value = u;
        } else {
          uint32_t u;
          std::memcpy(&u, at, sizeof u);
          value = u;
        }
        // Normalized integers stand for value / max (glTF 2.0, 3.11).
        if (!integers && !floats) value /= component_size == 1 ? 255.0 : 65535.0;
        values.push_back(value);
      }
    }
    return values;
  }

  std::optional<int> attribute(const tinygltf::Primitive& primitive, const char* key) const {
    const auto found = primitive.attributes.find(key);
    return found == primitive.attributes.end() ? std::nullopt : std::optional<int>(found->second);
  }

  // The primitive's triangles as vertex numbers: its index list (or the vertices in order) read as
  // triangles, a strip or a fan (glTF 2.0, 3.7.2.1); points and lines give none.
  std::vector<std::array<uint32_t, 3>> primitive_triangles(const tinygltf::Primitive& primitive, size_t vertices) const {
    const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
    std::vector<std::array<uint32_t, 3>> triangles;
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) return triangles;
    std::vector<uint32_t> order;
    if (primitive.indices >= 0) {
      for (const double index : accessor_values(primitive.indices, 1, "index", true)) {
        if (index >= static_cast<double>(vertices)) fail("index accessor " + std::to_string(primitive.indices) + " names a missing vertex");
        order.push_back(static_cast<uint32_t>(index));
      }
    } else {
      for (size_t v = 0; v < vertices; ++v) order.push_back(static_cast<uint32_t>(v));
    }
    const size_t n = order.size();
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      for (size_t i = 0; i + 2 < n; i += 3) triangles.push_back({order[i], order[i + 1], order[i + 2]});
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      for (size_t i = 0; i + 2 < n; ++i) {
        triangles.push_back(i % 2 == 0 ? std::array{order[i], order[i + 1], order[i + 2]} : std::array{order[i + 1], order[i], order[i + 2]});
      }
    } else {
      for (size_t i = 1; i + 1 < n; ++i) triangles.push_back({order[0], order[i], order[i + 1]});
    }
    return triangles;
  }

  void add_primitive(const tinygltf::Primitive& primitive, const glm::dmat4& transform, Mesh& mesh) const {
    const std::optional<int> position = attribute(primitive, "POSITION");
    if (!position) fail("a primitive has no POSITION (compressed meshes, KHR_draco_mesh_compression, are not read)");
    const std::vector<double> positions = accessor_values(*position, 3, "POSITION", false);
    const size_t vertices = positions.size() / 3;
    const std::vector<std::array<uint32_t, 3>> triangles = primitive_triangles(primitive, vertices);
    if (triangles.empty()) return;
    const auto first = static_cast<uint32_t>(mesh.positions.size());
    for (size_t v = 0; v < vertices; ++v) {
      mesh.positions.push_back(glm::dvec3(transform * glm::dvec4(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2], 1.0)));
    }
    const std::optional<int> normal = attribute(primitive, "NORMAL");
    const std::optional<int> texcoord = attribute(primitive, "TEXCOORD_0");
    const auto first_normal = static_cast<uint32_t>(mesh.normals.size());
    const auto first_texcoord = static_cast<uint32_t>(mesh.texcoords.size());
    if (normal) {
      const std::vector<double> normals = accessor_values(*normal, 3, "NORMAL", false);
      if (normals.size() != positions.size()) fail("NORMAL accessor " + std::to_string(*normal) + " counts other vertices than POSITION");
      const glm::dmat3 normal_transform = glm::transpose(glm::inverse(glm::dmat3(transform)));
      for (size_t v = 0; v < vertices; ++v) mesh.normals.push_back(normal_transform * glm::dvec3(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]));
    }
    if (texcoord) {
      const std::vector<double> uvs = accessor_values(*texcoord, 2, "TEXCOORD_0", false);
      if (uvs.size() != 2 * vertices) fail("TEXCOORD_0 accessor " + std::to_string(*texcoord) + " counts other vertices than POSITION");
      for (size_t v = 0; v < vertices; ++v) mesh.texcoords.emplace_back(uvs[2 * v], 1.0 - uvs[2 * v + 1]);
    }
    for (const auto& triangle : triangles) {
      mesh.triangles.push_back({first + triangle[0], first + triangle[1], first + triangle[2]});
      add_corners(mesh.normal_corners, normal.has_value(), first_normal, triangle, mesh.triangles.size());
      add_corners(mesh.texcoord_corners, texcoord.has_value(), first_texcoord, triangle, mesh.triangles.size());
    }
  }

  // A triangle's corners into an attribute list, the list kept one a triangle (or empty) when the
  // primitives merged into one mesh have the attribute only in part.
  static void add_corners(std::vector<std::array<uint32_t, 3>>& corners, bool present, uint32_t first,
                          const std::array<uint32_t, 3>& local, size_t triangles) {
    if (!present && corners.empty()) return;
    corners.resize(triangles - 1, {no_attribute, no_attribute, no_attribute});
    corners.push_back(present ? std::array{first + local[0], first + local[1], first + local[2]}
                              : std::array{no_attribute, no_attribute, no_attribute});
  }

  // glTF's camera looks down its node's -z with +y up, from the node's origin (glTF 2.0, 3.10.1).
  void read_camera(const tinygltf::Node& node, const std::string& node_name, const glm::dmat4& transform) {
    if (static_cast<size_t>(node.camera) >= gltf_.cameras.size()) fail("node '" + node_name + "' names a missing camera");
    const tinygltf::Camera& source = gltf_.cameras[static_cast<size_t>(node.camera)];
    Camera camera;
    camera.from = glm::dvec3(transform[3]);
    camera.to = camera.from - glm::dvec3(transform[2]);
    camera.up = glm::dvec3(transform[1]);
    const std::string what = "camera " + std::to_string(node.camera) + " (node '" + node_name + "')";
    if (source.type == "perspective") {
      const double yfov = source.perspective.yfov;
      if (!(yfov > 0.0 && yfov < std::numbers::pi)) fail(what + ": yfov must lie in (0, pi)");
      camera.fovy_degrees = yfov * 180.0 / std::numbers::pi;
      if (source.perspective.aspectRatio > 0.0 && std::isfinite(source.perspective.aspectRatio)) model_.aspect_ratio = source.perspective.aspectRatio;
    } else if (source.type == "orthographic") {
      const double xmag = std::abs(source.orthographic.xmag), ymag = std::abs(source.orthographic.ymag);
      if (!(xmag > 0.0 && ymag > 0.0 && std::isfinite(xmag) && std::isfinite(ymag))) fail(what + ": xmag and ymag must be non-zero");
      camera.projection = Projection::orthographic;
      camera.view_height = 2.0 * ymag;
      model_.aspect_ratio = xmag / ymag;
    } else {
      fail(what + ": unknown type '" + source.type + "'");
    }
    for (const glm::dvec3& v : {camera.from, camera.to, camera.up}) {
      if (!within_coordinate_bound(v)) fail(what + ": its placement is not finite");
    }
    if (camera.from == camera.to || camera.up == glm::dvec3(0.0)) fail(what + ": its node's transform flattens it (a scale of 0)");
    model_.camera = camera;
  }

  const tinygltf::Model& gltf_;
  std::string name_;
  size_t instances_ = 0;
  Model model_;
};

// vkray reads no textures: images are accepted unread.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) { return true; }

}  // namespace

Model read_gltf(std::string_view bytes, bool binary, const std::filesystem::path& folder, const std::string& name) {
  if (bytes.size() > std::numeric_limits<unsigned int>::max()) throw InputError(name + ": larger than 4 GiB, which tinygltf cannot read");
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  tinygltf::Model gltf;
  std::string error, warning;
  const auto size = static_cast<unsigned int>(bytes.size());
  const bool read = binary ? loader.LoadBinaryFromMemory(&gltf, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()), size, folder.string())
                           : loader.LoadASCIIFromString(&gltf, &error, &warning, bytes.data(), size, folder.string());
  if (!read) {
    const std::string reason = error.substr(0, error.find('\n'));
    throw InputError(name + ": not a glTF 2.0 file vkray can read: " + (reason.empty() ? "tinygltf gave no reason" : reason));
  }
  return GltfReader(gltf, name).read();
}

}  // namespace vkray
