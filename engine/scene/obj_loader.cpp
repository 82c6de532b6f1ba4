#include "engine/scene/obj_loader.hpp"

#include "engine/scene/text_start.hpp"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
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

// from_chars takes no leading '+', but OBJ writers emit it ("+0.5") and tinyobjloader reads it.
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

// What one pass over the text finds: the positions, and the faces while every one is a triangle
// (larger polygons go to tinyobjloader's triangulation).
struct ParsedObj {
  Mesh mesh;
  bool only_triangles = true;
};

// Records the corners' attribute indices of triangle `triangle_index`; the list starts at the first
// face that gives any (the triangles before it get no_attribute), and stays empty without.
void add_corners(std::vector<std::array<uint32_t, 3>>& list, const std::array<uint32_t, 3>& corners, size_t triangle_index) {
  if (list.empty() && corners[0] == no_attribute) return;
  list.resize(triangle_index, {no_attribute, no_attribute, no_attribute});
  list.push_back(corners);
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
  size_t form = std::string_view::npos;  // number of '/'-separated fields (with "//" as an empty one)
  bool form_has_texcoord = false;
  std::array<uint32_t, 3> triangle{}, normal_corners{}, texcoord_corners{};
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
    if (k <= 3) {
      triangle[k - 1] = static_cast<uint32_t>(vertex);
      texcoord_corners[k - 1] = texcoord < 0 ? no_attribute : static_cast<uint32_t>(texcoord);
      normal_corners[k - 1] = normal < 0 ? no_attribute : static_cast<uint32_t>(normal);
    }
  }
  if (tokens.size() == 4) {
    add_corners(parsed.mesh.normal_corners, normal_corners, parsed.mesh.triangles.size());
    add_corners(parsed.mesh.texcoord_corners, texcoord_corners, parsed.mesh.triangles.size());
    parsed.mesh.triangles.push_back(triangle);
  } else {
    parsed.only_triangles = false;
  }
  return {};
}

ParsedObj parse_obj_text(std::string_view text, const std::string& name) {
  ParsedObj parsed;
  ElementCounts counts;
  std::vector<std::string_view> tokens;
  size_t line_number = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    ++line_number;
    const size_t newline = text.find('\n', pos);
    const bool terminated = newline != std::string_view::npos;
    std::string_view line = text.substr(pos, terminated ? newline - pos : std::string_view::npos);
    pos = terminated ? newline + 1 : text.size();
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    if (const std::string error = check_statement(tokens, counts, parsed); !error.empty()) {
      throw InputError(name + ":" + std::to_string(line_number) + ": " + error +
                       (terminated ? "" : " (the file ends without a newline: cut off in the middle of this line?)"));
    }
  }
  if (counts.positions == 0) throw InputError(name + ": no vertices ('v' lines) found");
  return parsed;
}

}  // namespace

Mesh load_obj_text(std::string_view text, const std::string& name) {
  // One pass checks every statement and, for a mesh of triangles alone (scanned meshes, most
  // exports), builds it: the bunny loads in 16 ms instead of 45 with tinyobjloader's second parse.
  // Polygons of more vertices take tinyobjloader's triangulation.
  text = without_byte_order_mark(text);
  ParsedObj parsed = parse_obj_text(text, name);
  if (parsed.only_triangles) {
    if (parsed.mesh.triangles.empty()) throw InputError(name + ": no faces ('f' lines) found");
    for (auto* corners : {&parsed.mesh.normal_corners, &parsed.mesh.texcoord_corners}) {
      if (!corners->empty()) corners->resize(parsed.mesh.triangles.size(), {no_attribute, no_attribute, no_attribute});
    }
    return std::move(parsed.mesh);
  }

  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  // tinyobjloader only knows comments that start a line: in "f 1 2 3 # note" it reads '#' as index 0
  // and fails. The validation pass takes '#' anywhere as the start of a comment, so blank those out.
  std::string source(text);
  for (size_t hash = source.find('#'); hash != std::string::npos; hash = source.find('#', hash)) {
    const size_t end = std::min(source.find('\n', hash), source.size());
    std::fill(source.begin() + static_cast<long>(hash), source.begin() + static_cast<long>(end), ' ');
    hash = end;
  }
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(source, "", config)) {
    // The validation pass should leave nothing for tinyobjloader to reject; if it does, keep the
    // message on one line (tinyobjloader ends each of its messages with a newline).
    std::string detail = reader.Error();
    while (!detail.empty() && (detail.back() == '\n' || detail.back() == '\r')) detail.pop_back();
    std::replace(detail.begin(), detail.end(), '\n', ' ');
    throw InputError(name + ": " + detail);
  }

  // The positions are the checking pass's: std::from_chars rounds each number correctly, where
  // tinyobjloader's own parser is often an ulp off (46% of the bunny's coordinates).
  // So are the normals and texture coordinates, in the file's order as tinyobjloader's indices.
  Mesh mesh;
  mesh.positions = std::move(parsed.mesh.positions);
  mesh.normals = std::move(parsed.mesh.normals);
  mesh.texcoords = std::move(parsed.mesh.texcoords);
  auto attribute = [&](int index, size_t count) {
    if (index >= 0 && static_cast<size_t>(index) >= count) throw InputError(name + ": face refers to a missing normal or texture coordinate");
    return index < 0 ? no_attribute : static_cast<uint32_t>(index);
  };
  for (const auto& shape : reader.GetShapes()) {
    const auto& indices = shape.mesh.indices;
    for (size_t k = 0; k + 2 < indices.size(); k += 3) {
      std::array<uint32_t, 3> triangle, normal_corners, texcoord_corners;
      for (size_t c = 0; c < 3; ++c) {
        const int index = indices[k + c].vertex_index;
        if (index < 0 || static_cast<size_t>(index) >= mesh.positions.size()) {
          throw InputError(name + ": face refers to a missing vertex");  // the validation pass rules this out
        }
        triangle[c] = static_cast<uint32_t>(index);
        normal_corners[c] = attribute(indices[k + c].normal_index, mesh.normals.size());
        texcoord_corners[c] = attribute(indices[k + c].texcoord_index, mesh.texcoords.size());
      }
      add_corners(mesh.normal_corners, normal_corners, mesh.triangles.size());
      add_corners(mesh.texcoord_corners, texcoord_corners, mesh.triangles.size());
      mesh.triangles.push_back(triangle);
    }
  }
  if (mesh.triangles.empty()) throw InputError(name + ": no faces ('f' lines) found");
  for (auto* corners : {&mesh.normal_corners, &mesh.texcoord_corners}) {
    if (!corners->empty()) corners->resize(mesh.triangles.size(), {no_attribute, no_attribute, no_attribute});
  }
  return mesh;
}

Mesh load_obj_file(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    throw InputError(path.string() + (std::filesystem::exists(path, error) ? ": is not a regular file" : ": no such OBJ file"));
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path.string() + ": cannot open OBJ file");
  std::ostringstream contents;
  contents << file.rdbuf();
  if (file.bad()) throw InputError(path.string() + ": cannot read OBJ file");
  return load_obj_text(contents.str(), path.string());
}

}  // namespace vkray
