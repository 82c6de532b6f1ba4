// What every loader promises of a mesh it accepts, checked by the model fuzzers: positions finite and
// within the coordinate bound, triangle corners among the positions, attribute corners one a
// triangle (or none) and among their values. A broken promise aborts: a finding.
#pragma once

#include "engine/scene/scene.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>

namespace vkray::test {

template <typename Corners, typename Values>
void check_attribute_corners(const Corners& corners, const Values& values, size_t triangles) {
  if (!corners.empty() && corners.size() != triangles) std::abort();
  for (const auto& corner : corners) {
    for (uint32_t index : corner) {
      if (index != no_attribute && index >= values.size()) std::abort();
    }
  }
}

inline void check_mesh_promises(const Mesh& mesh) {
  for (const auto& position : mesh.positions) {
    for (int k = 0; k < 3; ++k) {
      if (!(std::abs(position[k]) <= max_coordinate)) std::abort();
    }
  }
  for (const auto& triangle : mesh.triangles) {
    for (uint32_t index : triangle) {
      if (index >= mesh.positions.size()) std::abort();
    }
  }
  check_attribute_corners(mesh.normal_corners, mesh.normals, mesh.triangles.size());
  check_attribute_corners(mesh.texcoord_corners, mesh.texcoords, mesh.triangles.size());
}

}  // namespace vkray::test
