#include "cli/scene_argument.hpp"

#include "engine/typed_names.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/scene/scene_or_model.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace vkray::cli {
namespace {

std::vector<std::string> split(const std::string& text, const std::string& separators) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find_first_of(separators, start), text.size());
    parts.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return parts;
}

constexpr const char* camera_forms =
    "write --camera 'from=0,1,5 to=0,0,0 up=0,1,0 fovy=35' (any of the keys, vectors also as [0,1,5]; "
    "intrinsics=FX,FY,CX,CY in place of fovy, world_to_camera=16 numbers by rows in place of from, to and up) or "
    "the scene file's camera as JSON, '{\"from\": [0, 1, 5], \"fovy\": 35}'";

// The items of the key=value form: separated by spaces or semicolons outside brackets, so that
// "from=[0, 1, 5]" stays one item.
std::vector<std::string> camera_items(const std::string& text) {
  std::vector<std::string> items(1);
  int depth = 0;
  for (char c : text) {
    depth += c == '[' ? 1 : c == ']' ? -1 : 0;
    if (depth == 0 && (c == ' ' || c == ';')) {
      if (!items.back().empty()) items.emplace_back();
    } else {
      items.back() += c;
    }
  }
  if (items.back().empty()) items.pop_back();
  return items;
}

std::string trimmed(const std::string& text) {
  const size_t first = text.find_first_not_of(' ');
  return first == std::string::npos ? "" : text.substr(first, text.find_last_not_of(' ') - first + 1);
}

// A number of the key=value form as exact JSON (17 digits give the same double back).
std::string number_json(const std::string& text, const std::string& key) {
  const std::string number = trimmed(text);
  double value = 0.0;
  const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), value);
  if (error != std::errc() || end != number.data() + number.size() || !std::isfinite(value)) {
    throw InputError("--camera: " + key + ": '" + number + "' is not a finite number; " + camera_forms);
  }
  char json[32];
  std::snprintf(json, sizeof json, "%.17g", value);
  return json;
}

// "from=X,Y,Z to=[X,Y,Z] fovy=35" as the JSON object {"from": [X, Y, Z], ...}.
std::string camera_json(const std::string& text) {
  std::string json;
  for (const std::string& item : camera_items(text)) {
    const size_t equals = item.find('=');
    const std::string key = item.substr(0, equals);
    const std::vector<std::string> keys = {"from", "to", "up", "fovy", "intrinsics", "world_to_camera", "projection", "view_height"};
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
      const auto nearest = nearest_name(key, keys);
      throw InputError("--camera: unknown key '" + key + "'" + (nearest ? " (did you mean '" + *nearest + "'?)" : "") +
                       "; " + camera_forms);
    }
    if (equals == std::string::npos) throw InputError("--camera: " + key + " has no value; " + camera_forms);
    std::string value = trimmed(item.substr(equals + 1));
    if (value.size() >= 2 && value.front() == '[' && value.back() == ']') value = value.substr(1, value.size() - 2);
    json += (json.empty() ? "{" : ", ") + std::string("\"") + key + "\": ";
    if (key == "fovy" || key == "view_height") {
      json += number_json(value, key);
      continue;
    }
    if (key == "projection") {  // a name: letters alone, quoted as a JSON string
      if (value.empty() || !std::all_of(value.begin(), value.end(), [](unsigned char c) { return std::isalpha(c) != 0; })) {
        throw InputError("--camera: projection takes a name (perspective, orthographic, equirectangular), got '" + value + "'");
      }
      json += "\"" + value + "\"";
      continue;
    }
    const std::vector<std::string> parts = split(value, ",");
    if (key == "intrinsics") {
      if (parts.size() != 4) throw InputError("--camera: intrinsics takes four numbers FX,FY,CX,CY (pixels); " + std::string(camera_forms));
      json += "{\"fx\": " + number_json(parts[0], key) + ", \"fy\": " + number_json(parts[1], key) +
              ", \"cx\": " + number_json(parts[2], key) + ", \"cy\": " + number_json(parts[3], key) + "}";
      continue;
    }
    if (key == "world_to_camera") {
      if (parts.size() != 16) {
        throw InputError("--camera: world_to_camera takes 16 numbers, the 4 x 4 matrix by rows; " + std::string(camera_forms));
      }
      for (size_t r = 0; r < 4; ++r) {
        json += r == 0 ? "[[" : "], [";
        for (size_t c = 0; c < 4; ++c) json += (c ? ", " : "") + number_json(parts[4 * r + c], key);
      }
      json += "]]";
      continue;
    }
    if (parts.size() != 3) {
      throw InputError("--camera: " + key + " takes three numbers X,Y,Z, got '" + item.substr(equals + 1) + "'; " +
                       camera_forms);
    }
    json += "[" + number_json(parts[0], key) + ", " + number_json(parts[1], key) + ", " + number_json(parts[2], key) + "]";
  }
  return json.empty() ? "{}" : json + "}";
}

}  // namespace

