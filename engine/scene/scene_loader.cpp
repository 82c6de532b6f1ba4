#include "engine/scene/scene_loader.hpp"

#include "engine/typed_names.hpp"
#include "engine/scene/model_loader.hpp"
#include "engine/unit_vector.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

namespace vkray {
namespace {

using Json = nlohmann::json;

// A key as JSON writes it, without the quotes: a key holding a newline or another control character
// must not break the one-line message.
std::string printable(const std::string& key) {
  const std::string quoted = Json(key).dump();
  return quoted.substr(1, quoted.size() - 2);
}

// Appends value as compact JSON, stopping once `out` is longer than `limit`. Unlike dump(), which
// recurses once per nesting level and overflows the stack on [[[[...]]]] a million levels deep,
// this recurses at most `limit` levels, since each level adds a character.
void append_json(const Json& value, std::string& out, size_t limit) {
  if (out.size() > limit) return;
  if (!value.is_array() && !value.is_object()) {
    out += value.dump();
    return;
  }
  out += value.is_array() ? '[' : '{';
  bool first = true;
  for (const auto& item : value.items()) {
    if (out.size() > limit) return;
    if (!first) out += ',';
    first = false;
    if (value.is_object()) out += Json(item.key()).dump() + ":";
    append_json(item.value(), out, limit);
  }
  out += value.is_array() ? ']' : '}';
}

std::string describe(const Json& value) {
  std::string text;
  append_json(value, text, 40);
  return text.size() > 40 ? text.substr(0, 37) + "..." : text;
}

// A JSON value together with its path from the root, so every check can say where it failed.
class Node {
 public:
  Node(const Json& value, std::string path, const std::string& file) : value_(value), path_(std::move(path)), file_(file) {}

  // "<file>: <JSON path>", the start of its messages.
  std::string where() const { return file_ + ": " + (path_.empty() ? "top level" : path_); }
  [[noreturn]] void fail(const std::string& message) const { throw InputError(where() + ": " + message); }

  const Json& json() const { return value_; }
  bool has(const char* key) const { return value_.contains(key); }

  // An object whose keys are all in `allowed`; an unknown key fails with the nearest allowed name.
  const Node& expect_object(std::initializer_list<const char*> allowed) const {
    if (!value_.is_object()) fail("expected an object, got " + describe(value_));
    for (const auto& item : value_.items()) {
      if (std::find_if(allowed.begin(), allowed.end(), [&](const char* k) { return item.key() == k; }) != allowed.end()) {
        continue;
      }
      std::string message = "unknown key '" + printable(item.key()) + "'";
      const std::vector<std::string> names(allowed.begin(), allowed.end());
      if (const auto nearest = nearest_name(item.key(), names)) {
        message += " (did you mean '" + *nearest + "'?)";
      } else {
        std::string list;
        for (const char* key : allowed) {
          if (!list.empty()) list += ", ";
          list += key;
        }
        message += " (expected one of: " + list + ")";
      }
      Node(item.value(), child_path(item.key()), file_).fail(message);
    }
    return *this;
  }

  Node at(const char* key) const {
    if (!value_.contains(key)) fail(std::string("missing required key '") + key + "'");
    return Node(value_.at(key), child_path(key), file_);
  }

  std::vector<Node> elements() const {
    if (!value_.is_array()) fail("expected an array, got " + describe(value_));
    std::vector<Node> nodes;
    for (size_t i = 0; i < value_.size(); ++i) nodes.emplace_back(value_[i], path_ + "[" + std::to_string(i) + "]", file_);
    return nodes;
  }

  double number() const {
    if (!value_.is_number()) fail("expected a number, got " + describe(value_));
    const double result = value_.get<double>();
    if (!std::isfinite(result)) fail("number is not finite");
    return result;
  }

  glm::dvec3 vec3() const {
    const auto items = elements();
    if (items.size() != 3) fail("expected 3 numbers [x, y, z], got " + describe(value_));
    return {items[0].number(), items[1].number(), items[2].number()};
  }

  // A position: a vec3 whose components are coordinates.
  glm::dvec3 point() const {
    const auto items = elements();
    if (items.size() != 3) fail("expected 3 numbers [x, y, z], got " + describe(value_));
    return {items[0].coordinate(), items[1].coordinate(), items[2].coordinate()};
  }

  double coordinate() const {
    const double result = number();
    if (std::abs(result) > max_coordinate) fail("magnitude above the supported " + describe(Json(max_coordinate)));
    return result;
  }

