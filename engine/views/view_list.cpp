#include "engine/views/view_list.hpp"

#include "engine/scene/scene_loader.hpp"
#include "engine/scene/text_lines.hpp"
#include "engine/scene/text_start.hpp"
#include "engine/views/json_strings.hpp"

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <numbers>

namespace vkray {
namespace {

// The camera objects of a JSON array: where each element starts and ends in `text`, found by
// tracking nesting outside strings, and the line each starts on, so that an error can name it (lines
// counted in the same walk: a million cameras take one pass, not one a camera).
struct Element {
  size_t begin, end, line;
};

std::vector<Element> array_elements(std::string_view text) {
  std::vector<Element> elements;
  int depth = 0;
  JsonStringTracker strings;
  size_t begin = std::string_view::npos, begin_line = 0, line = 1;
  for (size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    if (c == '\n') ++line;
    if (!strings.outside_strings(c)) continue;
    // An element starts at depth 1 with its first character, and ends at the comma or bracket that
    // brings the walk back to depth 1 (an object or array) or leaves it there (a scalar, which,
    // parsed alone, fails as not a camera).
    const bool element_pending = begin != std::string_view::npos;
    if (depth == 1 && !element_pending && !std::isspace(static_cast<unsigned char>(c)) && c != ',' && c != ']') {
      begin = k;
      begin_line = line;
    }
    if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      --depth;
      if (depth == 1 && begin != std::string_view::npos) elements.push_back({begin, k + 1, begin_line}), begin = std::string_view::npos;
      if (depth == 0 && begin != std::string_view::npos) elements.push_back({begin, k, begin_line}), begin = std::string_view::npos;
    } else if (c == ',' && depth == 1 && begin != std::string_view::npos) {
      elements.push_back({begin, k, begin_line});
      begin = std::string_view::npos;
    }
  }
  return elements;
}

// A JSON array is parsed whole (nlohmann finds its syntax errors): past this size a views file has to
// be JSON Lines, whose lines are read and checked one at a time. 1 GiB holds millions of cameras.
constexpr uintmax_t max_views_array_bytes = uintmax_t{1} << 30;

// The view object at `source` ("views.jsonl:57"), which it keeps where it places instances.
View parse_view(std::string_view text, std::string source) {
  View view;
  view.camera = parse_camera_object(text, source, &view.poses);
  if (!view.poses.empty()) view.source = std::move(source);
  return view;
}

// One line of a JSON Lines views file: a view, or nothing where it is blank.
void add_json_line_view(const TextLine& line, const std::string& name, std::vector<View>& views) {
  if (line.text.find_first_not_of(" \t\r") == std::string_view::npos) return;
  try {
    refuse_invalid_json(line.text, name, line.number);
  } catch (const InputError& error) {
    throw InputError(std::string(error.what()) + " (JSON Lines: one camera object a line, or a JSON array of them)");
  }
  views.push_back(parse_view(line.text, name + ":" + std::to_string(line.number)));
}

std::vector<View> with_a_camera(std::vector<View> views, const std::string& name) {
  if (views.empty()) throw InputError(name + ": no cameras (a JSON array of camera objects, or one a line)");
  return views;
}

// Whether the file's first character but white space (and a byte-order mark) is '[', read up to
// that character alone.
bool starts_a_json_array(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return false;  // for_each_file_line says what it is
  std::ifstream file(path, std::ios::binary);
  std::string start(4096, '\0');
  for (bool first_block = true; file; first_block = false) {
    file.read(start.data(), static_cast<std::streamsize>(start.size()));
    std::string_view block(start.data(), static_cast<size_t>(file.gcount()));
    if (first_block) block = without_byte_order_mark(block);
    const size_t first = block.find_first_not_of(" \t\r\n");
    if (first != std::string_view::npos) return block[first] == '[';
  }
  return false;
}

// `direction` turned by `angle` radians about the unit `axis` (Rodrigues' formula).
glm::dvec3 rotated(const glm::dvec3& direction, const glm::dvec3& axis, double angle) {
  return direction * std::cos(angle) + glm::cross(axis, direction) * std::sin(angle) +
         axis * glm::dot(axis, direction) * (1.0 - std::cos(angle));
}

}  // namespace

