#include "engine/scene/ply_loader.hpp"

#include "engine/scene/polygon_triangulation.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <optional>
#include <vector>

namespace vkray {
namespace {

enum class Scalar { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

std::optional<Scalar> scalar_from_name(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, Scalar>, 16> names{{
      {"char", Scalar::int8}, {"int8", Scalar::int8}, {"uchar", Scalar::uint8}, {"uint8", Scalar::uint8},
      {"short", Scalar::int16}, {"int16", Scalar::int16}, {"ushort", Scalar::uint16}, {"uint16", Scalar::uint16},
      {"int", Scalar::int32}, {"int32", Scalar::int32}, {"uint", Scalar::uint32}, {"uint32", Scalar::uint32},
      {"float", Scalar::float32}, {"float32", Scalar::float32}, {"double", Scalar::float64}, {"float64", Scalar::float64},
  }};
  for (const auto& [text, scalar] : names) {
    if (name == text) return scalar;
  }
  return std::nullopt;
}

size_t byte_size(Scalar scalar) {
  switch (scalar) {
    case Scalar::int8: case Scalar::uint8: return 1;
    case Scalar::int16: case Scalar::uint16: return 2;
    case Scalar::int32: case Scalar::uint32: case Scalar::float32: return 4;
    case Scalar::float64: return 8;
  }
  return 0;
}

// The values an integer type holds; {0, 0} for the floating types.
std::pair<double, double> integer_range(Scalar scalar) {
  switch (scalar) {
    case Scalar::int8: return {INT8_MIN, INT8_MAX};
    case Scalar::uint8: return {0, UINT8_MAX};
    case Scalar::int16: return {INT16_MIN, INT16_MAX};
    case Scalar::uint16: return {0, UINT16_MAX};
    case Scalar::int32: return {INT32_MIN, INT32_MAX};
    case Scalar::uint32: return {0, UINT32_MAX};
    case Scalar::float32: case Scalar::float64: return {0, 0};
  }
  return {0, 0};
}

struct Property {
  std::string name;
  Scalar type;                      // of the value, or of a list's items
  std::optional<Scalar> list_count;  // a list: the type of its length
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Format { ascii, little_endian, big_endian };

struct Header {
  Format format = Format::ascii;
  std::vector<Element> elements;
  size_t body = 0;       // byte offset of the body
  size_t body_line = 0;  // its line number, for an ASCII body
};

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t at = 0;
  while ((at = line.find_first_not_of(" \t\r", at)) != std::string_view::npos) {
    const size_t end = std::min(line.find_first_of(" \t\r", at), line.size());
    tokens.push_back(line.substr(at, end - at));
    at = end;
  }
  return tokens;
}

Header read_header(std::string_view bytes, const std::string& name) {
  Header header;
  size_t at = 0, line_number = 0;
  bool format_seen = false;
  for (;;) {
    ++line_number;
    const size_t end = bytes.find('\n', at);
    const std::string where = name + ":" + std::to_string(line_number) + ": ";
    if (end == std::string_view::npos) throw InputError(where + "the header ends without 'end_header'");
    const std::string_view line = bytes.substr(at, end - at);
    at = end + 1;
    const auto tokens = words(line);
    if (line_number == 1) {
      if (tokens.size() != 1 || tokens[0] != "ply") throw InputError(name + ":1: not a PLY file (its first line is not 'ply')");
      continue;
    }
    if (tokens.empty() || tokens[0] == "comment" || tokens[0] == "obj_info") continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "end_header") {
      if (!format_seen) throw InputError(where + "no 'format' line before 'end_header'");
      header.body = at;
      header.body_line = line_number + 1;
      return header;
    }
    if (keyword == "format") {
      if (format_seen) throw InputError(where + "a second 'format' line (a header has one)");
      if (tokens.size() != 3 || tokens[2] != "1.0") throw InputError(where + "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (tokens[1] == "ascii") header.format = Format::ascii;
      else if (tokens[1] == "binary_little_endian") header.format = Format::little_endian;
      else if (tokens[1] == "binary_big_endian") header.format = Format::big_endian;
      else throw InputError(where + "unknown format '" + std::string(tokens[1]) + "'");
      format_seen = true;
    } else if (keyword == "element") {
      uint64_t count = 0;
      if (tokens.size() != 3 || std::from_chars(tokens[2].data(), tokens[2].data() + tokens[2].size(), count).ec != std::errc{} ||
          std::to_string(count) != tokens[2]) {
        throw InputError(where + "expected 'element NAME COUNT'");
      }
      // One vertex and one face element: a face's indices and the vertices' attributes are read as
      // one list each (a second vertex element without normals left its vertices without any).
      const bool unique = tokens[1] == "vertex" || tokens[1] == "face";
      if (unique && std::any_of(header.elements.begin(), header.elements.end(), [&](const Element& e) { return e.name == tokens[1]; })) {
        throw InputError(where + "a second '" + std::string(tokens[1]) + "' element (vkray reads one)");
      }
      header.elements.push_back({std::string(tokens[1]), count, {}});
    } else if (keyword == "property") {
      if (header.elements.empty()) throw InputError(where + "a property before any element");
      Property property;
      const bool list = tokens.size() == 5 && tokens[1] == "list";
      if (!list && tokens.size() != 3) throw InputError(where + "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME'");
      const auto type = scalar_from_name(tokens[list ? 3 : 1]);
      if (!type) throw InputError(where + "unknown type '" + std::string(tokens[list ? 3 : 1]) + "'");
      property.type = *type;
      if (list) {
        property.list_count = scalar_from_name(tokens[2]);
        if (!property.list_count || *property.list_count == Scalar::float32 || *property.list_count == Scalar::float64) {
          throw InputError(where + "a list's length must have an integer type, not '" + std::string(tokens[2]) + "'");
        }
      }
      property.name = tokens.back();
      header.elements.back().properties.push_back(std::move(property));
    } else {
      throw InputError(where + "unknown header line '" + std::string(keyword) + "' (expected format, element, property, comment or end_header)");
    }
  }
}

// The body's numbers in file order, as doubles (every PLY type fits one exactly).
class AsciiBody {
 public:
  AsciiBody(std::string_view bytes, size_t at, size_t line, const std::string& name)
      : bytes_(bytes), at_(at), line_(line), name_(name) {}
  double next(Scalar type) {
    while (at_ < bytes_.size() && (bytes_[at_] == ' ' || bytes_[at_] == '\t' || bytes_[at_] == '\r' || bytes_[at_] == '\n')) {
      line_ += bytes_[at_++] == '\n';
    }
    if (at_ == bytes_.size()) fail("the file ends before the last element (cut off?)");
    const char* first = bytes_.data() + at_;
    const char* last = bytes_.data() + bytes_.size();
    double value = 0.0;
    std::from_chars_result result{};
    if (type == Scalar::float32 || type == Scalar::float64) {
      result = std::from_chars(first, last, value);
    } else {
      int64_t integer = 0;
      result = std::from_chars(first, last, integer);
      value = static_cast<double>(integer);
    }
    const char* end = std::find_if(first, last, [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; });
    const std::string text(first, std::min<size_t>(static_cast<size_t>(end - first), 40));
    if (result.ec != std::errc{} || result.ptr != end) {
      fail("'" + text + "' is not " + (type == Scalar::float32 || type == Scalar::float64 ? "a number" : "an integer"));
    }
    if (const auto [least, most] = integer_range(type); least < most && !(value >= least && value <= most)) {
      fail("'" + text + "' is beyond its type's range (" + std::to_string(static_cast<int64_t>(least)) + " to " +
           std::to_string(static_cast<int64_t>(most)) + ")");
    }
    at_ = static_cast<size_t>(end - bytes_.data());
    return value;
  }
  // The fewest bytes an element of `min_values` values takes: a digit and a separator each.
  size_t room(size_t min_values) const { return (bytes_.size() - at_) / std::max<size_t>(1, 2 * min_values); }
  [[noreturn]] void fail(const std::string& message) const { throw InputError(name_ + ":" + std::to_string(line_) + ": " + message); }