  glm::dvec3 nonzero_vec3() const {
    const glm::dvec3 result = vec3();
    if (result == glm::dvec3(0.0)) fail("must not be the zero vector");
    return result;
  }

  uint32_t index(uint64_t limit, const char* what) const {
    if (!value_.is_number_integer() && !(value_.is_number_float() && std::floor(number()) == number())) {
      fail("expected a whole number, got " + describe(value_));
    }
    const double result = number();
    if (result < 0 || result >= static_cast<double>(limit)) {
      fail(std::string(what) + " " + describe(value_) + " is out of range " +
           (limit == 0 ? std::string("(there are none)") : "0.." + std::to_string(limit - 1)));
    }
    return static_cast<uint32_t>(result);
  }

  // A ray mask (see Mask): a whole number 0..255.
  Mask mask() const { return static_cast<Mask>(index(uint64_t{every_mask_bit} + 1, "mask")); }

  std::string string() const {
    if (!value_.is_string()) fail("expected a string, got " + describe(value_));
    return value_.get<std::string>();
  }

 private:
  std::string child_path(const std::string& key) const { return path_.empty() ? printable(key) : path_ + "." + printable(key); }

  const Json& value_;
  std::string path_;
  const std::string& file_;
};

// OpenCV's [R t] as 4 rows of 4 numbers.
Matrix4 parse_matrix4(const Node& node) {
  const auto rows = node.elements();
  if (rows.size() != 4) node.fail("expected 4 rows of 4 numbers, [[r00, r01, r02, tx], ..., [0, 0, 0, 1]]");
  Matrix4 matrix{};
  for (size_t r = 0; r < 4; ++r) {
    const auto entries = rows[r].elements();
    if (entries.size() != 4) rows[r].fail("expected 4 numbers, got " + describe(rows[r].json()));
    for (size_t c = 0; c < 4; ++c) matrix[r][c] = entries[c].number();
  }
  return matrix;
}

PinholeIntrinsics parse_intrinsics(const Node& node) {
  node.expect_object({"fx", "fy", "cx", "cy"});
  PinholeIntrinsics k{node.at("fx").number(), node.at("fy").number(), node.at("cx").number(), node.at("cy").number()};
  if (!(k.fx > 0.0)) node.at("fx").fail("focal length must be > 0 pixels, got " + describe(node.at("fx").json()));
  if (!(k.fy > 0.0)) node.at("fy").fail("focal length must be > 0 pixels, got " + describe(node.at("fy").json()));
  // A principal point beyond 1e9 pixels or a ratio of focal lengths beyond 1e9 is a typo, and
  // would put the image plane's float32 basis out of range.
  for (const char* key : {"cx", "cy"}) {
    if (!(std::abs(node.at(key).number()) <= 1e9)) node.at(key).fail("must be within 1e9 pixels, got " + describe(node.at(key).json()));
  }
  if (!(k.fx / k.fy <= 1e9 && k.fy / k.fx <= 1e9)) node.at("fy").fail("fx / fy must be within 1e-9 .. 1e9");
  return k;
}

// A camera object. With a `base`, every key is optional and overrides that camera's (--camera).
// Where it stands: from, to and up, or OpenCV's world_to_camera; its image plane: fovy, or OpenCV's
// intrinsics in pixels.
Camera parse_camera(const Node& node, const Camera* base = nullptr) {
  node.expect_object({"from", "to", "up", "fovy", "intrinsics", "world_to_camera", "projection", "view_height"});
  Camera camera = base ? *base : Camera{};
  if (node.has("world_to_camera")) {
    const Node matrix = node.at("world_to_camera");
    for (const char* key : {"from", "to", "up"}) {
      if (node.has(key)) matrix.fail(std::string("give either world_to_camera or from, to and up, not both (") + key + " given)");
    }
    std::string fault;
    camera = with_world_to_camera(camera, parse_matrix4(matrix), fault);
    if (!fault.empty()) matrix.fail(fault);
    // The camera it places is held to from's limit: the manifest and --camera print it back.
    const glm::dvec3& from = camera.from;
    if (!within_coordinate_bound(from)) {
      matrix.fail("places the camera beyond the supported coordinate magnitude " + describe(Json(max_coordinate)));
    }
  } else {
    if (!base || node.has("from")) camera.from = node.at("from").point();
    if (!base || node.has("to")) camera.to = node.at("to").point();
    if (camera.from == camera.to) {
      if (node.has("to")) node.at("to").fail("must differ from camera.from");
      node.at("from").fail("must differ from camera.to");
    }
    if (node.has("up")) camera.up = node.at("up").nonzero_vec3();
  }
  if (node.has("projection")) {
    const Node name = node.at("projection");
    const auto projection = projection_from_name(name.string());
    if (!projection) name.fail("unknown projection '" + name.string() + "' (perspective, orthographic, equirectangular)");
    camera.projection = *projection;
  }
  if (node.has("view_height")) {
    const Node height = node.at("view_height");
    camera.view_height = height.number();
    if (!(camera.view_height > 0.0 && camera.view_height <= max_coordinate)) {
      height.fail("the image's height in world units must be in (0, 1e15], got " + describe(height.json()));
    }
  }
  if (node.has("view_height") && camera.projection != Projection::orthographic) {
    node.at("view_height").fail("view_height describes an orthographic camera; this one is " +
                                std::string(projection_name(camera.projection)));
  }
  if (camera.projection == Projection::orthographic && !(camera.view_height > 0.0)) {
    node.fail("an orthographic camera needs view_height, the image's height in world units");
  }
  if (camera.projection != Projection::perspective) {
    // fovy and intrinsics describe a perspective camera's image plane: none here.
    if (node.has("intrinsics")) node.at("intrinsics").fail("intrinsics describe a perspective camera, not an " + std::string(projection_name(camera.projection)) + " one");
    camera.intrinsics.reset();
    if (node.has("fovy")) node.at("fovy").fail("fovy describes a perspective camera");
    return camera;
  }
  if (node.has("intrinsics")) {
    if (node.has("fovy")) node.at("intrinsics").fail("give either fovy or intrinsics, not both");
    camera.intrinsics = parse_intrinsics(node.at("intrinsics"));
  } else if (!base || node.has("fovy")) {
    const Node fovy = node.at("fovy");
    camera.fovy_degrees = fovy.number();
    if (!(camera.fovy_degrees > 0.0 && camera.fovy_degrees < 180.0)) {
      fovy.fail("field of view must be in (0, 180) degrees, got " + describe(fovy.json()));
    }
    camera.intrinsics.reset();
  }
  return camera;
}

void parse_image(const Node& node, Scene& scene) {
  node.expect_object({"width", "height"});
  scene.width = node.has("width") ? node.at("width").index(uint64_t{max_image_side} + 1, "width") : default_image_width;
  scene.height = node.has("height") ? node.at("height").index(uint64_t{max_image_side} + 1, "height") : default_image_height;
  try {
    check_image_size(scene.width, scene.height);
  } catch (const InputError& error) {
    node.fail(error.what());
  }
}

Sphere parse_sphere(const Node& node) {
  node.expect_object({"center", "radius", "mask"});
  Sphere sphere{node.at("center").point(), node.at("radius").coordinate()};
  if (!(sphere.radius > 0.0)) node.at("radius").fail("must be > 0, got " + describe(node.at("radius").json()));
  if (node.has("mask")) sphere.mask = node.at("mask").mask();
  return sphere;
}

Plane parse_plane(const Node& node) {
  node.expect_object({"point", "normal", "mask"});
  Plane plane{node.at("point").point(), unit_vector(node.at("normal").nonzero_vec3())};
  if (node.has("mask")) plane.mask = node.at("mask").mask();
  return plane;
}

// A transform object: positions scaled, then rotated, then translated.
struct ParsedTransform {
  glm::dvec3 scale{1.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
  glm::dvec3 translation{0.0};
  glm::dmat3 linear() const {
    return glm::mat3_cast(rotation) * glm::dmat3(glm::dvec3(scale.x, 0.0, 0.0), glm::dvec3(0.0, scale.y, 0.0), glm::dvec3(0.0, 0.0, scale.z));
  }
};

ParsedTransform parse_transform(const Node& node) {
  node.expect_object({"scale", "rotate", "translate"});
  glm::dvec3 scale(1.0);
  if (node.has("scale")) {  // (non-zero: a transform is invertible, as an instance's must be)
    const Node value = node.at("scale");
    scale = value.json().is_array() ? value.vec3() : glm::dvec3(value.number());
    if (scale.x == 0.0 || scale.y == 0.0 || scale.z == 0.0) value.fail("scale factors must be non-zero");
  }
  glm::dquat rotation(1.0, 0.0, 0.0, 0.0);
  if (node.has("rotate")) {
    const Node rotate = node.at("rotate");
    rotate.expect_object({"axis", "degrees"});
    const glm::dvec3 axis = unit_vector(rotate.at("axis").nonzero_vec3());
    rotation = glm::angleAxis(rotate.at("degrees").number() * std::numbers::pi / 180.0, axis);
  }
  const glm::dvec3 translation = node.has("translate") ? node.at("translate").vec3() : glm::dvec3(0.0);
  return {scale, rotation, translation};
}

void apply_transform(const Node& node, Mesh& mesh) {
  const ParsedTransform transform = parse_transform(node);
  for (auto& position : mesh.positions) position = transform.rotation * (transform.scale * position) + transform.translation;
  // Normals through the inverse transpose of rotation times scale: rotation divided by the scale.
  for (auto& normal : mesh.normals) normal = transform.rotation * (normal / transform.scale);
}

// A mesh entry's meshes: its own positions and triangles, or those of the model file it names (a
// glTF's nodes give several), each through the entry's transform.
std::vector<Mesh> parse_meshes(const Node& node, const std::filesystem::path& base_dir, const ModelFileLoader& load_model) {
  node.expect_object({"positions", "triangles", "model", "obj", "transform", "mask", "name"});
  std::vector<Mesh> meshes;
  if (node.has("model") || node.has("obj")) {
    if (node.has("model") && node.has("obj")) node.fail("give 'model' ('obj' is its older name), not both");
    if (node.has("positions") || node.has("triangles")) node.fail("give either 'model' or 'positions' and 'triangles', not both");
    const Node file = node.at(node.has("model") ? "model" : "obj");
    // The system would read a name only up to a NUL ("cow.obj\u0000junk" as cow.obj).
    if (file.string().find('\0') != std::string::npos) file.fail("a file name cannot hold a NUL character (\\u0000)");
    const std::filesystem::path path = base_dir / file.string();
    if (!is_model_extension(lower_extension(path))) {
      file.fail("unknown kind of model '" + lower_extension(path) + "' (a model is " + model_extension_list() + ")");
    }
    try {
      meshes = load_model(path);
    } catch (const InputError& error) {
      file.fail(error.what());
    }
  } else {
    Mesh& mesh = meshes.emplace_back();
    for (const Node& position : node.at("positions").elements()) mesh.positions.push_back(position.vec3());
    for (const Node& triangle : node.at("triangles").elements()) {
      const auto corners = triangle.elements();
      if (corners.size() != 3) triangle.fail("expected 3 vertex indices [i, j, k], got " + describe(triangle.json()));
      mesh.triangles.push_back({corners[0].index(mesh.positions.size(), "vertex index"),
                                corners[1].index(mesh.positions.size(), "vertex index"),
                                corners[2].index(mesh.positions.size(), "vertex index")});
    }
    if (mesh.triangles.empty()) node.at("triangles").fail("a mesh needs at least one triangle");
    mesh.source = node.where();
  }
  if (node.has("name") && meshes.size() != 1) {
    node.at("name").fail("a named mesh is placed by instances as one mesh; the model gives " + std::to_string(meshes.size()));
  }
  if (node.has("name") && node.has("mask")) {
    node.at("mask").fail("a named mesh is drawn by its instances, whose masks stand for its own: give each instance the mask");
  }
  for (Mesh& mesh : meshes) {
    mesh.instanced = node.has("name");  // drawn only where instances place it
    if (node.has("mask")) mesh.mask = node.at("mask").mask();
    if (node.has("transform")) apply_transform(node.at("transform"), mesh);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      const glm::dvec3& p = mesh.positions[i];
      if (!within_coordinate_bound(p)) {
        node.fail("vertex " + std::to_string(i) + (meshes.size() > 1 ? " of " + mesh.source : "") +
                  " lies beyond the supported coordinate magnitude " + describe(Json(max_coordinate)) +
                  (node.has("transform") ? " after the transform" : ""));
      }
    }
  }
  return meshes;
}

// 1-based line and column of the 0-based byte offset `byte`.
std::string line_and_column(std::string_view text, size_t byte, size_t first_line = 1) {
  byte = std::min(byte, text.size());
  const size_t line = first_line + static_cast<size_t>(std::count(text.begin(), text.begin() + static_cast<long>(byte), '\n'));
  const size_t line_start = byte == 0 ? std::string_view::npos : text.rfind('\n', byte - 1);
  const size_t column = 1 + (line_start == std::string_view::npos ? byte : byte - line_start - 1);
  return std::to_string(line) + ":" + std::to_string(column);
}

// Walks a document to say where it failed, by JSON path: nlohmann::json refuses a number that
// overflows a double (1e999) with out_of_range.406, which carries no position; and it accepts an
// object with the same key twice, keeping the last, which a scene file must not do silently.
class JsonPathTracker : public Json::json_sax_t {
 public:
  std::string path;           // where parsing stopped
  std::string duplicate_key;  // the key met twice in one object, if that is why

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return levels_.push_back({false, 0, {}, {}}), true; }
  bool key(string_t& member) override {
    Level& level = levels_.back();
    level.key = member;
    if (level.keys.insert(member).second) return true;
    duplicate_key = member;
    return stop();
  }
  bool end_object() override { return levels_.pop_back(), value(); }
  bool start_array(std::size_t) override { return levels_.push_back({true, 0, {}, {}}), true; }
  bool end_array() override { return levels_.pop_back(), value(); }
  bool parse_error(std::size_t, const std::string&, const Json::exception&) override { return stop(); }

