// The reference's point queries, exact in double: the nearest point of the scene (a walk of its tree
// nearest box first, pruned by the distance found so far), and the generalized winding number (a walk
// of its tree with the caps of engine/scene/winding_caps.hpp); each with a brute force to check it.
#include "engine/reference/reference.hpp"

#include "engine/parallel.hpp"
#include "engine/scene/winding_caps.hpp"
#include "engine/unit_vector.hpp"
#include "shaders/point_geometry.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <numbers>
#include <tuple>

namespace vkray {
namespace {

constexpr double four_pi = 4.0 * std::numbers::pi;

// The distance from `point` to `box` (0 inside it).
double box_distance(const Box& box, const glm::dvec3& point) {
  return glm::length(glm::max(glm::max(box.lower - point, point - box.upper), glm::dvec3(0.0)));
}

// Ties at exactly the same distance go to the lowest kind, index and instance, in that order: the
// tree and brute force then agree on the primitive.
bool nearer(const PointHit& candidate, const PointHit& best) {
  return std::tie(candidate.distance, candidate.kind, candidate.index, candidate.instance) <
         std::tie(best.distance, best.kind, best.index, best.instance);
}

// The nearest point of triangle (v0, v1, v2), given relative to `point` (offsets), as a PointHit's
// distance and point.
PointHit nearest_on(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& point) {
  const glm::dvec2 weights = point_geometry::nearest_on_triangle(a, b, c);
  const glm::dvec3 offset = a + weights.x * (b - a) + weights.y * (c - a);
  PointHit hit;
  hit.distance = glm::length(offset);
  hit.point = point + offset;
  return hit;
}

}  // namespace

// The caps of the world's tree and of each instanced mesh's, with the positions their edges' vertex
// ids name.
struct ReferenceScene::Caps {
  struct OfTree {
    WindingCaps caps;
    std::vector<glm::dvec3> positions;  // by vertex id
  };
  OfTree world;
  std::vector<OfTree> meshes;  // by mesh: an instanced mesh's
};

namespace {

// `tree`'s caps over `triangles` (its entries of kind triangle index them); `capped(entry)` as
// build_winding_caps takes it.
template <typename Triangles, typename Capped>
auto make_caps(const auto& tree, const Triangles& triangles, Capped capped) {
  typename ReferenceScene::Caps::OfTree made;
  uint32_t most = 0;
  for (const auto& triangle : triangles) most = std::max({most, triangle.corners[0] + 1, triangle.corners[1] + 1, triangle.corners[2] + 1});
  made.positions.resize(most);
  for (const auto& triangle : triangles) {
    made.positions[triangle.corners[0]] = triangle.v0, made.positions[triangle.corners[1]] = triangle.v1;
    made.positions[triangle.corners[2]] = triangle.v2;
  }
  if (tree.empty()) return made;
  // The tree's entries are in leaf order already: its primitive order is the identity.
  Bvh shape;
  shape.nodes = tree.nodes;
  shape.primitive_order.resize(tree.entries.size());
  for (uint32_t k = 0; k < shape.primitive_order.size(); ++k) shape.primitive_order[k] = k;
  made.caps = build_winding_caps(
      shape,
      [&](uint32_t entry) -> std::optional<std::array<uint32_t, 3>> {
        if (tree.entries[entry].kind != PrimitiveKind::triangle) return std::nullopt;
        return triangles[tree.entries[entry].index].corners;
      },
      [&](uint32_t entry) { return capped(tree.entries[entry]); });
  return made;
}

}  // namespace

const ReferenceScene::Caps& ReferenceScene::caps() const {
  std::call_once(caps_made_, [&] {
    auto made = std::make_shared<Caps>();
    made->meshes.resize(mesh_trees_.size());
    for (size_t m = 0; m < mesh_trees_.size(); ++m) {
      made->meshes[m] = make_caps(mesh_trees_[m].tree, mesh_trees_[m].triangles, [](const TreeEntry&) { return true; });
    }
    // An instance outside its subtree's box contributes nothing where its mesh is closed (its own
    // caps' root is empty); one of a mesh that is not must be walked to.
    made->world = make_caps(tree_, triangles_, [&](const TreeEntry& entry) {
      return entry.kind != PrimitiveKind::instance || made->meshes[instances_[entry.index].mesh].caps.root.empty();
    });
    caps_ = std::move(made);
  });
  return *caps_;
}

ObjectPrimitive ReferenceScene::source(const PointHit& hit) const {
  ReferenceHit as_ray;
  as_ray.kind = hit.kind;
  as_ray.index = hit.index;
  as_ray.instance = hit.instance;
  return source(as_ray);
}

// The nearest so far of what a query measures, within its largest distance (inclusive: a point on a
// surface is found at 0 of it).
class ReferenceScene::NearestSoFar {
 public:
  explicit NearestSoFar(double max_distance) { best_.distance = max_distance; }
  double distance() const { return best_.distance; }
  void offer(const PointHit& candidate) {
    if (best_.kind == PrimitiveKind::none ? candidate.distance <= best_.distance : nearer(candidate, best_)) best_ = candidate;
  }
  // The answer: a miss's distance +inf, whatever the bound.
  PointHit found() const {
    PointHit answer = best_;
    if (answer.kind == PrimitiveKind::none) answer.distance = no_hit;
    return answer;
  }

