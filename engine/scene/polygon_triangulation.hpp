// Triangles of one polygon face, by ear clipping (D. Eberly, "Triangulation by Ear Clipping",
// Geometric Tools, 2002): the polygon is projected onto the axis plane its Newell normal faces most,
// an ear (a convex corner whose triangle holds no other corner) is cut off until three corners remain.
// Only reflex corners can lie in an ear: they are kept in a uniform grid over the polygon, so an ear
// test reads the cells its triangle's box covers, and the ears with the smallest boxes go first.
#pragma once

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vkray {

// Beyond this many corners a face is refused (its line named): real exports stay far below (Blender's
// n-gons, CAD caps of a few hundred segments), and ear clipping's cost grows faster than the corners.
// The hostile shapes tried (combs, stars, spirals, random corners) of 4096 corners each take at most
// 300 corner tests a corner (a star of radii 1 and 0.001), 8 ms (docs/scene-format.md, "Model files").
inline constexpr size_t max_polygon_corners = 4096;

// Appends the polygon's n - 2 triangles to `triangles`, each as three numbers of its corners (0 is the
// first corner of `corners`), counter-clockwise as seen from where the corners run counter-clockwise.
// A self-intersecting or degenerate polygon has no ear at some point; its remaining corners are then
// cut one by one in order, so every corner is still used and no triangle is lost. Returns the corner
// tests its ear tests made: the work, which the tests bound.
size_t triangulate_polygon(std::span<const glm::dvec3> corners, std::vector<std::array<uint32_t, 3>>& triangles);

}  // namespace vkray