 private:
  struct Level {
    bool array;
    size_t index;  // of the current element, in an array
    std::string key;  // of the current member, in an object
    std::set<std::string> keys;  // seen so far, in an object
  };
  bool value() {
    if (!levels_.empty() && levels_.back().array) ++levels_.back().index;
    return true;
  }
  bool stop() {
    for (const Level& level : levels_) {
      path += level.array ? "[" + std::to_string(level.index) + "]" : (path.empty() ? "" : ".") + printable(level.key);
    }
    return false;
  }
  std::vector<Level> levels_;
};

// Parses a whole JSON document; every error names `name` and the line and column or JSON path.
Json parse_document(std::string_view json_text, const std::string& name) {
  refuse_invalid_json(json_text, name);
  Json root;
  try {
    root = Json::parse(json_text);
  } catch (const Json::out_of_range& error) {
    JsonPathTracker tracker;
    Json::sax_parse(json_text, &tracker);
    std::string detail = error.what();  // "[json.exception.out_of_range.406] number overflow parsing '1e999'"
    if (const size_t bracket = detail.find("] "); bracket != std::string::npos) detail = detail.substr(bracket + 2);
    if (detail.size() > 80) detail = detail.substr(0, 77) + "...";  // the number may have thousands of digits
    throw InputError(name + ": " + (tracker.path.empty() ? "top level" : tracker.path) + ": number is not finite (" + detail + ")");
  }
  JsonPathTracker tracker;
  if (!Json::sax_parse(json_text, &tracker) && !tracker.duplicate_key.empty()) {
    throw InputError(name + ": " + tracker.path + ": the key '" + printable(tracker.duplicate_key) +
                     "' appears twice in one object (which one is meant?)");
  }
  return root;
}

}  // namespace