 private:
  PointHit best_;
};

template <typename Visit>
void ReferenceScene::nearest_in_mesh(uint32_t instance, const glm::dvec3& point, const NearestSoFar& nearest, Visit visit) const {
  const Placement& placement = instances_[instance];
  const MeshTree& mesh = mesh_trees_[placement.mesh];
  if (mesh.tree.empty()) return;
  // Boxes in the mesh's coordinates, their distances there shrunk by the placement's least scale: a
  // lower bound of the world's.
  const glm::dvec3 in_mesh = placement.to_mesh * (point - placement.translation);
  std::vector<std::pair<uint32_t, double>> stack{{0u, 0.0}};
  while (!stack.empty()) {
    const auto [node, below] = stack.back();
    stack.pop_back();
    if (below > nearest.distance()) continue;
    const auto& children = mesh.tree.nodes[node];
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children[1] == children[0]) break;
      const double distance = placement.smallest_scale * box_distance(mesh.tree.child_boxes[node][side], in_mesh);
      if (distance > nearest.distance()) continue;
      if (!is_leaf(children[side])) {
        stack.emplace_back(children[side], distance);
        continue;
      }
      for (uint32_t k = 0; k < leaf_count(children[side]); ++k) {
        visit(mesh.triangles[mesh.tree.entries[leaf_first(children[side]) + k].index]);
      }
    }
  }
}

PointHit ReferenceScene::plane_hit(uint32_t index, const glm::dvec3& point) const {
  const Plane& plane = planes_[index];
  const double height = glm::dot(plane.normal, point - plane.point);
  return {std::abs(height), point - height * plane.normal, plane.normal, PrimitiveKind::plane, index};
}

PointHit ReferenceScene::sphere_hit(uint32_t index, const glm::dvec3& point) const {
  const Sphere& sphere = spheres_[index];
  const glm::dvec3 away = point - sphere.center;
  const double from_centre = glm::length(away);
  // At the centre every point of the sphere is nearest: the one along +x (as the shaders take it).
  const glm::dvec3 outward = from_centre > 0.0 ? away / from_centre : glm::dvec3(1.0, 0.0, 0.0);
  return {std::abs(from_centre - sphere.radius), sphere.center + sphere.radius * outward, outward, PrimitiveKind::sphere, index};
}

PointHit ReferenceScene::triangle_hit(const Triangle& triangle, uint32_t instance, const glm::dvec3& point) const {
  PointHit hit;
  if (instance == no_object) {
    hit = nearest_on(triangle.v0 - point, triangle.v1 - point, triangle.v2 - point, point);
    hit.normal = triangle.normal;
  } else {  // in the world's coordinates: the nearest point of an unevenly scaled placement too
    const Placement& placement = instances_[instance];
    const glm::dvec3 from = placement.translation - point;
    hit = nearest_on(placement.linear * triangle.v0 + from, placement.linear * triangle.v1 + from, placement.linear * triangle.v2 + from,
                     point);
    hit.normal = unit_vector(glm::transpose(placement.to_mesh) * triangle.normal);
  }
  hit.kind = PrimitiveKind::triangle;
  hit.index = triangle.index;
  hit.instance = instance;
  return hit;
}

