#include "engine/scene/mesh_generators.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

namespace vkray {

glm::dvec3 PortableRandom::unit_vector() {
  while (true) {
    const double x = uniform(-1.0, 1.0);
    const double y = uniform(-1.0, 1.0);
    const glm::dvec3 v(x, y, uniform(-1.0, 1.0));
    const double length_squared = glm::dot(v, v);
    if (length_squared > 1e-6 && length_squared <= 1.0) return v / std::sqrt(length_squared);
  }
}

uint32_t sphere_mesh_frequency(size_t approx_triangles) {
  const auto below = static_cast<uint32_t>(std::sqrt(static_cast<double>(approx_triangles) / 20.0));
  if (below == 0) return 1;
  const auto count = [](uint64_t f) { return 20 * f * f; };
  const uint64_t target = approx_triangles;
  const uint64_t low = count(below), high = count(below + 1u);
  return target - std::min(target, low) <= high - target ? below : below + 1u;
}

Mesh make_sphere_mesh(size_t approx_triangles, const glm::dvec3& center, double radius) {
  // The icosahedron: corners (0, +-1, +-t) and their cyclic permutations, t the golden ratio; faces
  // counter-clockwise seen from outside.
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<glm::dvec3, 12> corners = {{{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                               {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                               {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}}};
  const std::array<std::array<uint32_t, 3>, 20> faces = {{{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                                          {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                          {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                                          {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}}};
  const uint32_t f = sphere_mesh_frequency(approx_triangles);

  Mesh mesh;
  mesh.positions.reserve(10 * size_t{f} * f + 2);
  mesh.triangles.reserve(20 * size_t{f} * f);
  // A point of the (flat) icosahedron, pushed onto the sphere.
  auto add = [&](const glm::dvec3& flat) { mesh.positions.push_back(center + radius * glm::normalize(flat)); };
  for (const auto& corner : corners) add(corner);

  // Points inside each edge, made once from the edge's lower-numbered corner, so both faces along
  // an edge use the same vertices (indices and bits): the mesh is closed.
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> edge_first;  // first of its f - 1 points
  for (const auto& face : faces) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = std::min(face[k], face[(k + 1) % 3]), b = std::max(face[k], face[(k + 1) % 3]);
      if (!edge_first.emplace(std::pair{a, b}, static_cast<uint32_t>(mesh.positions.size())).second) continue;
      for (uint32_t s = 1; s < f; ++s) add(double(f - s) * corners[a] + double(s) * corners[b]);
    }
  }
  // `steps` of f from corner `from` towards corner `to`, both ends excluded.
  auto edge_point = [&](uint32_t from, uint32_t to, uint32_t steps) {
    return from < to ? edge_first.at({from, to}) + steps - 1 : edge_first.at({to, from}) + (f - steps) - 1;
  };

  for (const auto& face : faces) {
    const glm::dvec3 &c0 = corners[face[0]], &c1 = corners[face[1]], &c2 = corners[face[2]];
    // Interior points, a steps towards c1 and b towards c2 (a, b >= 1, a + b <= f - 1), row by row.
    const auto interior_first = static_cast<uint32_t>(mesh.positions.size());
    std::vector<uint32_t> row_first(f + 1, 0);
    for (uint32_t a = 1, next = interior_first; a + 2 <= f; ++a) {
      row_first[a] = next;
      for (uint32_t b = 1; a + b + 1 <= f; ++b, ++next) add(double(f - a - b) * c0 + double(a) * c1 + double(b) * c2);
    }
    auto vertex = [&](uint32_t a, uint32_t b) -> uint32_t {
      if (a == 0 && b == 0) return face[0];
      if (a == f) return face[1];
      if (b == f) return face[2];
      if (b == 0) return edge_point(face[0], face[1], a);
      if (a == 0) return edge_point(face[0], face[2], b);
      if (a + b == f) return edge_point(face[1], face[2], b);
      return row_first[a] + b - 1;
    };
    for (uint32_t a = 0; a < f; ++a) {
      for (uint32_t b = 0; a + b < f; ++b) {
        mesh.triangles.push_back({vertex(a, b), vertex(a + 1, b), vertex(a, b + 1)});
        if (a + b + 2 <= f) mesh.triangles.push_back({vertex(a + 1, b), vertex(a + 1, b + 1), vertex(a, b + 1)});
      }
    }
  }
  return mesh;
}

namespace {

double largest_side(const Box& box) {
  const glm::dvec3 side = box.upper - box.lower;
  return std::max({side.x, side.y, side.z});
}

double default_triangle_size(const Box& box, size_t triangles) {
  return largest_side(box) / std::cbrt(static_cast<double>(std::max<size_t>(triangles, 1)));
}

// Three vertices within size / 2 of a centre uniform in `box`, per axis, clamped to the box.
std::array<glm::dvec3, 3> small_triangle(PortableRandom& random, const Box& box, double size) {
  const glm::dvec3 centre = random.uniform(box);
  const Box around{centre - 0.5 * size, centre + 0.5 * size};
  std::array<glm::dvec3, 3> corners;
  for (auto& corner : corners) corner = glm::clamp(random.uniform(around), box.lower, box.upper);
  return corners;
}

void add_triangle(Mesh& mesh, const std::array<glm::dvec3, 3>& corners) {
  const auto first = static_cast<uint32_t>(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), corners.begin(), corners.end());
  mesh.triangles.push_back({first, first + 1, first + 2});
}

}  // namespace

Mesh make_uniform_soup(const SoupOptions& options) {
  PortableRandom random(options.seed);
  const double size = options.triangle_size > 0.0 ? options.triangle_size : default_triangle_size(options.box, options.triangles);
  Mesh mesh;
  mesh.positions.reserve(3 * options.triangles);
  mesh.triangles.reserve(options.triangles);
  for (size_t i = 0; i < options.triangles; ++i) add_triangle(mesh, small_triangle(random, options.box, size));
  return mesh;
}

Mesh make_clustered_soup(const SoupOptions& options, uint32_t clusters) {
  PortableRandom random(options.seed);
  clusters = std::max(clusters, 1u);
  const double side = largest_side(options.box) / 20.0;
  std::vector<Box> cubes;
  // Cluster cubes inside the box (where the box is thinner than a cube, clamped to it).
  const Box centres{glm::min(options.box.lower + 0.5 * side, 0.5 * (options.box.lower + options.box.upper)),
                    glm::max(options.box.upper - 0.5 * side, 0.5 * (options.box.lower + options.box.upper))};
  for (uint32_t c = 0; c < clusters; ++c) {
    const glm::dvec3 centre = random.uniform(centres);
    cubes.push_back({glm::max(centre - 0.5 * side, options.box.lower), glm::min(centre + 0.5 * side, options.box.upper)});
  }
  const size_t per_cluster = (options.triangles + clusters - 1) / clusters;
  const double size = options.triangle_size > 0.0 ? options.triangle_size : side / std::cbrt(double(std::max<size_t>(per_cluster, 1)));
  Mesh mesh;
  mesh.positions.reserve(3 * options.triangles);
  mesh.triangles.reserve(options.triangles);
  for (size_t i = 0; i < options.triangles; ++i) add_triangle(mesh, small_triangle(random, cubes[random.below(clusters)], size));
  return mesh;
}

Mesh make_degenerate_soup(const SoupOptions& options) {
  PortableRandom random(options.seed);
  const Box& box = options.box;
  const double size = options.triangle_size > 0.0 ? options.triangle_size : default_triangle_size(box, options.triangles);
  const glm::dvec3 centre = 0.5 * (box.lower + box.upper);
  const Box huge_box{centre + 20.0 * (box.lower - centre), centre + 20.0 * (box.upper - centre)};
  Mesh mesh;
  mesh.positions.reserve(3 * options.triangles);
  mesh.triangles.reserve(options.triangles);
  for (size_t i = 0; i < options.triangles; ++i) {
    const double kind = random.uniform();
    std::array<glm::dvec3, 3> v = small_triangle(random, box, size);
    const auto first = static_cast<uint32_t>(mesh.positions.size());
    if (kind < 0.40) {  // ordinary
    } else if (kind < 0.48) {  // repeated vertex index
      mesh.positions.insert(mesh.positions.end(), {v[0], v[1]});
      mesh.triangles.push_back({first, first, first + 1});
      continue;
    } else if (kind < 0.56) {  // repeated position under another index
      v[2] = v[0];
    } else if (kind < 0.64) {  // exactly collinear: the corners differ along one axis only
      const auto axis = static_cast<int>(random.below(3));
      v[1] = v[0], v[2] = v[0];
      v[1][axis] = std::min(v[0][axis] + 0.5 * size * random.uniform(), box.upper[axis]);
      v[2][axis] = std::max(v[0][axis] - 0.5 * size * random.uniform(), box.lower[axis]);
    } else if (kind < 0.68) {  // a point
      v[1] = v[0], v[2] = v[0];
    } else if (kind < 0.76) {  // collinear along a slanted line, up to rounding
      const glm::dvec3 d = v[1] - v[0];
      v[2] = glm::clamp(v[0] + random.uniform() * d, box.lower, box.upper);
    } else if (kind < 0.84) {  // a needle, 1e-6 of its length wide
      const glm::dvec3 d = v[1] - v[0];
      v[2] = glm::clamp(0.5 * (v[0] + v[1]) + 1e-6 * glm::length(d) * random.unit_vector(), box.lower, box.upper);
    } else if (kind < 0.92) {  // flat along an axis: lies on a face of its box
      const auto axis = static_cast<int>(random.below(3));
      v[1][axis] = v[0][axis], v[2][axis] = v[0][axis];
    } else if (kind < 0.96 && !mesh.triangles.empty()) {  // a copy of an earlier triangle, maybe rotated
      auto copy = mesh.triangles[random.below(mesh.triangles.size())];
      if (random.uniform() < 0.5) copy = {copy[1], copy[2], copy[0]};
      mesh.triangles.push_back(copy);
      continue;
    } else {  // huge
      for (auto& corner : v) corner = random.uniform(huge_box);
    }
    add_triangle(mesh, v);
  }
  return mesh;
}

std::vector<Sphere> make_sphere_field(size_t count, uint64_t seed, const Box& box) {
  PortableRandom random(seed);
  const glm::dvec3 extent = box.upper - box.lower;
  const double largest_radius = 0.5 * std::max({extent.x, extent.y, extent.z}) / std::cbrt(static_cast<double>(count));
  std::vector<Sphere> spheres(count);
  for (auto& sphere : spheres) {
    sphere.center = random.uniform(box);
    sphere.radius = largest_radius * std::pow(10.0, random.uniform(-2.0, 0.0));
  }
  return spheres;
}

}  // namespace vkray
