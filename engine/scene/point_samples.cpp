#include "engine/scene/point_samples.hpp"


#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace vkray {
namespace {

// Picks an index by weight: the cumulative weights, searched.
class WeightedPick {
 public:
  void add(double weight) { cumulative_.push_back(total() + weight); }
  double total() const { return cumulative_.empty() ? 0.0 : cumulative_.back(); }
  size_t pick(std::mt19937_64& random) const {
    const double at = std::uniform_real_distribution<double>(0.0, total())(random);
    return std::min<size_t>(std::upper_bound(cumulative_.begin(), cumulative_.end(), at) - cumulative_.begin(), cumulative_.size() - 1);
  }

 private:
  std::vector<double> cumulative_;
};

double triangle_area(const Mesh& mesh, size_t t) {
  const auto& i = mesh.triangles[t];
  return 0.5 * glm::length(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]], mesh.positions[i[2]] - mesh.positions[i[0]]));
}

// A point uniform on triangle t (the square root of Osada et al. 2002's sampling).
glm::dvec3 on_triangle(const Mesh& mesh, size_t t, std::mt19937_64& random) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double r1 = std::sqrt(unit(random)), r2 = unit(random);
  const auto& i = mesh.triangles[t];
  return (1.0 - r1) * mesh.positions[i[0]] + r1 * (1.0 - r2) * mesh.positions[i[1]] + r1 * r2 * mesh.positions[i[2]];
}

}  // namespace

Bounds sample_box(const Scene& scene, double scale) {
  const Bounds box = finite_bounds(scene);
  if (box.empty()) throw InputError("the scene has nothing finite to sample around (planes alone)");
  const glm::dvec3 centre = 0.5 * (box.lower + box.upper), half = 0.5 * scale * (box.upper - box.lower);
  return {centre - half, centre + half};
}

std::vector<glm::dvec3> uniform_points(const Bounds& box, size_t count, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<glm::dvec3> points(count);
  for (glm::dvec3& p : points) p = box.lower + glm::dvec3(unit(random), unit(random), unit(random)) * (box.upper - box.lower);
  return points;
}

std::vector<glm::dvec3> near_surface_points(const Scene& scene, size_t count, double sigma, uint64_t seed) {
  // The parts first (each mesh drawn where it is, each instance, the spheres), by world area; then a
  // triangle of the part's mesh by its own area. An instance's linear map L scales a triangle of
  // unit normal n by |cof(L) n| (cof(L) = det(L) L^-T), at most |cof(L)|_F: a triangle drawn by its
  // mesh's area is kept with probability |cof(L) n| / |cof(L)|_F (at least 1/sqrt 3 of the draws).
  std::vector<WeightedPick> by_mesh(scene.meshes.size());
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    for (size_t t = 0; t < scene.meshes[m].triangles.size(); ++t) by_mesh[m].add(triangle_area(scene.meshes[m], t));
  }
  struct Part {
    size_t mesh = 0;
    const Instance* instance = nullptr;  // none: the mesh where it is, or the spheres
    bool spheres = false;
  };
  std::vector<Part> parts;
  WeightedPick by_part;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (!scene.meshes[m].instanced && by_mesh[m].total() > 0.0) parts.push_back({m}), by_part.add(by_mesh[m].total());
  }
  for (const Instance& instance : scene.instances) {
    const Mesh& mesh = scene.meshes[instance.mesh];
    const glm::dmat3 cofactor = glm::determinant(instance.linear) * glm::transpose(glm::inverse(instance.linear));
    double area = 0.0;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& i = mesh.triangles[t];
      area += 0.5 * glm::length(cofactor * glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]], mesh.positions[i[2]] - mesh.positions[i[0]]));
    }
    if (area > 0.0) parts.push_back({instance.mesh, &instance}), by_part.add(area);
  }
  WeightedPick by_sphere;
  for (const Sphere& sphere : scene.spheres) by_sphere.add(4.0 * std::numbers::pi * sphere.radius * sphere.radius);
  if (by_sphere.total() > 0.0) parts.push_back({0, nullptr, true}), by_part.add(by_sphere.total());
  if (parts.empty()) throw InputError("the scene has no surface to sample points near (no triangle or sphere)");

  std::mt19937_64 random(seed);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<glm::dvec3> points;
  points.reserve(count);
  while (points.size() < count) {
    const Part& part = parts[by_part.pick(random)];
    glm::dvec3 on;
    if (part.spheres) {
      const Sphere& sphere = scene.spheres[by_sphere.pick(random)];
      const glm::dvec3 direction(gaussian(random), gaussian(random), gaussian(random));
      if (!(glm::length(direction) > 0.0)) continue;
      on = sphere.center + sphere.radius * glm::normalize(direction);
    } else {
      const Mesh& mesh = scene.meshes[part.mesh];
      const size_t t = by_mesh[part.mesh].pick(random);
      on = on_triangle(mesh, t, random);
      if (part.instance) {
        const glm::dmat3& linear = part.instance->linear;
        const glm::dmat3 cofactor = glm::determinant(linear) * glm::transpose(glm::inverse(linear));
        const auto& i = mesh.triangles[t];
        const glm::dvec3 normal = glm::normalize(glm::cross(mesh.positions[i[1]] - mesh.positions[i[0]], mesh.positions[i[2]] - mesh.positions[i[0]]));
        double frobenius = 0.0;
        for (int c = 0; c < 3; ++c) frobenius += glm::dot(cofactor[c], cofactor[c]);
        if (unit(random) * std::sqrt(frobenius) > glm::length(cofactor * normal)) continue;
        on = placed(*part.instance, on);
      }
    }
    points.push_back(on + sigma * glm::dvec3(gaussian(random), gaussian(random), gaussian(random)));
  }
  return points;
}

std::vector<glm::dvec3> grid_points(const Bounds& box, uint32_t n) {
  std::vector<glm::dvec3> points;
  points.reserve(size_t{n} * n * n);
  const glm::dvec3 cell = (box.upper - box.lower) / double(n);
  for (uint32_t x = 0; x < n; ++x) {
    for (uint32_t y = 0; y < n; ++y) {
      for (uint32_t z = 0; z < n; ++z) points.push_back(box.lower + (glm::dvec3(x, y, z) + 0.5) * cell);
    }
  }
  return points;
}

}  // namespace vkray
