// Normalization that is safe for every finite input.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace vkray {

// v / |v| for any finite v; 0 for the zero vector. glm::normalize squares the components first,
// which overflows to inf beyond ~1e154 and underflows to 0 (then NaN) below ~1e-154: outside
// [2^-480, 2^480] the largest magnitude is divided out first, keeping the squares in [0, 3]
// (three divisions, which cost given rays' encoding a third of its time, are skipped inside).
inline glm::dvec3 unit_vector(const glm::dvec3& v) {
  const double scale = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  if (scale > 0x1p-480 && scale < 0x1p480) return glm::normalize(v);
  return scale > 0.0 ? glm::normalize(v / scale) : glm::dvec3(0.0);
}

}  // namespace vkray
