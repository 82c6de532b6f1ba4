#include "engine/scene/obj_loader.hpp"

#include "engine/scene/polygon_triangulation.hpp"
#include "engine/scene/text_lines.hpp"


#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <functional>
#include <vector>

namespace vkray {
namespace {

struct ElementCounts {
  long positions = 0;
  long texcoords = 0;
  long normals = 0;
};

// `tokens` is reused from line to line: no allocation per line once it has grown.
void split_tokens(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  size_t pos = 0;
  while (pos < line.size()) {
    const size_t start = line.find_first_not_of(" \t\r", pos);
    if (start == std::string_view::npos) break;
    const size_t end = std::min(line.find_first_of(" \t\r", start), line.size());
    tokens.push_back(line.substr(start, end - start));
    pos = end;
  }
}

// from_chars takes no leading '+', but OBJ writers emit it ("+0.5") and other readers take it.
std::string_view without_plus(std::string_view token) {
  return token.size() >= 2 && token[0] == '+' && token[1] != '-' ? token.substr(1) : token;
}

bool parse_whole_double(std::string_view token, double& value) {
  token = without_plus(token);
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

bool parse_whole_long(std::string_view token, long& value) {
  token = without_plus(token);
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

// Checks one index of a face vertex reference against the elements defined so far and sets
// `resolved` to the 0-based element. OBJ indices are 1-based; negative ones count back from the last
// element defined (-1 is the newest).
std::string check_index(std::string_view token, long defined, const char* what, long& resolved) {
  long index = 0;
  if (!parse_whole_long(token, index)) return "'" + std::string(token) + "' is not an integer " + what + " index";
  if (index == 0) return std::string(what) + " index 0 (OBJ indices start at 1)";
  if (index > defined || index < -defined) {  // not -index > defined: -LONG_MIN overflows
    return std::string(what) + " index " + std::string(token) + " is out of range (" +
           std::to_string(defined) + " defined so far)";
  }
  resolved = index > 0 ? index - 1 : defined + index;
  return {};
}

// What one pass over the text finds, and room for one face's corners reused from face to face.
struct ParsedObj {
  Mesh mesh;
  std::vector<std::array<uint32_t, 3>> face_corners;  // vertex, texture coordinate and normal of each corner
  std::vector<glm::dvec3> polygon;                    // the corners' positions, for triangulation
  std::vector<std::array<uint32_t, 3>> polygon_triangles;
};

// Records the corners' attribute indices of triangle `triangle_index`; the list starts at the first
// face that gives any (the triangles before it get no_attribute), and stays empty without.
void add_corners(std::vector<std::array<uint32_t, 3>>& list, const std::array<uint32_t, 3>& corners, size_t triangle_index) {
  if (list.empty() && corners[0] == no_attribute) return;
  list.resize(triangle_index, {no_attribute, no_attribute, no_attribute});
  list.push_back(corners);
}

// Adds the triangles of the face in `parsed.face_corners`: a polygon of more corners is triangulated.
void add_face(ParsedObj& parsed) {
  const auto& corners = parsed.face_corners;
  parsed.polygon_triangles.clear();
  if (corners.size() == 3) {
    parsed.polygon_triangles.push_back({0, 1, 2});
  } else {
    parsed.polygon.clear();
    for (const auto& corner : corners) parsed.polygon.push_back(parsed.mesh.positions[corner[0]]);
    triangulate_polygon(parsed.polygon, parsed.polygon_triangles);
  }
  Mesh& mesh = parsed.mesh;
  for (const auto& triangle : parsed.polygon_triangles) {
    const auto attribute = [&](size_t which) {
      return std::array<uint32_t, 3>{corners[triangle[0]][which], corners[triangle[1]][which], corners[triangle[2]][which]};
    };
    add_corners(mesh.texcoord_corners, attribute(1), mesh.triangles.size());
    add_corners(mesh.normal_corners, attribute(2), mesh.triangles.size());
    mesh.triangles.push_back(attribute(0));
  }
}

// Returns an empty string when the statement is acceptable, else what is wrong with it; adds what
// it defines to `parsed`.
std::string check_statement(const std::vector<std::string_view>& tokens, ElementCounts& counts, ParsedObj& parsed) {
  const std::string_view keyword = tokens[0];
  if (keyword == "v" || keyword == "vn" || keyword == "vt") {
    const size_t needed = keyword == "vt" ? 1 : 3;
    if (tokens.size() - 1 < needed) {
      return "'" + std::string(keyword) + "' needs " + std::to_string(needed) + " coordinates, got " +
             std::to_string(tokens.size() - 1);
    }
    glm::dvec3 position(0.0);
    for (size_t k = 1; k < tokens.size(); ++k) {
      double value = 0.0;
      if (!parse_whole_double(tokens[k], value)) return "'" + std::string(tokens[k]) + "' is not a number";
      if (!std::isfinite(value)) return "coordinate '" + std::string(tokens[k]) + "' is not finite";
      if (k <= 3) position[static_cast<int>(k - 1)] = value;
    }
    if (keyword == "v") parsed.mesh.positions.push_back(position);
    if (keyword == "vn") parsed.mesh.normals.push_back(position);
    if (keyword == "vt") parsed.mesh.texcoords.emplace_back(position.x, position.y);
    (keyword == "v" ? counts.positions : keyword == "vn" ? counts.normals : counts.texcoords) += 1;
    return {};
  }
  if (keyword != "f") return {};  // groups, materials, smoothing, lines and points: not geometry we use
  if (tokens.size() < 4) return "a face needs at least 3 vertices, got " + std::to_string(tokens.size() - 1);
  if (tokens.size() - 1 > max_polygon_corners) {
    return "a face of " + std::to_string(tokens.size() - 1) + " vertices; vkray takes at most " +
           std::to_string(max_polygon_corners) + " (split it into smaller faces)";
  }
  size_t form = std::string_view::npos;  // number of '/'-separated fields (with "//" as an empty one)
  bool form_has_texcoord = false;
  parsed.face_corners.clear();
  for (size_t k = 1; k < tokens.size(); ++k) {
    std::array<std::string_view, 4> fields;  // a fourth one is already malformed
    size_t field_count = 0;
    size_t start = 0;
    for (;;) {
      const size_t slash = tokens[k].find('/', start);
      fields[field_count++] =
          tokens[k].substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
      if (slash == std::string_view::npos || field_count == fields.size()) break;
      start = slash + 1;
    }
    const bool has_texcoord = field_count >= 2 && !fields[1].empty();
    if (field_count > 3 || (field_count == 2 && !has_texcoord) || fields[0].empty() ||
        (field_count == 3 && fields[2].empty())) {
      return "malformed face vertex '" + std::string(tokens[k]) + "'";
    }
    if (form == std::string_view::npos) {
      form = field_count;
      form_has_texcoord = has_texcoord;
    } else if (field_count != form || has_texcoord != form_has_texcoord) {
      return "face vertex '" + std::string(tokens[k]) + "' has a different form than '" +
             std::string(tokens[1]) + "'";
    }
    long vertex = 0, texcoord = -1, normal = -1;
    if (auto error = check_index(fields[0], counts.positions, "vertex", vertex); !error.empty()) return error;
    if (has_texcoord) {
      if (auto error = check_index(fields[1], counts.texcoords, "texture", texcoord); !error.empty()) return error;
    }
    if (field_count == 3) {
      if (auto error = check_index(fields[2], counts.normals, "normal", normal); !error.empty()) return error;
    }
    parsed.face_corners.push_back({static_cast<uint32_t>(vertex), texcoord < 0 ? no_attribute : static_cast<uint32_t>(texcoord),
                                   normal < 0 ? no_attribute : static_cast<uint32_t>(normal)});
  }
  add_face(parsed);
  return {};
}

// One line's statement, checked and added to `parsed`; throws InputError naming the line.
void read_obj_line(const TextLine& line, const std::string& name, ElementCounts& counts, ParsedObj& parsed,
                   std::vector<std::string_view>& tokens) {
  std::string_view content = line.text;
  if (const size_t hash = content.find('#'); hash != std::string_view::npos) content = content.substr(0, hash);
  split_tokens(content, tokens);
  if (tokens.empty()) return;
  if (const std::string error = check_statement(tokens, counts, parsed); !error.empty()) {
    throw InputError(name + ":" + std::to_string(line.number) + ": " + error +
                     (line.terminated ? "" : " (the file ends without a newline: cut off in the middle of this line?)"));
  }
}

// The mesh of an OBJ given line by line to `read_lines`.
Mesh parse_obj(const std::string& name, const std::function<void(const LineHandler&)>& read_lines) {
  ParsedObj parsed;
  ElementCounts counts;
  std::vector<std::string_view> tokens;  // reused from line to line
  read_lines([&](const TextLine& line) { read_obj_line(line, name, counts, parsed, tokens); });
  if (counts.positions == 0) throw InputError(name + ": no vertices ('v' lines) found");
  Mesh& mesh = parsed.mesh;
  if (mesh.triangles.empty()) throw InputError(name + ": no faces ('f' lines) found");
  for (auto* corners : {&mesh.normal_corners, &mesh.texcoord_corners}) {
    if (!corners->empty()) corners->resize(mesh.triangles.size(), {no_attribute, no_attribute, no_attribute});
  }
  return std::move(mesh);
}

}  // namespace

Mesh load_obj_text(std::string_view text, const std::string& name) {
  return parse_obj(name, [&](const LineHandler& handle) { for_each_line(text, name, handle); });
}

Mesh load_obj_file(const std::filesystem::path& path) {
  return parse_obj(path.string(), [&](const LineHandler& handle) { for_each_file_line(path, "OBJ file", handle); });
}

}  // namespace vkray