void refuse_nul_bytes(std::string_view text, const std::string& name, size_t first_line) {
  if (const size_t nul = text.find('\0'); nul != std::string_view::npos) {
    throw InputError(name + ":" + line_and_column(text, nul, first_line) +
                     ": a NUL byte: a JSON file is text, and the parser would stop there");
  }
}

void refuse_invalid_json(std::string_view text, const std::string& name, size_t first_line) {
  refuse_nul_bytes(text, name, first_line);
  if (Json::accept(text)) return;
  try {
    const Json ignored = Json::parse(text);  // reached only for text accept() refused: it throws
  } catch (const Json::parse_error& error) {
    // nlohmann's message starts with "[json.exception.parse_error.101] parse error at line L, column C: ";
    // keep the part after "parse error" and put the location in our own form.
    std::string detail = error.what();
    if (const size_t colon = detail.find(": ", detail.find("parse error")); colon != std::string::npos) {
      detail = detail.substr(colon + 2);
    }
    const size_t at = error.byte == 0 ? 0 : std::min(error.byte - 1, text.size());
    // Python's json.dumps writes NaN, Infinity and -Infinity (allow_nan=True), which JSON has not:
    // the parser stops at their first letter.
    if (at < text.size() && (text[at] == 'N' || text[at] == 'I')) {
      detail += " (JSON has no NaN or Infinity, which Python's json.dumps writes: give finite numbers)";
    }
    throw InputError(name + ":" + line_and_column(text, at, first_line) + ": invalid JSON: " + detail);
  } catch (const Json::out_of_range&) {
    // A number beyond a double (1e999): parse_document names its JSON path.
  }
}