 private:
  std::string_view bytes_;
  size_t at_;
  size_t line_;
  const std::string& name_;
};

class BinaryBody {
 public:
  BinaryBody(std::string_view bytes, size_t at, bool big_endian, const std::string& name)
      : bytes_(bytes), at_(at), swap_(big_endian != (std::endian::native == std::endian::big)), name_(name) {}
  double next(Scalar type) {
    const size_t size = byte_size(type);
    if (bytes_.size() - at_ < size) fail("the file ends before the last element (cut off?)");
    std::array<char, 8> raw{};
    std::memcpy(raw.data(), bytes_.data() + at_, size);
    if (swap_) std::reverse(raw.begin(), raw.begin() + static_cast<long>(size));
    at_ += size;
    switch (type) {
      case Scalar::int8: return load<int8_t>(raw);
      case Scalar::uint8: return load<uint8_t>(raw);
      case Scalar::int16: return load<int16_t>(raw);
      case Scalar::uint16: return load<uint16_t>(raw);
      case Scalar::int32: return load<int32_t>(raw);
      case Scalar::uint32: return load<uint32_t>(raw);
      case Scalar::float32: return load<float>(raw);
      case Scalar::float64: return load<double>(raw);
    }
    return 0.0;
  }
  size_t room(size_t min_bytes) const { return (bytes_.size() - at_) / std::max<size_t>(1, min_bytes); }
  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(name_ + ": byte " + std::to_string(at_) + ": " + message);
  }