std::vector<View> parse_views(std::string_view text, const std::string& name) {
  text = without_byte_order_mark(text);
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || text[first] != '[') {
    std::vector<View> views;
    for_each_line(text, name, [&](const TextLine& line) { add_json_line_view(line, name, views); });
    return with_a_camera(std::move(views), name);
  }
  refuse_invalid_json(text, name);
  std::vector<View> views;
  for (const Element& element : array_elements(text)) {
    views.push_back(parse_view(text.substr(element.begin, element.end - element.begin), name + ":" + std::to_string(element.line)));
  }
  return with_a_camera(std::move(views), name);
}

std::vector<View> load_views(const std::filesystem::path& path) {
  if (!starts_a_json_array(path)) {
    std::vector<View> views;
    for_each_file_line(path, "views file", [&](const TextLine& line) { add_json_line_view(line, path.string(), views); });
    return with_a_camera(std::move(views), path.string());
  }
  std::error_code error;
  if (std::filesystem::file_size(path, error) > max_views_array_bytes) {
    throw InputError(path.string() + ": a JSON array of over " + std::to_string(max_views_array_bytes >> 30) +
                     " GiB, which is parsed whole: write the cameras one a line (JSON Lines), read as they come");
  }
  return parse_views(read_input_file(path, "views file"), path.string());
}

void check_view_poses(const std::vector<View>& views, const Scene& scene) {
  std::vector<Bounds> mesh_boxes;  // found once a view places an instance
  std::vector<bool> placed(scene.instances.size());
  for (const View& view : views) {
    for (size_t k = 0; k < view.poses.instances.size(); ++k) {
      const std::string entry = view.source + ": instances[" + std::to_string(k) + "]";
      const uint32_t id = view.poses.instances[k];
      if (id >= scene.instances.size()) {
        const size_t count = scene.instances.size();
        throw InputError(entry + ".instance: " + std::to_string(id) + " is not an instance of the scene's " + std::to_string(count) +
                         (count == 0 ? " (it places none)" : " (0.." + std::to_string(count - 1) + ")"));
      }
      if (placed[id]) throw InputError(entry + ".instance: instance " + std::to_string(id) + " is placed twice in this view");
      placed[id] = true;
      if (mesh_boxes.empty()) mesh_boxes = instanced_mesh_boxes(scene);
      Instance instance = scene.instances[id];
      place_by(instance, view.poses.transforms[k]);
      check_transform(instance, mesh_boxes[instance.mesh], entry);
    }
    for (uint32_t id : view.poses.instances) placed[id] = false;
  }
}

std::vector<View> orbit_views(const Camera& start, uint32_t count) {
  const glm::dvec3 axis = glm::normalize(start.up);
  std::vector<View> views(count, View{start, {}, {}});
  for (uint32_t k = 0; k < count; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / count;
    views[k].camera.from = start.to + rotated(start.from - start.to, axis, angle);
  }
  return views;
}

std::vector<View> sphere_views(const Camera& start, uint32_t count) {
  const glm::dvec3 pole = glm::normalize(start.up);
  const glm::dvec3 offset = start.from - start.to;
  const double distance = glm::length(offset);
  // The lattice's longitude 0 is the start's own side; any side where it looks along the pole.
  glm::dvec3 side = offset - pole * glm::dot(pole, offset);
  if (glm::length(side) < 1e-9 * distance) side = std::abs(pole.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  side = glm::normalize(side - pole * glm::dot(pole, side));
  const glm::dvec3 across = glm::cross(pole, side);
  const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
  std::vector<View> views(count, View{start, {}, {}});
  for (uint32_t k = 0; k < count; ++k) {
    const double height = 1.0 - (2.0 * k + 1.0) / count;  // cos of the angle from the pole
    const double ring = std::sqrt(std::max(0.0, 1.0 - height * height));
    const double longitude = golden_angle * k;
    const glm::dvec3 direction = ring * (std::cos(longitude) * side + std::sin(longitude) * across) + height * pole;
    views[k].camera.from = start.to + distance * direction;
  }
  return views;
}

}  // namespace vkray
