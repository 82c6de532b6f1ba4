#include "engine/scene/gltf_json_shape.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <vector>

namespace vkray {
namespace {

using Json = nlohmann::json;

// One pass of nlohmann's SAX parser over the text (no tree is built, nothing recurses): the nesting
// depth, the asset's version and each node's transform keys, read as they stream past.
class ShapeCheck {
 public:
  std::optional<std::string> fault;

  bool null() { return value(); }
  bool boolean(bool) { return value(); }
  bool number_integer(Json::number_integer_t) { return value(); }
  bool number_unsigned(Json::number_unsigned_t) { return value(); }
  bool number_float(Json::number_float_t, const std::string&) { return value(); }
  bool binary(Json::binary_t&) { return value(); }
  bool string(std::string& text) {
    // "asset": {"version": "2.0"}: the root object, then the asset object.
    if (frames_.size() == 2 && frames_[0].key == "asset" && frames_[1].object && frames_[1].key == "version") version_ = text;
    return value();
  }
  bool start_object(size_t) { return open(true); }
  bool start_array(size_t) { return open(false); }
  bool key(std::string& name) {
    frames_.back().key = name;
    if (in_node()) {
      const bool trs = name == "translation" || name == "rotation" || name == "scale";
      node_trs_ = node_trs_ || trs;
      node_matrix_ = node_matrix_ || name == "matrix";
    }
    return true;
  }
  bool end_object() {
    if (in_node() && node_trs_ && node_matrix_) {
      return stop("node " + std::to_string(frames_[1].items - 1) +
                  " has a matrix and translation, rotation or scale, which glTF 2.0 forbids together (5.25)");
    }
    frames_.pop_back();
    return true;
  }
  bool end_array() {
    frames_.pop_back();
    return true;
  }
  bool parse_error(size_t, const std::string&, const nlohmann::detail::exception&) { return false; }

  // Called once the whole text was read.
  void finish() {
    if (fault || !version_) return;  // no asset.version: tinygltf names it
    const std::string& version = *version_;
    if (version.rfind("2.", 0) != 0 || version.size() < 3) {
      fault = "asset.version is '" + version.substr(0, 20) + "'; vkray reads glTF 2.x";
    }
  }

 private:
  struct Frame {
    bool object;
    std::string key;   // an object's current key
    size_t items = 0;  // an array's values so far
  };

  // The root's "nodes" array holds the node objects: a key read there is one of a node's.
  bool in_node() const {
    return frames_.size() == 3 && frames_[0].key == "nodes" && !frames_[1].object && frames_[2].object;
  }
  bool value() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().items;
    return true;
  }
  bool open(bool object) {
    value();
    if (frames_.size() >= max_gltf_json_depth) {
      return stop("its JSON nests arrays and objects deeper than " + std::to_string(max_gltf_json_depth) +
                  " levels, which no glTF needs");
    }
    frames_.push_back({object, {}, 0});
    if (in_node()) node_trs_ = node_matrix_ = false;
    return true;
  }
  bool stop(std::string message) {
    fault = std::move(message);
    return false;
  }

  std::vector<Frame> frames_;
  std::optional<std::string> version_;
  bool node_trs_ = false, node_matrix_ = false;
};

}  // namespace

std::string_view gltf_json_text(std::string_view bytes, bool binary) {
  if (!binary) return bytes;
  // A .glb: a 12-byte header, then the JSON chunk's length and type and its bytes (glTF 2.0, 4.4).
  constexpr size_t header = 12, chunk_header = 8;
  if (bytes.size() < header + chunk_header) return bytes;
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + header, sizeof length);
  if (length > bytes.size() - header - chunk_header) return bytes;
  return bytes.substr(header + chunk_header, length);
}

std::optional<std::string> gltf_json_fault(std::string_view json) {
  ShapeCheck check;
  Json::sax_parse(json.begin(), json.end(), &check);
  check.finish();
  return check.fault;
}

}  // namespace vkray
