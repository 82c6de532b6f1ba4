// Normalization that is safe for every finite input.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace vkray {

// v / |v| for any finite v; 0 for the zero vector. glm::normalize squares the components first,
// which overflows to inf beyond ~1e154 and underflows to 0 (then NaN) below ~1e-154; dividing by
// the largest magnitude first keeps the squares in [0, 3].
inline glm::dvec3 unit_vector(const glm::dvec3& v) {
  const double scale = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  return scale > 0.0 ? glm::normalize(v / scale) : glm::dvec3(0.0);
}

}  // namespace vkray
