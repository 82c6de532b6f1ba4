#include "engine/scene/polygon_triangulation.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>

namespace vkray {
namespace {

// Twice the signed area of triangle (a, b, c): positive where it turns counter-clockwise.
double orientation(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// The polygon as a ring of corners that ears are cut from, with what ear clipping keeps about each.
class EarClipper {
 public:
  explicit EarClipper(std::span<const glm::dvec3> corners) : points_(corners.size()), next_(corners.size()), previous_(corners.size()),
                                                            convex_(corners.size()), listed_reflex_(corners.size()), removed_(corners.size()) {
    // Newell's normal (the sum of the edges' cross products, taken about the first corner so that far
    // coordinates do not cancel) is the polygon's area vector even when it is concave or not planar.
    const glm::dvec3 origin = corners[0];
    glm::dvec3 normal(0.0);
    for (size_t i = 0; i < corners.size(); ++i) {
      normal += glm::cross(corners[i] - origin, corners[(i + 1) % corners.size()] - origin);
    }
    // Drop the axis the normal runs along most; order the other two so the polygon runs counter-clockwise.
    const glm::dvec3 magnitude = glm::abs(normal);
    const int axis = magnitude.x >= magnitude.y && magnitude.x >= magnitude.z ? 0 : magnitude.y >= magnitude.z ? 1 : 2;
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    if (normal[axis] < 0.0) std::swap(u, v);
    for (size_t i = 0; i < corners.size(); ++i) {
      points_[i] = {corners[i][u] - origin[u], corners[i][v] - origin[v]};
      next_[i] = static_cast<uint32_t>((i + 1) % corners.size());
      previous_[i] = static_cast<uint32_t>((i + corners.size() - 1) % corners.size());
    }
    for (uint32_t i = 0; i < corners.size(); ++i) {
      convex_[i] = turns_left(i);
      if (!convex_[i]) reflex_.push_back(i);
      listed_reflex_[i] = !convex_[i];
    }
    std::stable_sort(reflex_.begin(), reflex_.end(), [&](uint32_t a, uint32_t b) { return points_[a].x < points_[b].x; });
  }

  void triangulate(std::vector<std::array<uint32_t, 3>>& triangles) {
    size_t remaining = points_.size();
    uint32_t any_corner = 0;
    for (uint32_t corner = 0; corner < remaining; ++corner) {
      if (is_ear(corner)) ears_.push_back(corner);
    }
    while (remaining > 3) {
      // Cutting an ear changes only its two neighbours: a corner elsewhere that held a reflex corner
      // in its triangle still holds one, even if that corner turned convex (Eberly). So
      // the list of ears stays complete with only the neighbours tested again.
      uint32_t tip = no_corner;
      while (tip == no_corner && !ears_.empty()) {
        const uint32_t candidate = ears_.back();
        ears_.pop_back();
        if (!removed_[candidate] && is_ear(candidate)) tip = candidate;
      }
      // No ear left: the rest crosses itself (or has no area), and has no right triangulation. Cut
      // its corners in order all the same.
      if (tip == no_corner) tip = any_corner;
      const uint32_t before = previous_[tip], after = next_[tip];
      triangles.push_back({before, tip, after});
      removed_[tip] = true;
      if (listed_reflex_[tip] && !convex_[tip]) ++gone_reflex_;
      next_[before] = after;
      previous_[after] = before;
      --remaining;
      any_corner = after;
      for (const uint32_t neighbour : {before, after}) {
        update_convexity(neighbour);
        if (is_ear(neighbour)) ears_.push_back(neighbour);
      }
      drop_gone_reflex_corners();
    }
    triangles.push_back({previous_[any_corner], any_corner, next_[any_corner]});
  }

 private:
  static constexpr uint32_t no_corner = UINT32_MAX;

  bool turns_left(uint32_t corner) const {
    return orientation(points_[previous_[corner]], points_[corner], points_[next_[corner]]) > 0.0;
  }

  void update_convexity(uint32_t corner) {
    const bool was_convex = convex_[corner];
    convex_[corner] = turns_left(corner);
    if (listed_reflex_[corner] && convex_[corner] && !was_convex) ++gone_reflex_;
    if (!convex_[corner] && !listed_reflex_[corner]) {
      listed_reflex_[corner] = true;
      const auto after = std::upper_bound(reflex_.begin(), reflex_.end(), points_[corner].x,
                                          [&](double x, uint32_t other) { return x < points_[other].x; });
      reflex_.insert(after, corner);
    }
  }

  // Each ear test reads the part of the list in its triangle's x range: drop the corners cut off or turned convex once they are half
  // of it, which keeps the work of all the drops linear.
  void drop_gone_reflex_corners() {
    if (2 * gone_reflex_ <= reflex_.size()) return;
    std::erase_if(reflex_, [&](uint32_t corner) {
      if (!removed_[corner] && !convex_[corner]) return false;
      listed_reflex_[corner] = false;
      return true;
    });
    gone_reflex_ = 0;
  }

  // A convex corner whose triangle with its two neighbours holds no reflex corner, on its edges
  // included. A corner at the same place as one of the triangle's (a polygon with a hole joined by a
  // doubled edge has such pairs) does not count as inside.
  bool is_ear(uint32_t corner) const {
    if (!convex_[corner]) return false;
    const glm::dvec2 a = points_[previous_[corner]], b = points_[corner], c = points_[next_[corner]];
    const double x_end = std::max({a.x, b.x, c.x});
    const auto first = std::lower_bound(reflex_.begin(), reflex_.end(), std::min({a.x, b.x, c.x}),
                                        [&](uint32_t other, double x) { return points_[other].x < x; });
    for (auto it = first; it != reflex_.end() && points_[*it].x <= x_end; ++it) {
      const uint32_t other = *it;
      if (removed_[other] || convex_[other]) continue;
      const glm::dvec2 p = points_[other];
      if (p == a || p == b || p == c) continue;
      if (orientation(a, b, p) >= 0.0 && orientation(b, c, p) >= 0.0 && orientation(c, a, p) >= 0.0) return false;
    }
    return true;
  }

  std::vector<glm::dvec2> points_;
  std::vector<uint32_t> next_, previous_;
  std::vector<bool> convex_, listed_reflex_, removed_;
  // The corners that were reflex when last looked at, sorted by x: an ear test reads only those in
  // its triangle's x range, a few for the small triangles of a many-cornered polygon.
  std::vector<uint32_t> reflex_;
  size_t gone_reflex_ = 0;  // entries of reflex_ since cut off or turned convex
  std::vector<uint32_t> ears_;
};

}  // namespace

void triangulate_polygon(std::span<const glm::dvec3> corners, std::vector<std::array<uint32_t, 3>>& triangles) {
  if (corners.size() < 3) return;
  EarClipper clipper(corners);
  clipper.triangulate(triangles);
}

}  // namespace vkray