Scene parse_scene(std::string_view json_text, const std::string& name, const std::filesystem::path& base_dir,
                  const ModelFileLoader& load_model) {
  const Json root = parse_document(json_text, name);
  const Node top(root, "", name);
  top.expect_object({"camera", "image", "spheres", "planes", "meshes", "instances"});
  Scene scene;
  scene.camera = parse_camera(top.at("camera"));
  if (top.has("image")) parse_image(top.at("image"), scene);
  if (top.has("spheres")) {
    for (const Node& sphere : top.at("spheres").elements()) scene.spheres.push_back(parse_sphere(sphere));
  }
  if (top.has("planes")) {
    for (const Node& plane : top.at("planes").elements()) scene.planes.push_back(parse_plane(plane));
  }
  std::map<std::string, uint32_t> named;  // a named entry's mesh
  if (top.has("meshes")) {
    for (const Node& entry : top.at("meshes").elements()) {
      for (Mesh& mesh : parse_meshes(entry, base_dir, load_model)) scene.meshes.push_back(std::move(mesh));
      if (!entry.has("name")) continue;
      const Node mesh_name = entry.at("name");
      if (!named.emplace(mesh_name.string(), static_cast<uint32_t>(scene.meshes.size() - 1)).second) {
        mesh_name.fail("another mesh is named '" + printable(mesh_name.string()) + "'");
      }
    }
  }
  if (top.has("instances")) {
    std::vector<Bounds> mesh_boxes;  // instanced_mesh_boxes, found at the first transform
    for (const Node& entry : top.at("instances").elements()) {
      entry.expect_object({"mesh", "transform", "mask"});
      const Node placed_name = entry.at("mesh");
      const auto found = named.find(placed_name.string());
      if (found == named.end()) {
        std::string names;
        for (const auto& [known, mesh] : named) names += (names.empty() ? "'" : ", '") + printable(known) + "'";
        placed_name.fail("no mesh is named '" + printable(placed_name.string()) + "' (" +
                         (names.empty() ? "none is named" : "named: " + names) + ")");
      }
      Instance instance;
      instance.mesh = found->second;
      if (entry.has("transform")) {
        const ParsedTransform transform = parse_transform(entry.at("transform"));
        instance.linear = transform.linear();
        instance.translation = transform.translation;
        // Where it places the mesh's box, and whether float32 walks it as the reference does: the
        // check every way in takes (check_transform), here naming the file and the entry.
        if (mesh_boxes.empty()) mesh_boxes = instanced_mesh_boxes(scene);
        check_transform(instance, mesh_boxes[instance.mesh], entry.where());
      }
      if (entry.has("mask")) instance.mask = entry.at("mask").mask();
      scene.instances.push_back(instance);
    }
  }
  return scene;
}

