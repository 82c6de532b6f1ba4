#include "engine/reference/reference.hpp"

#include "engine/parallel.hpp"
#include "engine/surface_outputs.hpp"
#include "engine/unit_vector.hpp"
#include "shaders/gpu_layout.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <thread>

namespace vkray {

// Same formulation as shaders/intersect.glsl (Ray Tracing Gems ch. 7): discriminant from the
// perpendicular offset and roots without cancellation. Double precision makes even the
// tiny-far-sphere case exact to ~1e-16 relative.
double intersect_sphere(const glm::dvec3& f, double radius, const glm::dvec3& dir, double t_max, bool* near,
                        double* far_root) {
  const double a = glm::dot(dir, dir);
  const double b = glm::dot(f, dir);
  const glm::dvec3 f_perp = f - (b / a) * dir;
  const double disc = radius * radius - glm::dot(f_perp, f_perp);
  if (disc < 0.0) return t_max;
  const double c = glm::dot(f, f) - radius * radius;
  const double q = -(b + std::copysign(std::sqrt(a * disc), b));
  if (q == 0.0) return t_max;
  const double t0 = c / q;
  const double t1 = q / a;
  const bool near_root = std::min(t0, t1) > 0.0;
  if (far_root) *far_root = near_root ? std::max(t0, t1) : t_max;
  const double t = near_root ? std::min(t0, t1) : std::max(t0, t1);
  if (near) *near = near_root;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// In double the plane's point is subtracted first, which keeps large world coordinates exact; the
// GPU receives the offset relative to the scene anchor instead (engine/render/gpu_scene.cpp).
double intersect_plane(const glm::dvec3& normal, const glm::dvec3& point, const glm::dvec3& origin,
                       const glm::dvec3& dir, double t_max) {
  const double denom = glm::dot(normal, dir);
  if (denom == 0.0) return t_max;
  const double t = glm::dot(normal, point - origin) / denom;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

// Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013 (see the GLSL
// version for why): rays through a shared edge never fall between the two triangles. With
// claim_edges, an edge or vertex the ray passes exactly through belongs to one triangle alone, by
// the shader's rule (claims_edges in shaders/intersect.glsl).
double intersect_triangle(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2, const glm::dvec3& origin,
                          const glm::dvec3& dir, double t_max, bool claim_edges) {
  const glm::dvec3 ad = glm::abs(dir);
  const int kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
  int kx = (kz + 1) % 3;
  int ky = (kx + 1) % 3;
  if (dir[kz] < 0.0) std::swap(kx, ky);
  const double sx = dir[kx] / dir[kz], sy = dir[ky] / dir[kz], sz = 1.0 / dir[kz];
  auto to_ray_frame = [&](const glm::dvec3& vertex) {
    const glm::dvec3 p = vertex - origin;
    return glm::dvec3(p[kx] - sx * p[kz], p[ky] - sy * p[kz], p[kz]);
  };
  const glm::dvec3 a = to_ray_frame(v0), b = to_ray_frame(v1), c = to_ray_frame(v2);
  // p q - r s by Kahan's algorithm: within 2 ulp of the exact value (Jeannerod, Louvet and Muller,
  // Math. Comp. 82, 2013), so every sign is exact and 0 exactly where the value is: the triangles
  // around a vertex a ray passes near agree on which side of each edge it lies.
  auto difference_of_products = [](double p, double q, double r, double s) {
    const double rs = r * s;
    return std::fma(p, q, -rs) + std::fma(-r, s, rs);
  };
  const double u = difference_of_products(c.x, b.y, c.y, b.x);
  const double v = difference_of_products(a.x, c.y, a.y, c.x);
  const double w = difference_of_products(b.x, a.y, b.y, a.x);
  if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return t_max;
  const double det = u + v + w;
  if (det == 0.0) return t_max;
  if (claim_edges) {
    // Edges b->c, c->a, a->b, as u, v and w; counter-clockwise (det < 0) puts the triangle on their left.
    const std::array<std::array<glm::dvec3, 2>, 3> edges{{{b, c}, {c, a}, {a, b}}};
    const std::array<double, 3> edge_functions{u, v, w};
    for (size_t e = 0; e < 3; ++e) {
      const glm::dvec3 &from = edges[e][0], &to = edges[e][1];
      const bool upward = to.y > from.y || (to.y == from.y && to.x > from.x);
      if (edge_functions[e] == 0.0 && upward != (det < 0.0)) return t_max;
    }
  }
  const double t = sz * (u * a.z + v * b.z + w * c.z) / det;
  return (t > 0.0 && t < t_max) ? t : t_max;
}

namespace {

constexpr double infinity = std::numeric_limits<double>::infinity();
// At least one double step and box_margin outward: sphere boxes then hold the whole sphere, and
// node boxes keep their faces off what they hold (see enter_box).
constexpr double box_margin = 1e-200;
double step(double v, double direction) {
  return direction < 0 ? std::min(std::nextafter(v, -infinity), v - box_margin)
                       : std::max(std::nextafter(v, infinity), v + box_margin);
}
glm::dvec3 below(const glm::dvec3& v) { return {step(v.x, -1), step(v.y, -1), step(v.z, -1)}; }
glm::dvec3 above(const glm::dvec3& v) { return {step(v.x, 1), step(v.y, 1), step(v.z, 1)}; }

Box triangle_box(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2) {
  return {glm::min(v0, glm::min(v1, v2)), glm::max(v0, glm::max(v1, v2))};
}

}  // namespace

ReferenceScene::Tree ReferenceScene::build_tree(std::vector<TreeEntry> entries, const std::vector<Box>& boxes) {
  Tree tree;
  if (boxes.empty()) return tree;
  const Bvh bvh = build_bvh(boxes);
  tree.entries.reserve(entries.size());
  for (uint32_t i : bvh.primitive_order) tree.entries.push_back(entries[i]);
  tree.nodes = bvh.nodes;
  tree.child_boxes = child_bounds<Box>(bvh, [&](uint32_t slot) { return boxes[bvh.primitive_order[slot]]; });
  for (auto& children : tree.child_boxes) {
    for (Box& box : children) box = {below(box.lower), above(box.upper)};
  }
  return tree;
}

ReferenceScene::ReferenceScene(const Scene& scene, Mask ray_mask)
    : spheres_(scene.spheres), planes_(scene.planes), ray_mask_(ray_mask), mesh_trees_(scene.meshes.size()) {
  uint32_t index = 0;
  uint32_t vertex_base = 0;  // the world's vertex ids: each mesh's after the meshes before it
  std::vector<TreeEntry> entries;
  std::vector<Box> boxes;
  std::vector<bool> placed_mesh(scene.meshes.size(), false);
  for (const Instance& instance : scene.instances) {
    if (mask_hits(instance.mask, ray_mask)) placed_mesh[instance.mesh] = true;
  }
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const Mesh& mesh = scene.meshes[m];
    first_triangle_of_mesh_.push_back(index);
    // An instanced mesh's triangles in its own coordinates, where some instance the mask lets
    // through places it; the others' in the world's, where the mask lets the mesh through.
    const bool in_world = !mesh.instanced && mask_hits(mesh.mask, ray_mask);
    const uint32_t base = vertex_base;
    if (in_world) vertex_base += static_cast<uint32_t>(mesh.positions.size());
    if (!in_world && !placed_mesh[m]) {
      index += static_cast<uint32_t>(mesh.triangles.size());
      continue;
    }
    std::vector<Triangle>& triangles = in_world ? triangles_ : mesh_trees_[m].triangles;
    std::vector<TreeEntry> mesh_entries;
    std::vector<Box> mesh_boxes;
    for (const auto& corners : mesh.triangles) {
      const glm::dvec3& v0 = mesh.positions[corners[0]];
      const glm::dvec3& v1 = mesh.positions[corners[1]];
      const glm::dvec3& v2 = mesh.positions[corners[2]];
      const glm::dvec3 cross = glm::cross(v1 - v0, v2 - v0);
      if (cross != glm::dvec3(0.0)) {
        (in_world ? entries : mesh_entries).push_back({PrimitiveKind::triangle, static_cast<uint32_t>(triangles.size())});
        const uint32_t id_base = in_world ? base : 0;  // an instanced mesh's ids are its own
        triangles.push_back({v0, v1, v2, unit_vector(cross), index, {id_base + corners[0], id_base + corners[1], id_base + corners[2]}});
        (in_world ? boxes : mesh_boxes).push_back(triangle_box(v0, v1, v2));
      }
      ++index;
    }
    if (!in_world) mesh_trees_[m].tree = build_tree(std::move(mesh_entries), mesh_boxes);
  }
  for (uint32_t k = 0; k < scene.instances.size(); ++k) {
    const Instance& instance = scene.instances[k];
    const glm::dmat3 to_mesh = glm::inverse(instance.linear);
    const double winding = glm::determinant(instance.linear) < 0.0 ? -1.0 : 1.0;
    instances_.push_back({instance.mesh, to_mesh, instance.translation, winding * glm::transpose(to_mesh), instance.linear,
                          smallest_scale(instance.linear)});
    const Tree& mesh_tree = mesh_trees_[instance.mesh].tree;
    if (!mask_hits(instance.mask, ray_mask) || mesh_tree.empty()) continue;
    entries.push_back({PrimitiveKind::instance, k});
    const auto& root = mesh_tree.child_boxes[0];
    const Box mesh_box{glm::min(root[0].lower, root[1].lower), glm::max(root[0].upper, root[1].upper)};
    const Bounds placed_bounds = placed_box({mesh_box.lower, mesh_box.upper}, instance);
    boxes.push_back({below(placed_bounds.lower), above(placed_bounds.upper)});
  }
  for (uint32_t i = 0; i < spheres_.size(); ++i) {
    if (!mask_hits(spheres_[i].mask, ray_mask)) continue;
    entries.push_back({PrimitiveKind::sphere, i});
    boxes.push_back({below(spheres_[i].center - spheres_[i].radius), above(spheres_[i].center + spheres_[i].radius)});
  }
  tree_ = build_tree(std::move(entries), boxes);
}

void ReferenceScene::test_sphere(uint32_t index, const glm::dvec3& origin, const glm::dvec3& dir, ReferenceHit& hit) const {
  const glm::dvec3 f = origin - spheres_[index].center;
  bool near = false;
  const double t = intersect_sphere(f, spheres_[index].radius, dir, hit.t, &near);
  // Facing the ray by the root, as the shader does: outward where the ray enters, inward from inside.
  if (t < hit.t) hit = {t, (near ? 1.0 : -1.0) * (f + t * dir) / spheres_[index].radius, PrimitiveKind::sphere, index};
}

void ReferenceScene::test_triangle(const Triangle& triangle, const glm::dvec3& origin, const glm::dvec3& dir,
                                   ReferenceHit& hit, uint32_t instance) const {
  // Asking for hits up to the next double after the best distance lets an exact tie through, to be
  // settled by index, then by instance.
  const double t_max = std::nextafter(hit.t, no_hit);
  const double t = intersect_triangle(triangle.v0, triangle.v1, triangle.v2, origin, dir, t_max);
  const bool earlier = triangle.index < hit.index || (triangle.index == hit.index && instance < hit.instance);
  if (t < hit.t || (t == hit.t && t < t_max && hit.kind == PrimitiveKind::triangle && earlier)) {
    hit = {t, world_normal(triangle.normal, instance), PrimitiveKind::triangle, triangle.index, instance};
  }
}

glm::dvec3 ReferenceScene::world_normal(const glm::dvec3& normal, uint32_t instance) const {
  return instance == no_object ? normal : unit_vector(instances_[instance].normal_to_world * normal);
}

template <typename Visit>
void ReferenceScene::walk_instance(uint32_t instance, const glm::dvec3& origin, const glm::dvec3& dir, const double& t_max,
                                   Visit visit) const {
  const auto [mesh_origin, mesh_dir] = ray_in_mesh(instance, origin, dir);
  const MeshTree& mesh = mesh_trees_[instances_[instance].mesh];
  walk_tree(mesh.tree, mesh_origin, mesh_dir, t_max,
            [&](const TreeEntry& entry) { visit(mesh.triangles[entry.index], mesh_origin, mesh_dir); });
}

std::pair<glm::dvec3, glm::dvec3> ReferenceScene::ray_in_mesh(uint32_t instance, const glm::dvec3& origin,
                                                              const glm::dvec3& dir) const {
  return vkray::ray_in_mesh(instances_[instance].translation, instances_[instance].to_mesh, origin, dir);
}

namespace {

// Where the ray enters `box`, or +inf when it misses it or enters beyond t_max. Conservative like
// the shader's test (shaders/intersect.glsl) with gamma(3) of double on both ends: a box holding a
// hit, even one tied with the best so far, is never culled. Direction components below 1e-300
// (zeros) get the largest double as inverse, never 0 * inf = NaN; with faces at least box_margin
// from what a box holds, an origin inside the slab gets ends beyond 1e-200 * 1.8e308, farther than
// any hit, and a ray in the plane of a face meets nothing in the box (the shader does the same in
// float).
double enter_box(const Box& box, const glm::dvec3& origin, const glm::dvec3& inv_dir, double t_max) {
  double near = 0.0;
  double far = no_hit;
  for (int axis = 0; axis < 3; ++axis) {
    const double t0 = (box.lower[axis] - origin[axis]) * inv_dir[axis];
    const double t1 = (box.upper[axis] - origin[axis]) * inv_dir[axis];
    near = std::max(near, std::min(t0, t1));
    far = std::min(far, std::max(t0, t1));
  }
  constexpr double gamma3 = 3.0 * 0x1p-53 / (1.0 - 3.0 * 0x1p-53);
  return near <= far * (1.0 + 2.0 * gamma3) && near * (1.0 - 2.0 * gamma3) <= t_max ? near : no_hit;
}

}  // namespace

template <typename Visit>
void ReferenceScene::walk_tree(const Tree& tree, const glm::dvec3& origin, const glm::dvec3& dir, const double& t_max,
                               Visit visit) {
  glm::dvec3 inv_dir;
  for (int axis = 0; axis < 3; ++axis) {
    constexpr double tiny = 1e-300;
    inv_dir[axis] = std::abs(dir[axis]) < tiny ? std::copysign(std::numeric_limits<double>::max(), dir[axis])
                                               : 1.0 / dir[axis];
  }
  std::array<uint32_t, VKRAY_BVH_MAX_DEPTH + 1> stack;
  size_t stack_size = 0;
  uint32_t current = 0;
  while (true) {
    if (!is_leaf(current)) {
      // <= t_max rather than <: a triangle at exactly the best distance may still win the tie.
      const double enter0 = enter_box(tree.child_boxes[current][0], origin, inv_dir, t_max);
      const auto& children = tree.nodes[current];
      // A tree of one leaf is a root with that leaf as both children (Bvh::nodes): visited once.
      const double enter1 = children[1] == children[0] ? no_hit : enter_box(tree.child_boxes[current][1], origin, inv_dir, t_max);
      if (enter0 < no_hit && enter1 < no_hit) {
        const bool second_first = enter1 < enter0;
        stack[stack_size++] = children[second_first ? 0 : 1];
        current = children[second_first ? 1 : 0];
        continue;
      }
      if (enter0 < no_hit || enter1 < no_hit) {
        current = children[enter0 < no_hit ? 0 : 1];
        continue;
      }
    } else {
      for (uint32_t k = 0; k < leaf_count(current); ++k) visit(tree.entries[leaf_first(current) + k]);
    }
    if (stack_size == 0) return;
    current = stack[--stack_size];
  }
}

void ReferenceScene::nearest_in_tree(const glm::dvec3& origin, const glm::dvec3& dir, ReferenceHit& hit) const {
  walk_tree(tree_, origin, dir, hit.t, [&](const TreeEntry& entry) {
    if (entry.kind == PrimitiveKind::sphere) {
      test_sphere(entry.index, origin, dir, hit);
    } else if (entry.kind == PrimitiveKind::instance) {
      walk_instance(entry.index, origin, dir, hit.t, [&](const Triangle& triangle, const glm::dvec3& o, const glm::dvec3& d) {
        test_triangle(triangle, o, d, hit, entry.index);
      });
    } else {
      test_triangle(triangles_[entry.index], origin, dir, hit);
    }
  });
}

std::vector<ReferenceHit> ReferenceScene::first_hits(const glm::dvec3& origin, const glm::dvec3& dir, double t_max,
                                                     uint32_t count) const {
  std::vector<ReferenceHit> found;  // nearest first, at most `count`
  double bound = t_max;             // the last one's distance once there are `count`
  auto add = [&](const ReferenceHit& hit) {
    if (!(hit.t < bound)) return;
    found.insert(std::upper_bound(found.begin(), found.end(), hit.t, [](double t, const ReferenceHit& h) { return t < h.t; }), hit);
    if (found.size() > count) found.pop_back();
    if (found.size() == count) bound = found.back().t;
  };
  for (uint32_t i = 0; i < planes_.size(); ++i) {
    if (!mask_hits(planes_[i].mask, ray_mask_)) continue;
    add({intersect_plane(planes_[i].normal, planes_[i].point, origin, dir, bound), planes_[i].normal, PrimitiveKind::plane, i});
  }
  if (!tree_.empty()) {
    walk_tree(tree_, origin, dir, bound, [&](const TreeEntry& entry) {
      if (entry.kind == PrimitiveKind::instance) {
        walk_instance(entry.index, origin, dir, bound, [&](const Triangle& triangle, const glm::dvec3& o, const glm::dvec3& d) {
          add({intersect_triangle(triangle.v0, triangle.v1, triangle.v2, o, d, bound, true),
               world_normal(triangle.normal, entry.index), PrimitiveKind::triangle, triangle.index, entry.index});
        });
      } else if (entry.kind == PrimitiveKind::sphere) {
        const Sphere& sphere = spheres_[entry.index];
        const glm::dvec3 f = origin - sphere.center;
        bool near = false;
        double far_root = bound;
        const double t = intersect_sphere(f, sphere.radius, dir, bound, &near, &far_root);
        // Facing the ray by the root, as test_sphere does; the far root after a near one faces inward.
        if (t < bound) add({t, (near ? 1.0 : -1.0) * (f + t * dir) / sphere.radius, PrimitiveKind::sphere, entry.index});
        if (far_root < bound) {
          add({far_root, -(f + far_root * dir) / sphere.radius, PrimitiveKind::sphere, entry.index});
        }
      } else {
        const Triangle& triangle = triangles_[entry.index];
        add({intersect_triangle(triangle.v0, triangle.v1, triangle.v2, origin, dir, bound, true), triangle.normal,
             PrimitiveKind::triangle, triangle.index});
      }
    });
  }
  for (ReferenceHit& hit : found) {
    hit.normal = glm::normalize(hit.normal);
    if (hit.kind != PrimitiveKind::sphere && glm::dot(hit.normal, dir) > 0.0) hit.normal = -hit.normal;
  }
  found.resize(count);  // misses past the last: t = +infinity, kind none
  return found;
}

uint32_t ReferenceScene::count_crossings(const glm::dvec3& origin, const glm::dvec3& dir, double t_max) const {
  uint32_t crossings = 0;
  for (const Plane& plane : planes_) {
    if (mask_hits(plane.mask, ray_mask_) && intersect_plane(plane.normal, plane.point, origin, dir, t_max) < t_max) ++crossings;
  }
  if (tree_.empty()) return crossings;
  walk_tree(tree_, origin, dir, t_max, [&](const TreeEntry& entry) {
    if (entry.kind == PrimitiveKind::instance) {
      walk_instance(entry.index, origin, dir, t_max, [&](const Triangle& triangle, const glm::dvec3& o, const glm::dvec3& d) {
        if (intersect_triangle(triangle.v0, triangle.v1, triangle.v2, o, d, t_max, true) < t_max) ++crossings;
      });
    } else if (entry.kind == PrimitiveKind::sphere) {
      // Both roots that lie ahead within the range, a tangent's double root twice (as the shader's
      // sphere_crossings).
      double far_root = t_max;
      const double t = intersect_sphere(origin - spheres_[entry.index].center, spheres_[entry.index].radius, dir, t_max,
                                        nullptr, &far_root);
      crossings += (t < t_max ? 1 : 0) + (far_root < t_max ? 1 : 0);
    } else {
      const Triangle& triangle = triangles_[entry.index];
      if (intersect_triangle(triangle.v0, triangle.v1, triangle.v2, origin, dir, t_max, true) < t_max) ++crossings;
    }
  });
  return crossings;
}

// Planes first, then spheres and triangles, in the shader's order (the first of equal distances
// wins, but for the triangles' tie-break), up to VKRAY_PRIMITIVE_T_MAX behind the nearest plane:
// the shader's rule for coincident surfaces (shaders/gpu_layout.h).
ReferenceHit ReferenceScene::trace_with(const glm::dvec3& origin, const glm::dvec3& dir, double t_max,
                                        bool brute_force) const {
  ReferenceHit plane_hit;
  plane_hit.t = t_max;
  for (uint32_t i = 0; i < planes_.size(); ++i) {
    if (!mask_hits(planes_[i].mask, ray_mask_)) continue;
    const double t = intersect_plane(planes_[i].normal, planes_[i].point, origin, dir, plane_hit.t);
    if (t < plane_hit.t) plane_hit = {t, planes_[i].normal, PrimitiveKind::plane, i};
  }
  ReferenceHit hit;
  hit.t = plane_hit.kind != PrimitiveKind::none ? VKRAY_PRIMITIVE_T_MAX(plane_hit.t, std::abs(glm::dot(plane_hit.normal, dir)))
                                                : t_max;
  if (brute_force) {
    for (uint32_t i = 0; i < spheres_.size(); ++i) {
      if (mask_hits(spheres_[i].mask, ray_mask_)) test_sphere(i, origin, dir, hit);
    }
    for (const auto& triangle : triangles_) test_triangle(triangle, origin, dir, hit);
    for (const TreeEntry& entry : tree_.entries) {
      if (entry.kind != PrimitiveKind::instance) continue;
      const auto [mesh_origin, mesh_dir] = ray_in_mesh(entry.index, origin, dir);
      for (const auto& triangle : mesh_trees_[instances_[entry.index].mesh].triangles) {
        test_triangle(triangle, mesh_origin, mesh_dir, hit, entry.index);
      }
    }
  } else if (!tree_.empty()) {
    nearest_in_tree(origin, dir, hit);
  }
  if (hit.kind == PrimitiveKind::none) hit = plane_hit;
  if (hit.kind == PrimitiveKind::none) hit.t = no_hit;
  if (hit.kind != PrimitiveKind::none) {
    hit.normal = glm::normalize(hit.normal);
    if (hit.kind != PrimitiveKind::sphere && glm::dot(hit.normal, dir) > 0.0) hit.normal = -hit.normal;
  }
  return hit;
}

ReferenceHit ReferenceScene::trace(const glm::dvec3& origin, const glm::dvec3& dir, double t_max) const {
  return trace_with(origin, dir, t_max, false);
}

ReferenceHit ReferenceScene::trace_brute_force(const glm::dvec3& origin, const glm::dvec3& dir) const {
  return trace_with(origin, dir, no_hit, true);
}

ObjectPrimitive ReferenceScene::source(const ReferenceHit& hit) const {
  const auto meshes = static_cast<uint32_t>(first_triangle_of_mesh_.size());
  switch (hit.kind) {
    case PrimitiveKind::triangle: {
      // The last mesh whose first triangle is at or before the hit's (empty meshes share a first).
      const auto next = std::upper_bound(first_triangle_of_mesh_.begin(), first_triangle_of_mesh_.end(), hit.index);
      const auto mesh = static_cast<uint32_t>(next - first_triangle_of_mesh_.begin()) - 1;
      return {mesh, hit.index - first_triangle_of_mesh_[mesh]};
    }
    case PrimitiveKind::sphere:
      return {meshes + hit.index, hit.index};
    case PrimitiveKind::plane:
      return {meshes + static_cast<uint32_t>(spheres_.size()) + hit.index, hit.index};
    default:
      return {};
  }
}

std::vector<ReferenceHit> render_reference_hits(const ReferenceScene& scene, const Camera& camera,
                                                uint32_t width, uint32_t height,
                                                const std::function<void(double)>& progress) {
  const CameraBasis basis = make_camera_basis(camera, width, height);
  std::vector<ReferenceHit> hits(size_t{width} * height);
  parallel_for_strided(height, [&](size_t row, size_t worker) {
    const auto j = static_cast<uint32_t>(row);
    for (uint32_t i = 0; i < width; ++i) {
      const PixelRay ray = pixel_ray(camera, basis, i, j, width, height);
      hits[size_t{j} * width + i] = scene.trace(ray.origin, ray.direction);
    }
    if (progress && worker == 0) progress(static_cast<double>(j + 1) / height);
  });
  return hits;
}

Frame float32_ray_frame(const ReferenceScene& scene, const Camera& camera, uint32_t width, uint32_t height,
                        AovSet aovs) {
  // Straight into a float frame, not through a second hit per pixel: at 7680x4320 the hits would
  // be another 1.6 GB beside the reference's.
  const CameraBasis basis = make_camera_basis(camera, width, height);
  AovSet traced;
  for (Aov aov : {Aov::depth, Aov::normal}) {
    if (aovs.has(aov)) traced.add(aov);
  }
  Frame frame(width, height, traced);
  frame.allocate();
  parallel_for_strided(height, [&](size_t row, size_t) {
    const auto j = static_cast<uint32_t>(row);
    for (uint32_t i = 0; i < width; ++i) {
      store_reference_hit(frame, size_t{j} * width + i,
                          scene.trace(basis.origin, float32_ray_direction(basis, i, j, width, height)));
    }
  });
  return frame;
}

ReferenceHit trace_reference_ray(const ReferenceScene& scene, const GivenRay& ray, double t_min, double t_max) {
  if (t_min == 0.0) return scene.trace({ray[0], ray[1], ray[2]}, unit_vector({ray[3], ray[4], ray[5]}), t_max);
  const GivenRay start = range_start_ray(ray, t_min);
  ReferenceHit hit = scene.trace({start[0], start[1], start[2]}, {start[3], start[4], start[5]}, t_max - t_min);
  hit.t += t_min;  // a miss stays +infinity
  return hit;
}

std::vector<ReferenceHit> first_reference_hits(const ReferenceScene& scene, const GivenRay& ray, double t_min, double t_max,
                                               uint32_t count) {
  if (t_min == 0.0) return scene.first_hits({ray[0], ray[1], ray[2]}, unit_vector({ray[3], ray[4], ray[5]}), t_max, count);
  const GivenRay start = range_start_ray(ray, t_min);
  std::vector<ReferenceHit> hits = scene.first_hits({start[0], start[1], start[2]}, {start[3], start[4], start[5]}, t_max - t_min, count);
  for (ReferenceHit& hit : hits) hit.t += t_min;  // a miss stays +infinity
  return hits;
}

uint32_t count_reference_crossings(const ReferenceScene& scene, const GivenRay& ray, double t_min, double t_max) {
  if (t_min == 0.0) return scene.count_crossings({ray[0], ray[1], ray[2]}, unit_vector({ray[3], ray[4], ray[5]}), t_max);
  const GivenRay start = range_start_ray(ray, t_min);
  return scene.count_crossings({start[0], start[1], start[2]}, {start[3], start[4], start[5]}, t_max - t_min);
}

std::vector<ReferenceHit> trace_reference_rays(const ReferenceScene& scene, std::span<const GivenRay> rays,
                                               const RayRanges& ranges) {
  check_given_rays(rays);
  check_ray_ranges(rays, ranges);
  std::vector<ReferenceHit> hits(rays.size());
  parallel_for_chunks(
      rays.size(),
      [&](size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) hits[k] = trace_reference_ray(scene, rays[k], ranges.start(k), ranges.end(k));
      },
      1);
  return hits;
}

void store_reference_hit(Frame& frame, size_t pixel, const ReferenceHit& hit) {
  if (!frame.depth.empty()) frame.depth[pixel] = static_cast<float>(hit.t);
  if (!frame.depth64.empty()) frame.depth64[pixel] = hit.t;
  if (!frame.normal.empty()) {
    for (size_t c = 0; c < 3; ++c) frame.normal[c * frame.pixel_count() + pixel] = static_cast<float>(hit.normal[int(c)]);
  }
  if (!frame.normal64.empty()) {
    for (size_t c = 0; c < 3; ++c) frame.normal64[c * frame.pixel_count() + pixel] = hit.normal[int(c)];
  }
}

Frame reference_frame(const ReferenceScene& scene, const Scene& source, const std::vector<ReferenceHit>& hits,
                      const Camera& camera, uint32_t width, uint32_t height, AovSet aovs, bool doubles) {
  Frame frame(width, height, aovs);
  frame.camera = camera;
  frame.allocate(doubles || aovs.has_camera_outputs());  // the camera outputs from the exact depth
  for (size_t p = 0; p < frame.pixel_count(); ++p) {
    store_reference_hit(frame, p, hits[p]);
    if (aovs.has_ids() || aovs.has_surface_outputs()) store_ids(frame, p, scene.source(hits[p]), hits[p].instance);
  }
  if (aovs.has(Aov::uv)) fill_pixel_uv(frame);
  add_camera_outputs(frame);
  add_surface_outputs(frame, source);
  return frame;
}

}  // namespace vkray
