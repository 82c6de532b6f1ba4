#include "cli/scene_argument.hpp"

#include "engine/framing.hpp"
#include "engine/scene_loader.hpp"

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

std::string lower_extension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

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

double parse_number(const std::string& text, const std::string& key) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    throw InputError("--camera: " + key + ": '" + text + "' is not a finite number");
  }
  return value;
}

glm::dvec3 parse_vector(const std::string& text, const std::string& key) {
  const std::vector<std::string> parts = split(text, ",");
  if (parts.size() != 3) throw InputError("--camera: " + key + " takes three numbers X,Y,Z, got '" + text + "'");
  return {parse_number(parts[0], key), parse_number(parts[1], key), parse_number(parts[2], key)};
}

}  // namespace

Scene load_scene_argument(const std::string& path, std::optional<uint32_t> width, std::optional<uint32_t> height) {
  const std::string extension = lower_extension(path);
  if (!path.empty() && extension != ".json" && extension != ".obj") {
    throw InputError(path + ": unknown kind of file '" + extension + "' (a scene is .json, a model .obj)");
  }
  Scene scene = path.empty() ? default_scene() : extension == ".obj" ? load_model_file(path) : load_scene_file(path);
  if (width) scene.width = *width;
  if (height) scene.height = *height;
  check_image_size(scene.width, scene.height);
  if (extension == ".obj") scene.camera = frame_scene(scene, scene.width, scene.height);
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
  Camera changed = camera;
  for (const std::string& item : split(text, " ;")) {
    if (item.empty()) continue;
    const size_t equals = item.find('=');
    const std::string key = item.substr(0, equals);
    const std::string value = equals == std::string::npos ? "" : item.substr(equals + 1);
    if (key == "from") {
      changed.from = parse_vector(value, key);
    } else if (key == "to") {
      changed.to = parse_vector(value, key);
    } else if (key == "up") {
      changed.up = parse_vector(value, key);
      if (changed.up == glm::dvec3(0.0)) throw InputError("--camera: up must not be zero");
    } else if (key == "fovy") {
      changed.fovy_degrees = parse_number(value, key);
      if (!(changed.fovy_degrees > 0.0 && changed.fovy_degrees < 180.0)) {
        throw InputError("--camera: fovy must be in (0, 180) degrees, got " + value);
      }
    } else {
      throw InputError("--camera: unknown key '" + key + "' (use from=X,Y,Z to=X,Y,Z up=X,Y,Z fovy=DEGREES)");
    }
  }
  if (changed.from == changed.to) throw InputError("--camera: from and to must differ");
  for (const auto& v : {changed.from, changed.to, changed.up}) {
    for (int axis = 0; axis < 3; ++axis) {
      if (std::abs(v[axis]) > max_coordinate) throw InputError("--camera: coordinates must stay within +-1e15");
    }
  }
  camera = changed;
}

}  // namespace vkray::cli