Camera parse_camera_override(std::string_view json_text, const std::string& name, const Camera& base) {
  const Json root = parse_document(json_text, name);
  return parse_camera(Node(root, "", name), &base);
}

Camera parse_camera_object(std::string_view json_text, const std::string& name, InstancePoses* poses) {
  Json root = parse_document(json_text, name);
  if (!poses || !root.is_object() || !root.contains("instances")) return parse_camera(Node(root, "", name));
  const Json placed = std::move(root["instances"]);
  root.erase("instances");
  for (const Node& entry : Node(placed, "instances", name).elements()) {
    entry.expect_object({"instance", "transform"});
    // The range is the scene's, checked where the scene is known (check_view_poses).
    poses->instances.push_back(entry.at("instance").index(uint64_t{std::numeric_limits<uint32_t>::max()}, "instance"));
    const ParsedTransform transform = parse_transform(entry.at("transform"));
    poses->transforms.push_back(affine_matrix(transform.linear(), transform.translation));
  }
  return parse_camera(Node(root, "", name));
}

void check_input_file(const std::filesystem::path& path, const std::string& what) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw InputError(path.string() + (std::filesystem::exists(path, error) ? ": is not a regular file" : ": no such " + what));
  }
}

std::string read_input_file(const std::filesystem::path& path, const std::string& what) {
  check_input_file(path, what);
  std::ifstream file(path, std::ios::binary);
  std::ostringstream contents;
  contents << file.rdbuf();
  if (!file) throw InputError(path.string() + ": cannot read the " + what);
  return contents.str();
}

Scene load_scene_file(const std::filesystem::path& path) {
  return parse_scene(read_input_file(path, "scene file"), path.string(), path.parent_path(),
                     [](const std::filesystem::path& model) { return load_model(model).meshes; });
}

}  // namespace vkray
