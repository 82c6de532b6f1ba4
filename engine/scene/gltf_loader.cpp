#include "engine/scene/gltf_loader.hpp"

#include "engine/scene/gltf_json_shape.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>

// tinygltf's implementation, without its image decoders: vkray reads no textures. Its file access
// goes through BufferFiles below.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numbers>
#include <set>

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
    const std::vector<int>& roots = gltf_.scenes[static_cast<size_t>(scene)].nodes;
    check_placements(roots);
    for (const int root : roots) read_node(root, glm::dmat4(1.0));
    if (model_.meshes.empty()) fail("no faces to render (no triangle in the scene's meshes)");
    return std::move(model_);
  }

 private:
  [[noreturn]] void fail(const std::string& message) const { throw InputError(name_ + ": " + message); }

  const tinygltf::Node& node_at(int index) const {
    if (index < 0 || static_cast<size_t>(index) >= gltf_.nodes.size()) fail("node " + std::to_string(index) + " does not exist");
    return gltf_.nodes[static_cast<size_t>(index)];
  }

  // What a placement of a primitive makes, from its accessors alone (add_primitive reads and checks
  // them): its corners (indices, or vertices in order) and vertices, each count no more than its
  // buffer view can hold, and the buffer views they come from.
  struct PrimitiveData {
    size_t corners = 0, vertices = 0;
    std::array<int, 2> views{-1, -1};
  };
  PrimitiveData primitive_data(const tinygltf::Primitive& primitive) const {
    PrimitiveData data;
    const auto elements = [&](int index, size_t& count, int& view) {
      if (index < 0 || static_cast<size_t>(index) >= gltf_.accessors.size()) return;
      const tinygltf::Accessor& accessor = gltf_.accessors[static_cast<size_t>(index)];
      if (accessor.bufferView < 0 || static_cast<size_t>(accessor.bufferView) >= gltf_.bufferViews.size()) return;
      view = accessor.bufferView;
      count = std::min(accessor.count, gltf_.bufferViews[static_cast<size_t>(view)].byteLength);  // an element is a byte at least
    };
    const int position = attribute(primitive, "POSITION").value_or(-1);
    elements(position, data.vertices, data.views[0]);
    if (primitive.indices >= 0) elements(primitive.indices, data.corners, data.views[1]);
    else data.corners = data.vertices;
    return data;
  }

  // Before anything is read: the node graph walked as read_node will walk it, bounded in depth and
  // node instances, adding up what each placement of a mesh makes. A node named as a child of many, a
  // chain of such nodes (node k's children [k+1, k+1]: 2^19 copies from 20 nodes), primitives sharing
  // accessors, accessors sharing bytes: each multiplies data the file holds once, and every copy is
  // stored. Refused past max_gltf_instancing corners and vertices a byte of the buffer views placed.
  void check_placements(const std::vector<int>& roots) const {
    std::vector<size_t> mesh_elements(gltf_.meshes.size());
    std::set<int> views;
    for (size_t m = 0; m < gltf_.meshes.size(); ++m) {
      for (const tinygltf::Primitive& primitive : gltf_.meshes[m].primitives) {
        const PrimitiveData data = primitive_data(primitive);
        mesh_elements[m] += data.corners + data.vertices;
        for (const int view : data.views) {
          if (view >= 0) views.insert(view);
        }
      }
    }
    // The bytes of each buffer the views cover, at most the buffer's own (views may overlap).
    std::map<int, size_t> buffer_bytes;
    for (const int view : views) buffer_bytes[gltf_.bufferViews[static_cast<size_t>(view)].buffer] += gltf_.bufferViews[static_cast<size_t>(view)].byteLength;
    size_t held_bytes = 0;
    for (const auto& [buffer, bytes] : buffer_bytes) {
      if (buffer >= 0 && static_cast<size_t>(buffer) < gltf_.buffers.size()) held_bytes += std::min(bytes, gltf_.buffers[static_cast<size_t>(buffer)].data.size());
    }
    size_t instances = 0, placed = 0;
    const auto walk = [&](const auto& self, int index, int depth) -> void {
      if (depth > max_node_depth) fail("nodes nested deeper than " + std::to_string(max_node_depth) + " (a node its own ancestor?)");
      if (++instances > max_node_instances) fail("more than " + std::to_string(max_node_instances) + " node instances");
      const tinygltf::Node& node = node_at(index);
      if (node.mesh >= 0 && static_cast<size_t>(node.mesh) < mesh_elements.size()) placed += mesh_elements[static_cast<size_t>(node.mesh)];
      for (const int child : node.children) self(self, child, depth + 1);
    };
    for (const int root : roots) walk(walk, root, 0);
    if (placed > max_gltf_instancing * held_bytes) {
      fail("its nodes place " + std::to_string(placed) + " triangle corners and vertices, more than " + std::to_string(max_gltf_instancing) +
           " for each of the " + std::to_string(held_bytes) + " bytes of mesh data it holds (vkray stores every placement: docs/scene-format.md, Model files)");
    }
  }

  glm::dmat4 local_transform(const tinygltf::Node& node, int index) const {
    if (node.matrix.size() == 16) {
      // Column-major, as glm's. glTF's matrices are affine (a translation, rotation and scale, 5.25):
      // a projective one has no such reading.
      const std::vector<double>& m = node.matrix;
      if (m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0) {
        fail("node " + std::to_string(index) + "'s matrix is projective (its last row is not 0 0 0 1), which glTF 2.0 does not allow");
      }
      return glm::make_mat4(m.data());
    }
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

  // check_placements has bounded the walk's depth and its node instances.
  void read_node(int index, const glm::dmat4& parent) {
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
    for (const int child : node.children) read_node(child, transform);
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
    // A transform of determinant 0 (a scale of 0) flattens the mesh onto a plane, line or point, where
    // the flat surface's own normal is the only right one: its NORMALs are left out.
    const std::optional<glm::dmat3> normal_transform = normal_transform_of(glm::dmat3(transform));
    const std::optional<int> normal = normal_transform ? attribute(primitive, "NORMAL") : std::nullopt;
    const std::optional<int> texcoord = attribute(primitive, "TEXCOORD_0");
    const auto first_normal = static_cast<uint32_t>(mesh.normals.size());
    const auto first_texcoord = static_cast<uint32_t>(mesh.texcoords.size());
    if (normal) {
      const std::vector<double> normals = accessor_values(*normal, 3, "NORMAL", false);
      if (normals.size() != positions.size()) fail("NORMAL accessor " + std::to_string(*normal) + " counts other vertices than POSITION");
      for (size_t v = 0; v < vertices; ++v) {
        mesh.normals.push_back(*normal_transform * glm::dvec3(normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]));
      }
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

  // Normals go through the inverse transpose of the transform's linear part, to stay perpendicular to
  // the surface. Its cofactor matrix, times the determinant's sign, is that up to a positive factor,
  // which normals (made unit length where they are interpolated) do not feel; taken of the matrix
  // scaled to entries of at most 1, it neither overflows nor underflows for a scale of 1e-300 or 1e300,
  // where the inverse would. None where the determinant is 0.
  static std::optional<glm::dmat3> normal_transform_of(glm::dmat3 linear) {
    double largest = 0.0;
    for (int c = 0; c < 3; ++c) largest = std::max({largest, std::abs(linear[c].x), std::abs(linear[c].y), std::abs(linear[c].z)});
    if (!(largest > 0.0) || !std::isfinite(largest)) return std::nullopt;
    linear /= largest;
    const double determinant = glm::determinant(linear);
    if (determinant == 0.0) return std::nullopt;
    const glm::dmat3 cofactors(glm::cross(linear[1], linear[2]), glm::cross(linear[2], linear[0]), glm::cross(linear[0], linear[1]));
    return determinant > 0.0 ? cofactors : -cofactors;
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
      // The image spans 2 xmag by 2 ymag world units, which must lie within vkray's coordinates.
      if (!(xmag > 0.0 && ymag > 0.0 && 2.0 * xmag <= max_coordinate && 2.0 * ymag <= max_coordinate)) {
        fail(what + ": xmag and ymag must be non-zero and at most 5e14 (the image spans twice them, within vkray's 1e15)");
      }
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
  Model model_;
};

// vkray reads no textures: images are accepted unread.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) { return true; }

// tinygltf's file access, narrowed to what docs/scene-format.md promises: a buffer is embedded, or a regular
// file beside the model or below its folder. tinygltf tries its uri in the model's folder, then in
// the working folder, and would read an absolute path, a "../" path, a FIFO (waiting for ever) or a
// folder; here only the first try can succeed, and only for a regular file there.
struct BufferFiles {
  std::string folder_prefix;  // the model's folder as tinygltf joins it to a uri ("" or ending in '/')
  std::string refusal;        // why the last uri tried was refused, for the message
};

bool buffer_file_exists(const std::string& path, void* user_data) {
  auto& files = *static_cast<BufferFiles*>(user_data);
  if (!path.starts_with(files.folder_prefix)) return false;  // the working folder's try
  const std::string uri = path.substr(files.folder_prefix.size());
  const std::filesystem::path relative = std::filesystem::path(uri).lexically_normal();
  const auto quoted = "buffer uri '" + uri.substr(0, 200) + "'";
  if (relative.is_absolute() || relative.empty() || *relative.begin() == "..") {
    files.refusal = quoted + " leads outside the model's folder: vkray reads a buffer embedded or from beside the model";
    return false;
  }
  struct stat status{};
  if (::stat(path.c_str(), &status) != 0) {
    files.refusal = quoted + ": no such file beside the model";
    return false;
  }
  if (!S_ISREG(status.st_mode)) {
    files.refusal = quoted + " is not a regular file";
    return false;
  }
  return true;
}

std::string buffer_file_path(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion

bool read_buffer_file(std::vector<unsigned char>* out, std::string* error, const std::string& path, void* user_data) {
  auto& files = *static_cast<BufferFiles*>(user_data);
  // O_NONBLOCK: a FIFO swapped in since buffer_file_exists opens at once, and fstat refuses it.
  const int descriptor = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  struct stat status{};
  const bool regular = descriptor >= 0 && ::fstat(descriptor, &status) == 0 && S_ISREG(status.st_mode);
  bool read_whole = regular;
  if (regular) {
    out->resize(static_cast<size_t>(status.st_size));
    for (size_t at = 0; read_whole && at < out->size();) {
      const ssize_t got = ::read(descriptor, out->data() + at, out->size() - at);
      read_whole = got > 0;
      at += got > 0 ? static_cast<size_t>(got) : 0;
    }
  }
  if (descriptor >= 0) ::close(descriptor);
  if (!read_whole) {
    files.refusal = "buffer file '" + path.substr(0, 200) + "' cannot be read" + (regular ? "" : " (not a regular file)");
    if (error) *error = files.refusal;
  }
  return read_whole;
}

bool write_no_file(std::string* error, const std::string&, const std::vector<unsigned char>&, void*) {
  if (error) *error = "vkray writes no glTF files";
  return false;
}

}  // namespace

Model read_gltf(std::string_view bytes, bool binary, const std::filesystem::path& folder, const std::string& name) {
  if (bytes.size() > std::numeric_limits<unsigned int>::max()) throw InputError(name + ": larger than 4 GiB, which tinygltf cannot read");
  if (const auto fault = gltf_json_fault(gltf_json_text(bytes, binary))) throw InputError(name + ": " + *fault);
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skip_image, nullptr);
  std::string folder_name = folder.string();
  if (!folder_name.empty() && !folder_name.ends_with('/')) folder_name += '/';
  BufferFiles files{folder_name, {}};
  loader.SetFsCallbacks({buffer_file_exists, buffer_file_path, read_buffer_file, write_no_file, &files});
  tinygltf::Model gltf;
  std::string error, warning;
  const auto size = static_cast<unsigned int>(bytes.size());
  const bool read = binary ? loader.LoadBinaryFromMemory(&gltf, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()), size, folder.string())
                           : loader.LoadASCIIFromString(&gltf, &error, &warning, bytes.data(), size, folder.string());
  if (!read) {
    // tinygltf's own reason quotes the uri whole (megabytes for a data: uri): its first 200 bytes.
    const std::string reason = !files.refusal.empty() ? files.refusal : error.substr(0, std::min<size_t>(error.find('\n'), 200));
    throw InputError(name + ": not a glTF 2.0 file vkray can read: " + (reason.empty() ? "tinygltf gave no reason" : reason));
  }
  return GltfReader(gltf, name).read();
}

}  // namespace vkray
