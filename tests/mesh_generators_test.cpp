// The generated meshes are what they claim: the sphere is closed and outward-facing at every size,
// the soups stay in their box with the promised mix of hard cases, and the same arguments give the
// same bits (the random mapping is our own, not the standard library's).
#include "engine/scene/mesh_generators.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <utility>

namespace vkray {
namespace {

bool zero_area(const Mesh& mesh, const std::array<uint32_t, 3>& t) {
  const glm::dvec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
  return glm::cross(b - a, c - a) == glm::dvec3(0.0);
}

bool same_bits(const Mesh& a, const Mesh& b) {
  return a.positions.size() == b.positions.size() && a.triangles == b.triangles &&
         std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(glm::dvec3)) == 0;
}

bool inside(const Box& box, const glm::dvec3& p) {
  return glm::all(glm::greaterThanEqual(p, box.lower)) && glm::all(glm::lessThanEqual(p, box.upper));
}

// The mapping to [0, 1) is ours: if it were swapped for std::uniform_real_distribution (which
// differs between standard libraries) or changed, every generated mesh would change. mt19937_64
// itself is pinned by the standard (its 10000th output from the default seed).
TEST(PortableRandom, FixedValues) {
  std::mt19937_64 engine;
  engine.discard(9999);
  EXPECT_EQ(engine(), 9981545732273789042ull);
  PortableRandom random(42);
  std::mt19937_64 same(42);
  EXPECT_EQ(random.uniform(), double(same() >> 11) * 0x1p-53);
  EXPECT_EQ(random.uniform(2.0, 4.0), 2.0 + 2.0 * (double(same() >> 11) * 0x1p-53));
  for (int i = 0; i < 10000; ++i) {
    const double u = random.uniform();
    ASSERT_TRUE(u >= 0.0 && u < 1.0) << u;
    ASSERT_LT(random.below(3), 3u);
  }
  const glm::dvec3 v = random.unit_vector();
  EXPECT_NEAR(glm::length(v), 1.0, 1e-15);
}

TEST(SphereMesh, FrequencyGivesTheNearestTriangleCount) {
  EXPECT_EQ(sphere_mesh_frequency(0), 1u);
  EXPECT_EQ(sphere_mesh_frequency(20), 1u);
  EXPECT_EQ(sphere_mesh_frequency(49), 1u);   // 20 is nearer than 80
  EXPECT_EQ(sphere_mesh_frequency(51), 2u);
  EXPECT_EQ(sphere_mesh_frequency(1000), 7u);  // 980
  EXPECT_EQ(sphere_mesh_frequency(1'000'000), 224u);  // 1,003,520
  EXPECT_EQ(sphere_mesh_frequency(4'000'000), 447u);  // 3,996,180
}

// Closed and consistently outward: every directed edge appears exactly once and its reverse exactly
// once (so each edge joins two triangles through the same vertex indices), V - E + F = 2, no vertex
// is unused, every vertex is on the sphere and every triangle faces away from the centre.
TEST(SphereMesh, ClosedOutwardAndOnTheSphere) {
  const glm::dvec3 center(1.5, -2.0, 0.25);
  const double radius = 3.0;
  for (size_t approx : {size_t{20}, size_t{80}, size_t{1000}, size_t{5000}}) {
    SCOPED_TRACE(approx);
    const Mesh mesh = make_sphere_mesh(approx, center, radius);
    const uint32_t f = sphere_mesh_frequency(approx);
    ASSERT_EQ(mesh.triangles.size(), 20u * f * f);
    ASSERT_EQ(mesh.positions.size(), 10u * f * f + 2);
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    std::vector<int> uses(mesh.positions.size(), 0);
    for (const auto& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_LT(t[k], mesh.positions.size());
        ++uses[t[k]];
        ++directed[{t[k], t[(k + 1) % 3]}];
      }
      const glm::dvec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
      ASSERT_GT(glm::dot(glm::cross(b - a, c - a), (a + b + c) / 3.0 - center), 0.0) << "inward or degenerate";
    }
    for (const auto& [edge, count] : directed) {
      ASSERT_EQ(count, 1) << edge.first << "->" << edge.second;
      ASSERT_EQ(directed.count({edge.second, edge.first}), 1u) << "open edge " << edge.first << "-" << edge.second;
    }
    const size_t edges = directed.size() / 2;
    EXPECT_EQ(mesh.positions.size() + mesh.triangles.size(), edges + 2);
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      ASSERT_GT(uses[v], 0) << v;
      ASSERT_NEAR(glm::length(mesh.positions[v] - center), radius, 1e-14 * radius);
    }
  }
}

