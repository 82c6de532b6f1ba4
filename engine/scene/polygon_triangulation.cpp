#include "engine/scene/polygon_triangulation.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <compare>
#include <functional>
#include <utility>

namespace vkray {
namespace {

// Twice the signed area of triangle (a, b, c): positive where it turns counter-clockwise.
double orientation(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// The polygon as a ring of corners that ears are cut from, with what ear clipping keeps about each.
class EarClipper {
 public:
  explicit EarClipper(std::span<const glm::dvec3> corners)
      : points_(corners.size()), next_(corners.size()), previous_(corners.size()), convex_(corners.size()),
        removed_(corners.size()), cell_of_(corners.size(), no_cell), place_in_cell_(corners.size()) {
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
    low_ = glm::dvec2(INFINITY), high_ = glm::dvec2(-INFINITY);
    for (size_t i = 0; i < corners.size(); ++i) {
      points_[i] = {corners[i][u] - origin[u], corners[i][v] - origin[v]};
      low_ = glm::min(low_, points_[i]), high_ = glm::max(high_, points_[i]);
      next_[i] = static_cast<uint32_t>((i + 1) % corners.size());
      previous_[i] = static_cast<uint32_t>((i + corners.size() - 1) % corners.size());
    }
    // About one cell a corner, the cells as square as the polygon's box allows.
    const glm::dvec2 size = high_ - low_;
    const double n = static_cast<double>(corners.size());
    const double aspect = size.x > 0.0 && size.y > 0.0 ? size.x / size.y : 1.0;
    columns_ = static_cast<uint32_t>(std::clamp(std::round(std::sqrt(n * aspect)), 1.0, n));
    rows_ = static_cast<uint32_t>(std::clamp(std::round(n / columns_), 1.0, n));
    cells_.resize(size_t{columns_} * rows_);
    for (uint32_t i = 0; i < corners.size(); ++i) {
      convex_[i] = turns_left(i);
      if (!convex_[i]) add_reflex(i);
    }
  }

  // Returns the corner tests the ear tests made.
  size_t triangulate(std::vector<std::array<uint32_t, 3>>& triangles) {
    // Convex (no reflex corner): a fan from the first corner, which is exact for any convex polygon
    // and gives a non-planar quad the diagonal from its first corner, as Blender and trimesh cut it.
    if (std::all_of(cells_.begin(), cells_.end(), [](const auto& cell) { return cell.empty(); })) {
      for (uint32_t k = 1; k + 1 < points_.size(); ++k) triangles.push_back({0, k, k + 1});
      return 0;
    }
    size_t remaining = points_.size();
    uint32_t any_corner = 0;
    for (uint32_t corner = 0; corner < remaining; ++corner) consider(corner);
    while (remaining > 3) {
      // Cutting an ear changes only its two neighbours: a corner elsewhere that held a reflex corner
      // in its triangle still holds one, even if that corner turned convex (Eberly). So the
      // candidates stay complete with only the neighbours added again.
      uint32_t tip = no_corner;
      while (tip == no_corner && !candidates_.empty()) {
        std::pop_heap(candidates_.begin(), candidates_.end(), std::greater<>());
        const uint32_t candidate = candidates_.back().corner;
        candidates_.pop_back();
        if (!removed_[candidate] && is_ear(candidate)) tip = candidate;
      }
      // No ear left: the rest crosses itself (or has no area), and has no right triangulation. Cut
      // its corners in order all the same.
      if (tip == no_corner) tip = any_corner;
      const uint32_t before = previous_[tip], after = next_[tip];
      triangles.push_back({before, tip, after});
      removed_[tip] = true;
      if (cell_of_[tip] != no_cell) remove_reflex(tip);
      next_[before] = after;
      previous_[after] = before;
      --remaining;
      any_corner = after;
      for (const uint32_t neighbour : {before, after}) {
        update_convexity(neighbour);
        consider(neighbour);
      }
    }
    triangles.push_back({previous_[any_corner], any_corner, next_[any_corner]});
    return corner_tests_;
  }

 private:
  static constexpr uint32_t no_corner = UINT32_MAX, no_cell = UINT32_MAX;

  // A convex corner becomes a candidate ear, tested when it comes first: the fewest grid cells under
  // its triangle's box first, the fattest triangle of those first (a sliver of nearly collinear corners
  // faces either way by rounding). An ear test reads the reflex corners in those cells, so small ones
  // are cheap, and cutting them first leaves the large triangles (a comb's base, all its teeth under
  // its box) for when few reflex corners are left: a comb of 4096 corners took 3.5 times as long in
  // the order found.
  void consider(uint32_t corner) {
    if (!convex_[corner]) return;
    const glm::dvec2 a = points_[previous_[corner]], b = points_[corner], c = points_[next_[corner]];
    const auto [first_column, first_row] = cell_coordinates(glm::min(glm::min(a, b), c));
    const auto [last_column, last_row] = cell_coordinates(glm::max(glm::max(a, b), c));
    const double cells = (last_column - first_column + 1.0) * (last_row - first_row + 1.0);
    const double longest = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
    candidates_.push_back({cells, -orientation(a, b, c) / longest, corner});
    std::push_heap(candidates_.begin(), candidates_.end(), std::greater<>());
  }

  // A corner turning left by less than 1e-12 radians counts as straight: collinear corners of a
  // polygon that was turned and rounded turn by 1e-15 either way, and an ear of three of them would
  // face either way.
  bool turns_left(uint32_t corner) const {
    const glm::dvec2 a = points_[previous_[corner]], b = points_[corner], c = points_[next_[corner]];
    return orientation(a, b, c) > 1e-12 * glm::length(b - a) * glm::length(c - b);
  }

  void update_convexity(uint32_t corner) {
    convex_[corner] = turns_left(corner);
    // A simple polygon's corners only turn convex as ears go; one that crosses itself can turn one back.
    if (convex_[corner] && cell_of_[corner] != no_cell) remove_reflex(corner);
    if (!convex_[corner] && cell_of_[corner] == no_cell) add_reflex(corner);
  }

  // The reflex corners by cell of a uniform grid over the polygon's box, each cell's in any order:
  // an ear test reads the cells its triangle's box covers, and a corner leaves its cell as soon as it
  // is cut off or turns convex. (Sorted by x alone, a comb whose teeth run along x had every tooth's
  // triangle read every reflex corner: 4096 corners took 60 ms.)
  std::pair<uint32_t, uint32_t> cell_coordinates(glm::dvec2 p) const {
    const glm::dvec2 size = high_ - low_;
    const auto along = [](double t, double extent, uint32_t count) {
      return extent > 0.0 ? std::min(count - 1, static_cast<uint32_t>(std::max(0.0, (t / extent) * count))) : 0u;
    };
    return {along(p.x - low_.x, size.x, columns_), along(p.y - low_.y, size.y, rows_)};
  }
  void add_reflex(uint32_t corner) {
    const auto [column, row] = cell_coordinates(points_[corner]);
    cell_of_[corner] = row * columns_ + column;
    std::vector<uint32_t>& cell = cells_[cell_of_[corner]];
    place_in_cell_[corner] = static_cast<uint32_t>(cell.size());
    cell.push_back(corner);
  }
  void remove_reflex(uint32_t corner) {
    std::vector<uint32_t>& cell = cells_[cell_of_[corner]];
    const uint32_t last = cell.back();
    cell[place_in_cell_[corner]] = last;
    place_in_cell_[last] = place_in_cell_[corner];
    cell.pop_back();
    cell_of_[corner] = no_cell;
  }

  // A convex corner whose triangle with its two neighbours holds no reflex corner, on its edges
  // included. A corner at the same place as one of the triangle's (a polygon with a hole joined by a
  // doubled edge has such pairs) does not count as inside.
  bool is_ear(uint32_t corner) {
    if (!convex_[corner]) return false;
    const glm::dvec2 a = points_[previous_[corner]], b = points_[corner], c = points_[next_[corner]];
    const auto [first_column, first_row] = cell_coordinates(glm::min(glm::min(a, b), c));
    const auto [last_column, last_row] = cell_coordinates(glm::max(glm::max(a, b), c));
    for (uint32_t row = first_row; row <= last_row; ++row) {
      for (uint32_t column = first_column; column <= last_column; ++column) {
        for (const uint32_t other : cells_[row * columns_ + column]) {
          ++corner_tests_;
          const glm::dvec2 p = points_[other];
          if (p == a || p == b || p == c) continue;
          if (orientation(a, b, p) >= 0.0 && orientation(b, c, p) >= 0.0 && orientation(c, a, p) >= 0.0) return false;
        }
      }
    }
    return true;
  }

  std::vector<glm::dvec2> points_;
  std::vector<uint32_t> next_, previous_;
  std::vector<bool> convex_, removed_;
  glm::dvec2 low_{0.0}, high_{0.0};  // the polygon's box
  uint32_t columns_ = 1, rows_ = 1;
  std::vector<std::vector<uint32_t>> cells_;  // reflex corners, by cell: row * columns_ + column
  std::vector<uint32_t> cell_of_, place_in_cell_;  // each reflex corner's cell and place there; no_cell for the others
  struct Candidate {
    double cells, thinness;  // thinness: minus twice the area over the longest edge squared
    uint32_t corner;
    auto operator<=>(const Candidate&) const = default;
  };
  std::vector<Candidate> candidates_;  // a min-heap
  size_t corner_tests_ = 0;
};

}  // namespace

size_t triangulate_polygon(std::span<const glm::dvec3> corners, std::vector<std::array<uint32_t, 3>>& triangles) {
  if (corners.size() < 3) return 0;
  EarClipper clipper(corners);
  return clipper.triangulate(triangles);
}

}  // namespace vkray
