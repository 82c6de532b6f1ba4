// Deterministic generated meshes for tests and benchmarks (`vkray bench --suite scaling`): a closed
// sphere of any size and random triangle soups. The same arguments give the same mesh, bit for bit,
// on every platform: randomness comes from std::mt19937_64 with an explicit seed, mapped to [0, 1)
// by our own code (std::uniform_real_distribution differs between standard libraries).
#pragma once

#include "engine/scene/bvh.hpp"
#include "engine/scene/scene.hpp"

#include <cstddef>
#include <cstdint>
#include <random>

namespace vkray {

// Uniform doubles from a 64-bit Mersenne Twister, identical on every standard library.
class PortableRandom {
 public:
  explicit PortableRandom(uint64_t seed) : engine_(seed) {}
  // The top 53 bits of one 64-bit draw: a multiple of 2^-53 in [0, 1).
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1p-53; }
  double uniform(double lower, double upper) { return lower + (upper - lower) * uniform(); }
  // A point uniform in the box (upper excluded).
  glm::dvec3 uniform(const Box& box) {
    const double x = uniform(box.lower.x, box.upper.x);
    const double y = uniform(box.lower.y, box.upper.y);
    return {x, y, uniform(box.lower.z, box.upper.z)};
  }
  // An integer uniform in [0, count), 1 <= count <= 2^53.
  uint64_t below(uint64_t count) {
    const auto value = static_cast<uint64_t>(uniform() * static_cast<double>(count));
    return value < count ? value : count - 1;
  }
  // A unit vector uniform on the sphere (rejection from the cube).
  glm::dvec3 unit_vector();

 private:
  std::mt19937_64 engine_;
};

// A closed, watertight sphere: a geodesic sphere (an icosahedron whose faces are cut into f x f
// triangles, vertices pushed onto the sphere) with 20 f^2 triangles, f chosen so that is as close to
// `approx_triangles` as it gets (at least 20). Every edge is shared by exactly two triangles through
// the same vertex indices; triangles wind counter-clockwise seen from outside.
Mesh make_sphere_mesh(size_t approx_triangles, const glm::dvec3& center = glm::dvec3(0.0), double radius = 1.0);
// The frequency f make_sphere_mesh uses for `approx_triangles`.
uint32_t sphere_mesh_frequency(size_t approx_triangles);

// Soups: `triangles` independent triangles (three vertices of their own), inside `box` unless said
// otherwise. `triangle_size` is the largest extent of a triangle along each axis; 0 picks the box's
// largest side / cbrt(triangles), so a soup of any size looks about equally dense along a ray.
struct SoupOptions {
  size_t triangles = 1000;
  uint64_t seed = 1;
  Box box{glm::dvec3(-1.0), glm::dvec3(1.0)};
  double triangle_size = 0.0;
};

// Centres uniform in the box, each vertex uniform within triangle_size / 2 of its centre per axis
// (clamped to the box).
Mesh make_uniform_soup(const SoupOptions& options);

// `clusters` dense clusters with centres uniform in the box, each a cube of side a twentieth of the
// box's largest side holding about as many triangles as the others, sized as a uniform soup of the
// cluster's own cube (so far denser than the box around it).
Mesh make_clustered_soup(const SoupOptions& options, uint32_t clusters = 4);

// A uniform soup with hard cases mixed in, in fixed proportions (per triangle, by chance):
// ~40% ordinary; zero-area ones (~8% repeated vertex index, ~8% repeated position under another
// index, ~8% exactly collinear along an axis, ~4% all three corners one point); ~8% collinear along a
// slanted line (zero area up to rounding); ~8% needles (1e-6 wide); ~8% axis-aligned flat triangles
// (lying on a face of their own box); ~4% exact copies of an earlier triangle under a new index;
// ~4% huge triangles, corners anywhere in the box scaled 20 times about its centre.
Mesh make_degenerate_soup(const SoupOptions& options);

// `count` spheres with centres uniform in `box` and radii log-uniform over two decades below the
// box's largest side / cbrt(count) / 2, so fields of any size are about equally dense along a ray.
std::vector<Sphere> make_sphere_field(size_t count, uint64_t seed, const Box& box = {glm::dvec3(-1.0), glm::dvec3(1.0)});

}  // namespace vkray
