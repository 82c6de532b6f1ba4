#include "engine/frame.hpp"

#include <algorithm>
#include <cmath>

namespace vkray {

namespace {
struct NamedAov {
  Aov aov;
  const char* name;
};
constexpr NamedAov named_aovs[] = {{Aov::depth, "depth"}, {Aov::normal, "normal"}, {Aov::uv, "uv"}};
}  // namespace

std::string AovSet::names() const {
  std::string list;
  for (const auto& entry : named_aovs) {
    if (!has(entry.aov)) continue;
    if (!list.empty()) list += ',';
    list += entry.name;
  }
  return list;
}

std::optional<Aov> aov_from_name(std::string_view name) {
  for (const auto& entry : named_aovs) {
    if (name == entry.name) return entry.aov;
  }
  return std::nullopt;
}

void Frame::allocate(bool doubles) {
  depth.assign(aovs.has(Aov::depth) ? pixel_count() : 0, 0.0f);
  normal.assign(aovs.has(Aov::normal) ? 3 * pixel_count() : 0, 0.0f);
  uv.assign(aovs.has(Aov::uv) ? 2 * pixel_count() : 0, 0.0f);
  depth64.assign(doubles ? depth.size() : 0, 0.0);
  normal64.assign(doubles ? normal.size() : 0, 0.0);
}

void Frame::round_doubles() {
  if (!depth64.empty()) std::copy(depth64.begin(), depth64.end(), depth.begin());
  if (!normal64.empty()) std::copy(normal64.begin(), normal64.end(), normal.begin());
}

bool Frame::hit(size_t pixel) const {
  if (aovs.has(Aov::depth)) return std::isfinite(depth[pixel]);
  if (aovs.has(Aov::normal)) return normal_at(pixel) != glm::vec3(0.0f);
  return false;
}

DepthRange finite_depth_range(const Frame& frame) {
  DepthRange range;
  for (float z : frame.depth) {
    if (std::isfinite(z)) range.add(z);
  }
  return range;
}

}  // namespace vkray
