// Points to query, as signed-distance and occupancy datasets draw them (DeepSDF, Park et al. 2019;
// occupancy networks, Mescheder et al. 2019): uniform in a box around the model, and near its
// surface (points on it, area-weighted, moved by a Gaussian of a given sigma). `vkray points` and
// `vkray bench --suite points` take them; deterministic for a seed, on every platform.
#pragma once

#include "engine/scene/scene.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace vkray {

// The box of finite_bounds(scene) grown about its centre by `scale` (1.2: a tenth of its size on
// each side). Throws InputError for a scene with nothing finite in it.
Bounds sample_box(const Scene& scene, double scale);

// `count` points uniform in `box`.
std::vector<glm::dvec3> uniform_points(const Bounds& box, size_t count, uint64_t seed);

// `count` points on the scene's triangles and spheres, each primitive as likely as its area (planes,
// being infinite, left out), each moved by a Gaussian of standard deviation `sigma` on every axis
// (0: on the surface). Throws InputError for a scene without triangles or spheres.
std::vector<glm::dvec3> near_surface_points(const Scene& scene, size_t count, double sigma, uint64_t seed);

// A grid of n x n x n points at the centres of the cells of `box` cut n times along each axis, in the
// C order of an array indexed [x][y][z] (z fastest: numpy's meshgrid(..., indexing="ij"), the order
// marching cubes and volume tools read).
std::vector<glm::dvec3> grid_points(const Bounds& box, uint32_t n);

}  // namespace vkray
