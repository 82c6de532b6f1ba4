// Triangles of one polygon face, by ear clipping (D. Eberly, "Triangulation by Ear Clipping",
// Geometric Tools, 2002): the polygon is projected onto the axis plane its Newell normal faces most,
// an ear (a convex corner whose triangle holds no other corner) is cut off until three corners remain.
// Only reflex corners can lie in an ear, so a convex polygon costs O(n) and any other O(n * reflex).
#pragma once

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vkray {

// Beyond this many corners a face is refused (its line named): the cost of a concave polygon grows as
// corners times reflex corners, and a star of 4096 corners (2048 reflex) takes 24 ms, a 20 KB line,
// so a hostile file still loads at about 1 MB/s. Real exports stay far below (Blender's n-gons, CAD
// caps of a few hundred segments).
inline constexpr size_t max_polygon_corners = 4096;

// Appends the polygon's n - 2 triangles to `triangles`, each as three numbers of its corners (0 is the
// first corner of `corners`), counter-clockwise as seen from where the corners run counter-clockwise.
// A self-intersecting or degenerate polygon has no ear at some point; its remaining corners are then
// cut one by one in order, so every corner is still used and no triangle is lost.
void triangulate_polygon(std::span<const glm::dvec3> corners, std::vector<std::array<uint32_t, 3>>& triangles);

}  // namespace vkray