PointHit ReferenceScene::closest_point(const glm::dvec3& point, double max_distance) const {
  NearestSoFar nearest(max_distance);
  for (uint32_t i = 0; i < planes_.size(); ++i) {
    if (mask_hits(planes_[i].mask, ray_mask_)) nearest.offer(plane_hit(i, point));
  }
  if (tree_.empty()) return nearest.found();
  std::vector<std::pair<uint32_t, double>> stack{{0u, 0.0}};
  while (!stack.empty()) {
    const auto [node, below] = stack.back();
    stack.pop_back();
    if (below > nearest.distance()) continue;
    const auto& children = tree_.nodes[node];
    // The nearer child last on the stack: walked first.
    std::array<std::pair<uint32_t, double>, 2> sides;
    int count = 0;
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children[1] == children[0]) break;
      sides[count++] = {children[side], box_distance(tree_.child_boxes[node][side], point)};
    }
    if (count == 2 && sides[1].second > sides[0].second) std::swap(sides[0], sides[1]);
    for (int k = 0; k < count; ++k) {
      const auto [child, distance] = sides[k];
      if (distance > nearest.distance()) continue;
      if (!is_leaf(child)) {
        stack.emplace_back(child, distance);
        continue;
      }
      for (uint32_t e = 0; e < leaf_count(child); ++e) {
        const TreeEntry& entry = tree_.entries[leaf_first(child) + e];
        if (entry.kind == PrimitiveKind::triangle) {
          nearest.offer(triangle_hit(triangles_[entry.index], no_object, point));
        } else if (entry.kind == PrimitiveKind::sphere) {
          nearest.offer(sphere_hit(entry.index, point));
        } else {
          nearest_in_mesh(entry.index, point, nearest,
                          [&](const Triangle& triangle) { nearest.offer(triangle_hit(triangle, entry.index, point)); });
        }
      }
    }
  }
  return nearest.found();
}

PointHit ReferenceScene::closest_point_brute_force(const glm::dvec3& point, double max_distance) const {
  NearestSoFar nearest(max_distance);
  for (uint32_t i = 0; i < planes_.size(); ++i) {
    if (mask_hits(planes_[i].mask, ray_mask_)) nearest.offer(plane_hit(i, point));
  }
  for (const TreeEntry& entry : tree_.entries) {
    if (entry.kind == PrimitiveKind::triangle) {
      nearest.offer(triangle_hit(triangles_[entry.index], no_object, point));
    } else if (entry.kind == PrimitiveKind::sphere) {
      nearest.offer(sphere_hit(entry.index, point));
    } else {
      for (const Triangle& triangle : mesh_trees_[instances_[entry.index].mesh].triangles) {
        nearest.offer(triangle_hit(triangle, entry.index, point));
      }
    }
  }
  return nearest.found();
}

namespace {

// The winding number times 4 pi of `tree`'s triangles at `point` (in the tree's coordinates), walked
// with its caps; `other(entry)` gives an entry that is no triangle its share (times 4 pi).
template <typename Tree, typename Triangles, typename Other>
double winding_in_tree(const Tree& tree, const ReferenceScene::Caps::OfTree& made, const Triangles& triangles, const glm::dvec3& point,
                       Other other) {
  if (tree.empty()) return 0.0;
  const auto angle = [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    return point_geometry::solid_angle(a - point, b - point, c - point);
  };
  const auto entry_share = [&](const auto& entry) {
    if (entry.kind != PrimitiveKind::triangle) return other(entry);
    const auto& triangle = triangles[entry.index];
    return angle(triangle.v0, triangle.v1, triangle.v2);
  };
  double total = 0.0;
  std::vector<uint32_t> stack{0u};
  while (!stack.empty()) {
    const uint32_t node = stack.back();
    stack.pop_back();
    const auto& children = tree.nodes[node];
    for (int side = 0; side < 2; ++side) {
      if (side == 1 && children[1] == children[0]) break;
      const uint32_t child = children[side];
      if (is_leaf(child)) {
        for (uint32_t k = 0; k < leaf_count(child); ++k) total += entry_share(tree.entries[leaf_first(child) + k]);
        continue;
      }
      const Box& box = tree.child_boxes[node][side];
      const uint32_t first = made.caps.first[node][side];
      // A cap where the point lies half the box's diagonal from it or more (its terms then well
      // conditioned, as the shaders take them: shaders/point_walk.glsl).
      if (first == WindingCaps::no_cap || box_distance(box, point) < 0.5 * glm::length(box.upper - box.lower)) {
        stack.push_back(child);
        continue;
      }
      const glm::dvec3 centre = 0.5 * (box.lower + box.upper);
      for (uint32_t e = first; e < first + made.caps.count[node][side]; ++e) {
        const CapEdge& edge = made.caps.edges[e];
        total += angle(made.positions[edge.from], made.positions[edge.to], centre);
      }
    }
  }
  return total;
}

}  // namespace

