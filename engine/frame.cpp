#include "engine/frame.hpp"

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

bool Frame::hit(size_t pixel) const {
  if (aovs.has(Aov::depth)) return std::isfinite(depth[pixel]);
  if (aovs.has(Aov::normal)) {
    return normal[3 * pixel] != 0.0f || normal[3 * pixel + 1] != 0.0f || normal[3 * pixel + 2] != 0.0f;
  }
  return false;
}

}  // namespace vkray