 private:
  template <typename T>
  static double load(const std::array<char, 8>& raw) {
    T value;
    std::memcpy(&value, raw.data(), sizeof(T));
    return static_cast<double>(value);
  }
  std::string_view bytes_;
  size_t at_;
  bool swap_;
  const std::string& name_;
};

// Where the vertex element's properties are: indices among its values that are not lists (a
// record's values as read_body keeps them).
struct VertexLayout {
  std::array<size_t, 3> position{};
  std::optional<std::array<size_t, 3>> normal;
  std::optional<std::array<size_t, 2>> texcoord;
};

std::optional<size_t> find_property(const Element& element, std::string_view name) {
  size_t value = 0;
  for (const Property& property : element.properties) {
    if (property.list_count) continue;
    if (property.name == name) return value;
    ++value;
  }
  return std::nullopt;
}

template <size_t N>
std::optional<std::array<size_t, N>> find_properties(const Element& element, const std::array<const char*, N>& names) {
  std::array<size_t, N> found{};
  for (size_t k = 0; k < N; ++k) {
    const auto at = find_property(element, names[k]);
    if (!at) return std::nullopt;
    found[k] = *at;
  }
  return found;
}

VertexLayout vertex_layout(const Element& vertex, const std::string& name) {
  VertexLayout layout;
  const auto position = find_properties<3>(vertex, {"x", "y", "z"});
  if (!position) throw InputError(name + ": the vertex element has no x, y and z properties");
  layout.position = *position;
  layout.normal = find_properties<3>(vertex, {"nx", "ny", "nz"});
  for (const auto& names : {std::array{"u", "v"}, std::array{"s", "t"}, std::array{"texture_u", "texture_v"}}) {
    if (!layout.texcoord) layout.texcoord = find_properties<2>(vertex, names);
  }
  return layout;
}

// The face's list property of one of `names`, by its number among the face's properties.
std::optional<size_t> face_list(const Element& face, std::initializer_list<std::string_view> names) {
  for (size_t i = 0; i < face.properties.size(); ++i) {
    const Property& property = face.properties[i];
    if (property.list_count && std::find(names.begin(), names.end(), property.name) != names.end()) return i;
  }
  return std::nullopt;
}

// The fewest values (ASCII) or bytes (binary) one record of `element` takes: an empty list has its
// length alone. What the rest of the file can hold bounds a count before anything is allocated.
size_t least_record(const Element& element, bool binary) {
  size_t least = 0;
  for (const Property& property : element.properties) {
    least += binary ? byte_size(property.list_count.value_or(property.type)) : 1;
  }
  return least;
}

template <typename Body>
Mesh read_body(const Header& header, Body& body, const std::string& name) {
  Mesh mesh;
  const bool binary = header.format != Format::ascii;
  std::vector<double> values;  // one record's, its lists left out
  std::vector<glm::dvec3> polygon;
  std::vector<uint32_t> corners;
  std::vector<double> corner_texcoords;  // a face's texcoord list: u, v a corner
  std::vector<std::array<uint32_t, 3>> triangles;
  // Texture coordinates by face corner (MeshLab's face "texcoord" list), and each triangle's corners in them.
  std::vector<glm::dvec2> wedge_texcoords;
  std::vector<std::array<uint32_t, 3>> wedge_corners;
  bool vertices_read = false;
  for (const Element& element : header.elements) {
    if (element.count > body.room(least_record(element, binary))) {
      body.fail("element '" + element.name + "' counts " + std::to_string(element.count) +
                " records, more than the rest of the file can hold (cut off?)");
    }
    const bool is_vertex = element.name == "vertex", is_face = element.name == "face";
    std::optional<VertexLayout> layout;
    if (is_vertex) {
      layout = vertex_layout(element, name);
      mesh.positions.reserve(element.count);
    }
    constexpr size_t none = ~size_t{0};
    const size_t list = is_face ? face_list(element, {"vertex_indices", "vertex_index"}).value_or(none) : none;  // the face's corner list
    const size_t texcoord_list = is_face ? face_list(element, {"texcoord"}).value_or(none) : none;
    if (is_face && list == none) throw InputError(name + ": the face element has no vertex_indices list");
    if (is_face && (element.properties[list].type == Scalar::float32 || element.properties[list].type == Scalar::float64)) {
      throw InputError(name + ": the face element's vertex indices must have an integer type");
    }
    if (is_face && !vertices_read) throw InputError(name + ": the face element comes before the vertex element");
    vertices_read = vertices_read || is_vertex;
    // Records of no properties take no bytes: nothing to read, however many the header claims.
    if (element.properties.empty()) continue;
    for (uint64_t record = 0; record < element.count; ++record) {
      values.clear();
      corner_texcoords.clear();
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const Property& property = element.properties[p];
        if (!property.list_count) {
          values.push_back(body.next(property.type));
          continue;
        }
        const double length = body.next(*property.list_count);
        if (p == list && !(length >= 3 && length <= static_cast<double>(max_polygon_corners))) {
          body.fail("face " + std::to_string(record) + " has " + std::to_string(static_cast<int64_t>(length)) +
                    " corners (a face has 3 to " + std::to_string(max_polygon_corners) + ")");
        }
        if (length < 0) body.fail("a list of negative length");
        if (p == list) corners.clear();
        for (double k = 0; k < length; ++k) {
          const double value = body.next(property.type);
          if (p == texcoord_list) corner_texcoords.push_back(value);
          if (p != list) continue;
          if (!(value >= 0 && value < static_cast<double>(mesh.positions.size()))) {
            body.fail("face " + std::to_string(record) + " names vertex " + std::to_string(static_cast<int64_t>(value)) +
                      " of " + std::to_string(mesh.positions.size()));
          }
          corners.push_back(static_cast<uint32_t>(value));
        }
      }
      if (is_vertex) {
        const auto at = [&](size_t k) { return values[k]; };
        const glm::dvec3 position(at(layout->position[0]), at(layout->position[1]), at(layout->position[2]));
        if (!within_coordinate_bound(position)) {
          body.fail("vertex " + std::to_string(record) + " is not finite or lies beyond the supported coordinate magnitude 1e15");
        }
        mesh.positions.push_back(position);
        if (layout->normal) mesh.normals.emplace_back(at((*layout->normal)[0]), at((*layout->normal)[1]), at((*layout->normal)[2]));
        if (layout->texcoord) mesh.texcoords.emplace_back(at((*layout->texcoord)[0]), at((*layout->texcoord)[1]));
      } else if (is_face) {
        triangles.clear();
        if (corners.size() == 3) {
          triangles.push_back({0, 1, 2});
        } else {
          polygon.clear();
          for (uint32_t corner : corners) polygon.push_back(mesh.positions[corner]);
          triangulate_polygon(polygon, triangles);
        }
        // A texcoord list of u, v for each corner gives the face's own texture coordinates.
        const bool wedges = corner_texcoords.size() == 2 * corners.size();
        const auto first_wedge = static_cast<uint32_t>(wedge_texcoords.size());
        for (size_t k = 0; wedges && k < corners.size(); ++k) wedge_texcoords.emplace_back(corner_texcoords[2 * k], corner_texcoords[2 * k + 1]);
        for (const auto& t : triangles) {
          mesh.triangles.push_back({corners[t[0]], corners[t[1]], corners[t[2]]});
          if (texcoord_list == none) continue;
          wedge_corners.push_back(wedges ? std::array{first_wedge + t[0], first_wedge + t[1], first_wedge + t[2]}
                                         : std::array{no_attribute, no_attribute, no_attribute});
        }
      }
    }
  }
  if (!vertices_read) throw InputError(name + ": no vertex element");
  if (mesh.triangles.empty()) throw InputError(name + ": no faces to render (no face element, or an empty one)");
  // Shading normals and texture coordinates belong to the vertices, each corner naming its vertex's;
  // texture coordinates given by face corner take the place of the vertices'.
  if (!mesh.normals.empty()) mesh.normal_corners = mesh.triangles;
  if (!wedge_texcoords.empty()) {
    mesh.texcoords = std::move(wedge_texcoords);
    mesh.texcoord_corners = std::move(wedge_corners);
  } else if (!mesh.texcoords.empty()) {
    mesh.texcoord_corners = mesh.triangles;
  }
  return mesh;
}

}  // namespace

Mesh read_ply(std::string_view bytes, const std::string& name) {
  const Header header = read_header(bytes, name);
  if (header.format == Format::ascii) {
    AsciiBody body(bytes, header.body, header.body_line, name);
    return read_body(header, body, name);
  }
  BinaryBody body(bytes, header.body, header.format == Format::big_endian, name);
  return read_body(header, body, name);
}

}  // namespace vkray