double ReferenceScene::winding_number(const glm::dvec3& point) const {
  const Caps& made = caps();
  double total = 0.0;
  for (const Plane& plane : planes_) {
    if (mask_hits(plane.mask, ray_mask_) && glm::dot(plane.normal, point - plane.point) < 0.0) total += four_pi;
  }
  total += winding_in_tree(tree_, made.world, triangles_, point, [&](const TreeEntry& entry) {
    if (entry.kind == PrimitiveKind::sphere) {
      const Sphere& sphere = spheres_[entry.index];
      return glm::length(point - sphere.center) < sphere.radius ? four_pi : 0.0;
    }
    const Placement& placement = instances_[entry.index];
    const MeshTree& mesh = mesh_trees_[placement.mesh];
    const glm::dvec3 in_mesh = placement.to_mesh * (point - placement.translation);
    return winding_in_tree(mesh.tree, made.meshes[placement.mesh], mesh.triangles, in_mesh, [](const TreeEntry&) { return 0.0; });
  });
  return total / four_pi;
}

double ReferenceScene::winding_number_brute_force(const glm::dvec3& point) const {
  double total = 0.0;
  for (const Plane& plane : planes_) {
    if (mask_hits(plane.mask, ray_mask_) && glm::dot(plane.normal, point - plane.point) < 0.0) total += four_pi;
  }
  for (const TreeEntry& entry : tree_.entries) {
    if (entry.kind == PrimitiveKind::triangle) {
      const Triangle& t = triangles_[entry.index];
      total += point_geometry::solid_angle(t.v0 - point, t.v1 - point, t.v2 - point);
    } else if (entry.kind == PrimitiveKind::sphere) {
      total += glm::length(point - spheres_[entry.index].center) < spheres_[entry.index].radius ? four_pi : 0.0;
    } else {
      const Placement& placement = instances_[entry.index];
      const glm::dvec3 in_mesh = placement.to_mesh * (point - placement.translation);
      for (const Triangle& t : mesh_trees_[placement.mesh].triangles) {
        total += point_geometry::solid_angle(t.v0 - in_mesh, t.v1 - in_mesh, t.v2 - in_mesh);
      }
    }
  }
  return total / four_pi;
}

void answer_point(const ReferenceScene& reference, const glm::dvec3& point, double max_distance, HitQuery query, PointHits& hits,
                  size_t k) {
  if (query == HitQuery::winding) {
    hits.store(k, reference.winding_number(point), glm::dvec3(0.0), {}, no_object);
    return;
  }
  const PointHit hit = reference.closest_point(point, max_distance);
  hits.store(k, hit.distance, hit.kind == PrimitiveKind::none ? glm::dvec3(0.0) : hit.point - point, reference.source(hit), hit.instance);
}

PointHits reference_point_hits(const ReferenceScene& reference, std::span<const glm::dvec3> points, std::span<const double> max_distances,
                               HitQuery query) {
  check_query_points(points, max_distances);
  PointHits hits;
  hits.allocate(points.size(), true, query == HitQuery::nearest);
  parallel_for_chunks(points.size(), [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      answer_point(reference, points[k], max_distance_of(max_distances, k), query, hits, k);
    }
  });
  return hits;
}

}  // namespace vkray