TEST(SphereMesh, Deterministic) { EXPECT_TRUE(same_bits(make_sphere_mesh(3000), make_sphere_mesh(3000))); }

TEST(Soups, UniformStaysInItsBoxAndDependsOnTheSeed) {
  SoupOptions options;
  options.triangles = 5000;
  options.box = {{-3, 1, 10}, {5, 2, 11}};
  options.seed = 7;
  const Mesh mesh = make_uniform_soup(options);
  ASSERT_EQ(mesh.triangles.size(), 5000u);
  for (const auto& p : mesh.positions) ASSERT_TRUE(inside(options.box, p));
  EXPECT_TRUE(same_bits(mesh, make_uniform_soup(options)));
  options.seed = 8;
  EXPECT_FALSE(same_bits(mesh, make_uniform_soup(options)));
  // Uniform: every eighth of the box holds about an eighth of the triangle centres.
  std::map<int, int> octants;
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 c = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
    const glm::dvec3 mid = 0.5 * (options.box.lower + options.box.upper);
    ++octants[(c.x > mid.x) + 2 * (c.y > mid.y) + 4 * (c.z > mid.z)];
  }
  ASSERT_EQ(octants.size(), 8u);
  for (const auto& [octant, count] : octants) EXPECT_NEAR(count, 5000 / 8, 120) << octant;
}

// Clustered: the triangles occupy only a few small cells of the box.
TEST(Soups, ClusteredIsDense) {
  SoupOptions options;
  options.triangles = 4000;
  const Mesh mesh = make_clustered_soup(options, 3);
  ASSERT_EQ(mesh.triangles.size(), 4000u);
  std::set<std::array<int, 3>> cells;  // a 20^3 grid over the box
  for (const auto& p : mesh.positions) {
    ASSERT_TRUE(inside(options.box, p));
    const glm::dvec3 cell = glm::floor((p - options.box.lower) / (options.box.upper - options.box.lower) * 20.0);
    cells.insert({int(cell.x), int(cell.y), int(cell.z)});
  }
  EXPECT_LE(cells.size(), 3u * 8u);
  EXPECT_TRUE(same_bits(mesh, make_clustered_soup(options, 3)));
}

// The hard cases are all there, in about the documented shares.
TEST(Soups, DegenerateMixesTheHardCases) {
  SoupOptions options;
  options.triangles = 4000;
  const Mesh mesh = make_degenerate_soup(options);
  ASSERT_EQ(mesh.triangles.size(), 4000u);
  size_t zero = 0, repeated_index = 0, huge = 0, axis_flat = 0, copies = 0;
  std::set<std::array<uint32_t, 3>> seen;
  for (const auto& t : mesh.triangles) {
    for (uint32_t v : t) ASSERT_LT(v, mesh.positions.size());
    zero += zero_area(mesh, t);
    repeated_index += t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    const Box bigger{1.5 * options.box.lower, 1.5 * options.box.upper};  // the box is centred on 0
    bool outside = false;
    for (uint32_t v : t) outside |= !inside(bigger, mesh.positions[v]);
    huge += outside;
    for (uint32_t v : t) ASSERT_TRUE(outside || inside(options.box, mesh.positions[v]));
    bool flat = false;
    for (int axis = 0; axis < 3; ++axis) {
      flat |= mesh.positions[t[0]][axis] == mesh.positions[t[1]][axis] && mesh.positions[t[1]][axis] == mesh.positions[t[2]][axis];
    }
    axis_flat += flat && !zero_area(mesh, t);
    std::array<uint32_t, 3> key = t;
    std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
    copies += !seen.insert(key).second;
  }
  EXPECT_NEAR(double(zero) / 4000, 0.28, 0.04);  // repeated index, repeated position, collinear, points
  EXPECT_NEAR(double(repeated_index) / 4000, 0.08, 0.02);
  EXPECT_NEAR(double(huge) / 4000, 0.04, 0.015);
  EXPECT_NEAR(double(axis_flat) / 4000, 0.08, 0.02);
  EXPECT_NEAR(double(copies) / 4000, 0.04, 0.015);
  EXPECT_TRUE(same_bits(mesh, make_degenerate_soup(options)));
}

}  // namespace
}  // namespace vkray