FramingView parse_view_option(const std::string& text) {
  const std::string given = trimmed(text);
  if (const auto named = framing_view_from_name(given)) return *named;
  const std::string forms = std::string("--view: '") + given + "' is neither a side (" + framing_view_names +
                            ") nor a direction X,Y,Z from the centre to the eye";
  const std::vector<std::string> parts = split(given, ",");
  if (parts.size() != 3 || given.find_first_not_of("0123456789+-.,eE ") != std::string::npos) throw InputError(forms);
  glm::dvec3 direction;
  for (int c = 0; c < 3; ++c) {
    const std::string number = trimmed(parts[static_cast<size_t>(c)]);
    const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), direction[c]);
    if (error != std::errc() || end != number.data() + number.size() || !std::isfinite(direction[c])) throw InputError(forms);
  }
  if (direction == glm::dvec3(0.0)) throw InputError("--view: the direction must not be 0, 0, 0");
  return {direction, {0.0, 1.0, 0.0}};
}

Scene load_scene_argument(const std::string& path, std::optional<uint32_t> width, std::optional<uint32_t> height,
                          const std::optional<std::string>& view) {
  const std::optional<FramingView> side = view ? std::optional(parse_view_option(*view)) : std::nullopt;
  Scene scene = load_scene_or_model(path, width, height);
  if (side) scene.camera = frame_scene(scene, scene.width, scene.height, *side);
  if (const size_t dropped = scene.zero_area_triangle_count(); dropped > 0) {
    std::fprintf(stderr, "vkray: note: %s: %zu zero-area triangle%s dropped (no ray can hit them)\n",
                 path.empty() ? "built-in scene" : path.c_str(), dropped, dropped == 1 ? "" : "s");
  }
  return scene;
}

std::pair<uint32_t, uint32_t> parse_size(const std::string& text) {
  const size_t x = text.find('x');
  try {
    size_t used_w = 0, used_h = 0;
    if (x == std::string::npos) throw std::invalid_argument("no x");
    const unsigned long width = std::stoul(text.substr(0, x), &used_w);
    const unsigned long height = std::stoul(text.substr(x + 1), &used_h);
    if (used_w != x || used_h != text.size() - x - 1 || width > UINT32_MAX || height > UINT32_MAX) {
      throw std::invalid_argument("trailing text");
    }
    check_image_size(static_cast<uint32_t>(width), static_cast<uint32_t>(height));
    return {static_cast<uint32_t>(width), static_cast<uint32_t>(height)};
  } catch (const std::logic_error&) {
    throw InputError("--size: '" + text + "' is not WIDTHxHEIGHT, e.g. 1920x1080");
  }
}

void apply_camera_option(const std::string& text, Camera& camera) {
  const std::string given = trimmed(text);
  camera = parse_camera_override(given.starts_with("{") ? given : camera_json(given), "--camera", camera);
}

void check_scene_camera(const Scene& scene, bool camera_option_given, const std::string& scene_path) {
  const std::string source = camera_option_given ? "--camera" : scene_path.empty() ? "the built-in scene's camera" : scene_path + ": its camera";
  check_camera_reach(scene.camera, scene.width, scene.height, source);
}

std::string camera_option(const Camera& camera) {
  auto number = [](double value) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, value).ptr;  // shortest round trip
    return std::string(text, end);
  };
  auto vector = [&](const glm::dvec3& v) { return number(v.x) + "," + number(v.y) + "," + number(v.z); };
  const std::string plane =
      camera.projection == Projection::orthographic ? " projection=orthographic view_height=" + number(camera.view_height)
      : camera.projection == Projection::equirectangular ? std::string(" projection=equirectangular")
      : camera.intrinsics ? " intrinsics=" + number(camera.intrinsics->fx) + "," + number(camera.intrinsics->fy) + "," +
                                number(camera.intrinsics->cx) + "," + number(camera.intrinsics->cy)
                          : " fovy=" + number(camera.fovy_degrees);
  return "--camera 'from=" + vector(camera.from) + " to=" + vector(camera.to) + " up=" + vector(camera.up) + plane + "'";
}

}  // namespace vkray::cli
