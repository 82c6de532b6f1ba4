// OBJ loader: polygon triangulation, index forms, merging of groups, and one-line InputErrors that
// name the file and the line for every malformed input.
#include "tests/input_error_test.hpp"
#include "tests/temp_dir_test.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/polygon_triangulation.hpp"
#include "engine/scene/text_lines.hpp"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>
#include <array>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace {

using vkray::test::error_of;
using vkray::test::expect_error;

using vkray::InputError;
using vkray::Mesh;

std::string text_error(const std::string& text, const std::string& name = "t.obj") {
  return error_of([&] { vkray::load_obj_text(text, name); });
}

// Every error is one line that starts with the file name.
double triangle_area(const Mesh& mesh, const std::array<uint32_t, 3>& t) {
  return 0.5 * glm::length(glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
}

double total_area(const Mesh& mesh) {
  double area = 0.0;
  for (const auto& t : mesh.triangles) area += triangle_area(mesh, t);
  return area;
}

void expect_valid_triangles(const Mesh& mesh) {
  for (const auto& t : mesh.triangles) {
    for (uint32_t index : t) EXPECT_LT(index, mesh.positions.size());
    EXPECT_NE(t[0], t[1]);
    EXPECT_NE(t[1], t[2]);
    EXPECT_NE(t[0], t[2]);
  }
}

const std::string tri_vertices = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

class ObjFileTest : public vkray::test::TempDirTest {};

TEST(ObjText, SingleTriangle) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "f 1 2 3\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[1], glm::dvec3(1, 0, 0));
  EXPECT_EQ(mesh.positions[2], glm::dvec3(0, 1, 0));
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
}

TEST(ObjText, CoordinatesKeepFullPrecision) {
  const Mesh mesh = vkray::load_obj_text("v 0.1 -2.5e3 1234567.125\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[0], glm::dvec3(0.1, -2.5e3, 1234567.125));
}

TEST(ObjText, QuadBecomesTwoTriangles) {
  const Mesh mesh = vkray::load_obj_text("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nf 1 2 3 4\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 4u);
  ASSERT_EQ(mesh.triangles.size(), 2u);
  expect_valid_triangles(mesh);
  std::set<uint32_t> used;
  for (const auto& t : mesh.triangles) used.insert(t.begin(), t.end());
  EXPECT_EQ(used, (std::set<uint32_t>{0, 1, 2, 3}));
  EXPECT_NEAR(total_area(mesh), 2.0, 1e-12);
}

TEST(ObjText, PentagonBecomesThreeTriangles) {
  // A convex pentagon in the z = 1 plane: a 2x2 square with a roof of height 1 (area 4 + 1).
  const Mesh mesh = vkray::load_obj_text("v 0 0 1\nv 2 0 1\nv 2 2 1\nv 1 3 1\nv 0 2 1\nf 1 2 3 4 5\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 5u);
  ASSERT_EQ(mesh.triangles.size(), 3u);
  expect_valid_triangles(mesh);
  EXPECT_NEAR(total_area(mesh), 5.0, 1e-12);
}

TEST(ObjText, HexagonBecomesFourTriangles) {
  const Mesh mesh = vkray::load_obj_text("v 1 0 0\nv 2 0 0\nv 3 1 0\nv 2 2 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5 6\n", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 4u);
  expect_valid_triangles(mesh);
  EXPECT_NEAR(total_area(mesh), 4.0, 1e-12);
}

// A polygon given by its corners in the z = 0 plane, as an OBJ face; `tilt` turns it out of that plane.
std::string polygon_obj(const std::vector<glm::dvec2>& corners, const glm::dmat3& tilt = glm::dmat3(1.0)) {
  std::string text;
  for (const glm::dvec2 corner : corners) {
    const glm::dvec3 p = tilt * glm::dvec3(corner, 0.0);
    text += "v " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
  }
  text += "f";
  for (size_t k = 1; k <= corners.size(); ++k) text += " " + std::to_string(k);
  return text + "\n";
}

// Twice a polygon's signed area (shoelace formula): positive where its corners run counter-clockwise.
double signed_area(const std::vector<glm::dvec2>& corners) {
  double twice = 0.0;
  for (size_t k = 0; k < corners.size(); ++k) {
    const glm::dvec2 a = corners[k], b = corners[(k + 1) % corners.size()];
    twice += a.x * b.y - b.x * a.y;
  }
  return 0.5 * twice;
}

// A simple polygon is cut exactly when its n - 2 triangles all face the polygon's way and their areas
// add up to its area: a triangle reaching outside, or two overlapping, would make the sum larger.
void expect_exact_triangulation(const std::vector<glm::dvec2>& corners, const glm::dmat3& tilt = glm::dmat3(1.0)) {
  const Mesh mesh = vkray::load_obj_text(polygon_obj(corners, tilt), "t.obj");
  ASSERT_EQ(mesh.triangles.size(), corners.size() - 2);
  expect_valid_triangles(mesh);
  const glm::dvec3 facing = tilt * glm::dvec3(0, 0, signed_area(corners) > 0.0 ? 1.0 : -1.0);
  for (const auto& t : mesh.triangles) {
    const glm::dvec3 normal = glm::cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]);
    EXPECT_GE(glm::dot(normal, facing), 0.0) << "a triangle faces away from the polygon";
  }
  const double area = std::abs(signed_area(corners));
  EXPECT_NEAR(total_area(mesh), area, 1e-5 * area);  // the corners went through 6-digit text
}

std::vector<glm::dvec2> star(size_t points) {
  std::vector<glm::dvec2> corners;
  for (size_t k = 0; k < 2 * points; ++k) {
    const double angle = 6.283185307179586 * static_cast<double>(k) / static_cast<double>(2 * points);
    corners.push_back((k % 2 == 0 ? 1.0 : 0.6) * glm::dvec2(std::cos(angle), std::sin(angle)));
  }
  return corners;
}

// A comb: 20 teeth on a bar. tinyobjloader's ear clipping (which vkray used before) filled the gaps
// between the teeth: 184.5 square units for a polygon of 148.5.
std::vector<glm::dvec2> comb() {
  std::vector<glm::dvec2> corners{{0, -1}};
  for (int k = 0; k < 20; ++k) {
    for (const glm::dvec2 corner : {glm::dvec2(2 * k, 0), glm::dvec2(2 * k, 5), glm::dvec2(2 * k + 1, 5), glm::dvec2(2 * k + 1, 1)}) {
      corners.push_back(corner);
    }
  }
  corners.emplace_back(39, -1);
  return corners;
}

TEST(ObjText, ConcavePolygonsAreCutExactlyEitherWayRound) {
  const std::vector<glm::dvec2> l_shape{{10, 10}, {12, 10}, {12, 11}, {11, 11}, {11, 12}, {10, 12}};
  const glm::dmat3 tilt = glm::dmat3(glm::dvec3(0.36, 0.48, -0.8), glm::dvec3(-0.8, 0.6, 0.0), glm::dvec3(0.48, 0.64, 0.6));
  for (const auto& corners : {l_shape, star(8), star(300), comb()}) {
    for (const bool reversed : {false, true}) {
      SCOPED_TRACE(std::to_string(corners.size()) + " corners" + (reversed ? ", clockwise" : ""));
      const std::vector<glm::dvec2> ordered = reversed ? std::vector<glm::dvec2>(corners.rbegin(), corners.rend()) : corners;
      expect_exact_triangulation(ordered);
      expect_exact_triangulation(ordered, tilt);
    }
  }
}

// A square with a square hole, joined to it by a doubled edge (how n-gons with holes are written):
// the hole's corners sit at the same places twice.
TEST(ObjText, PolygonWithAHoleJoinedByADoubledEdge) {
  expect_exact_triangulation({{0, 0}, {4, 0}, {4, 4}, {0, 4}, {0, 0}, {1, 1}, {1, 3}, {3, 3}, {3, 1}, {1, 1}});
}

// Collinear corners (a rectangle with extra corners along its sides) are used, with no sliver left out.
TEST(ObjText, CollinearCornersAreKept) {
  expect_exact_triangulation({{0, 0}, {1, 0}, {2, 0}, {3, 0}, {3, 1}, {2, 1}, {1, 1}, {0, 1}});
}

// A bow tie crosses itself: no triangulation is right, but every corner is used and none is lost.
TEST(ObjText, SelfIntersectingPolygonStillGivesEveryTriangle) {
  const Mesh mesh = vkray::load_obj_text(polygon_obj({{0, 0}, {2, 2}, {2, 0}, {0, 2}, {-1, 1}}), "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 3u);
  expect_valid_triangles(mesh);
}

TEST(ObjText, PolygonsUpToTheLimitAreTriangulatedAndLargerOnesRefused) {
  expect_exact_triangulation(star(vkray::max_polygon_corners / 2));
  const std::string too_large = polygon_obj(star(vkray::max_polygon_corners / 2 + 1));
  expect_error(text_error("# a large star\n" + too_large), "t.obj:" + std::to_string(vkray::max_polygon_corners + 4) + ": ",
               "a face of 4098 vertices; vkray takes at most 4096");
}

// The ear tests' work, in corner tests, stays within a small multiple of the corners on the shapes
// that made ear clipping quadratic: a comb of 4096 corners (its teeth along x, then along y: each
// tooth's triangle once read every reflex corner, 1280 tests a corner, 60 ms a face) and a star.
TEST(ObjText, EarClippingWorkStaysNearLinearOnCombsAndStars) {
  std::vector<glm::dvec2> teeth{{0, -1}};
  for (int k = 0; k < 1023; ++k) {
    for (const glm::dvec2 corner : {glm::dvec2(2 * k, 0), glm::dvec2(2 * k, 10), glm::dvec2(2 * k + 1, 10), glm::dvec2(2 * k + 1, 0)}) {
      teeth.push_back(corner);
    }
  }
  teeth.emplace_back(2045, -1);
  std::vector<glm::dvec2> turned;
  for (const glm::dvec2 corner : teeth) turned.emplace_back(-corner.y, corner.x);
  for (const auto& corners : {teeth, turned, star(vkray::max_polygon_corners / 2)}) {
    for (const bool reversed : {false, true}) {
      std::vector<glm::dvec3> polygon;
      for (const glm::dvec2 corner : corners) polygon.emplace_back(corner, 0.0);
      if (reversed) std::reverse(polygon.begin(), polygon.end());
      std::vector<std::array<uint32_t, 3>> triangles;
      const size_t work = vkray::triangulate_polygon(polygon, triangles);
      EXPECT_EQ(triangles.size(), polygon.size() - 2);
      EXPECT_LE(work, 64 * polygon.size()) << polygon.size() << " corners" << (reversed ? ", clockwise" : "");
    }
  }
}

// A quad whose corners are not in one plane is two different surfaces depending on the diagonal:
// vkray takes the one from its first corner, as Blender's importers and trimesh do, whichever is
// shorter (tinyobjloader, which vkray used before, took the shorter: here 2-4).
TEST(ObjText, ANonPlanarQuadIsCutAlongTheDiagonalFromItsFirstCorner) {
  for (const char* lift : {"0.5", "-0.5"}) {
    const Mesh mesh = vkray::load_obj_text(std::string("v 0 0 0\nv 1 0 0\nv 1.5 1.5 ") + lift + "\nv 0 1 0\nf 1 2 3 4\n", "t.obj");
    ASSERT_EQ(mesh.triangles.size(), 2u);
    for (const auto& triangle : mesh.triangles) {  // both hold the diagonal 1-3 (0 and 2 here)
      EXPECT_TRUE(std::ranges::count(triangle, 0u) == 1 && std::ranges::count(triangle, 2u) == 1) << lift;
    }
  }
}

TEST(ObjText, NegativeIndicesCountBackFromTheNewestVertex) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "f -3 -2 -1\nv 1 1 0\nf -3 -2 -1\nf -1 1 -3\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 4u);
  ASSERT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (std::array<uint32_t, 3>{1, 2, 3}));
  EXPECT_EQ(mesh.triangles[2], (std::array<uint32_t, 3>{3, 0, 1}));
}

TEST(ObjText, VertexTexcoordNormalReferences) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
}

// vn and vt are kept, with each triangle's corners' indices into them, for triangles and polygons
// alike; faces without them (before the first that gives them and after) get no_attribute.
TEST(ObjText, NormalsAndTexcoordsByCorner) {
  constexpr uint32_t none = vkray::no_attribute;
  const std::string attributes = "vt 0 0\nvt 1 0\nvt 0.25 1\nvn 0 0 1\nvn 0 1 0\n";
  for (const std::string& extra : {std::string(), std::string("v 1 1 0\nf 1 2 4 3\n")}) {
    SCOPED_TRACE(extra.empty() ? "triangles only" : "with a quad");
    const Mesh mesh = vkray::load_obj_text(tri_vertices + attributes + "f 1 2 3\nf 1/1/2 2/2/1 3/3/2\nf 3//1 1//2 2//1\n" +
                                               "f 2/3 3/2 1/1\n" + extra, "t.obj");
    ASSERT_EQ(mesh.normals.size(), 2u);
    EXPECT_EQ(mesh.normals[1], glm::dvec3(0, 1, 0));
    ASSERT_EQ(mesh.texcoords.size(), 3u);
    EXPECT_EQ(mesh.texcoords[2], glm::dvec2(0.25, 1));
    ASSERT_EQ(mesh.normal_corners.size(), mesh.triangles.size());
    ASSERT_EQ(mesh.texcoord_corners.size(), mesh.triangles.size());
    using Corners = std::array<uint32_t, 3>;
    EXPECT_EQ(mesh.normal_corners[0], (Corners{none, none, none}));
    EXPECT_EQ(mesh.normal_corners[1], (Corners{1, 0, 1}));
    EXPECT_EQ(mesh.texcoord_corners[1], (Corners{0, 1, 2}));
    EXPECT_EQ(mesh.normal_corners[2], (Corners{0, 1, 0}));
    EXPECT_EQ(mesh.texcoord_corners[2], (Corners{none, none, none}));
    EXPECT_EQ(mesh.texcoord_corners[3], (Corners{2, 1, 0}));
    EXPECT_EQ(mesh.normal_corners[3], (Corners{none, none, none}));
    for (size_t t = 4; t < mesh.triangles.size(); ++t) EXPECT_EQ(mesh.normal_corners[t], (Corners{none, none, none}));
  }
  // A file without any keeps no lists.
  const Mesh plain = vkray::load_obj_text(tri_vertices + "vn 0 0 1\nf 1 2 3\n", "t.obj");
  EXPECT_TRUE(plain.normal_corners.empty());
  EXPECT_TRUE(plain.texcoord_corners.empty());
}

TEST(ObjText, VertexNormalReferences) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "vn 0 0 1\nf 3//1 1//1 2//1\n", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{2, 0, 1}));
}

TEST(ObjText, VertexTexcoordReferences) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "vt 0 0\nvt 1 0\nf 2/1 3/2 1/-1\n", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{1, 2, 0}));
}

TEST(ObjText, GroupsAndObjectsMergeIntoOneMesh) {
  const std::string text =
      "o first\n" + tri_vertices + "f 1 2 3\n"
      "g part\nusemtl red\ns 1\nv 1 1 0\nf 2 4 3\n"
      "o second\ng a b\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf -3 -2 -1\n";
  const Mesh mesh = vkray::load_obj_text(text, "t.obj");
  ASSERT_EQ(mesh.positions.size(), 7u);
  EXPECT_EQ(mesh.positions[6], glm::dvec3(5, 6, 5));
  ASSERT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (std::array<uint32_t, 3>{1, 3, 2}));
  EXPECT_EQ(mesh.triangles[2], (std::array<uint32_t, 3>{4, 5, 6}));
}

TEST(ObjText, ExtraVertexComponentsAreIgnored) {
  // "v x y z w" and the common "v x y z r g b" vertex colours.
  const Mesh mesh = vkray::load_obj_text("v 1 2 3 0.5\nv 4 5 6 1 0 0\nv 7 8 9 0 1 0\nf 1 2 3\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[0], glm::dvec3(1, 2, 3));
  EXPECT_EQ(mesh.positions[1], glm::dvec3(4, 5, 6));
  EXPECT_EQ(mesh.positions[2], glm::dvec3(7, 8, 9));
}

TEST(ObjText, LeadingPlusSign) {
  const Mesh mesh = vkray::load_obj_text("v +0.5 0 +2\nv 1 0 0\nv 0 1 0\nf +1 2 3\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[0], glm::dvec3(0.5, 0, 2));
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
  expect_error(text_error("v +-1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "t.obj:1: ", "'+-1' is not a number");
}

TEST(ObjText, CommentsAndBlankLines) {
  const std::string text = "# header\n\n   \n\t\nv 0 0 0 # origin\n# v 9 9 9\nv 1 0 0\n\nv 0 1 0\n#\nf 1 2 3\n\n";
  const Mesh mesh = vkray::load_obj_text(text, "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
}

TEST(ObjText, CommentAfterFaceOnSameLine) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "f 1 2 3 # the only face\n", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
}

TEST(ObjText, CommentAfterStatementsWithCrlf) {
  const Mesh mesh = vkray::load_obj_text("v 0 0 0 #a\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3 #b\r\nf 3 2 1#c", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[1], (std::array<uint32_t, 3>{2, 1, 0}));
}

TEST(ObjText, CrlfLineEndings) {
  const Mesh mesh = vkray::load_obj_text("v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nf 1 2 3 4\r\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.positions[2], glm::dvec3(1, 1, 0));
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_NEAR(total_area(mesh), 1.0, 1e-12);
}

TEST(ObjText, AByteOrderMarkIsNotPartOfTheFirstLine) {
  const Mesh mesh = vkray::load_obj_text("\xEF\xBB\xBFv 0 0 7\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj");
  ASSERT_EQ(mesh.positions.size(), 3u);
  EXPECT_EQ(mesh.positions[0], glm::dvec3(0, 0, 7));
}

TEST(ObjText, TabsBetweenTokens) {
  const Mesh mesh = vkray::load_obj_text("v\t0\t0\t0\nv 1  0 0\nv  0 1 0\nf\t1\t2  3\n", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.positions[1], glm::dvec3(1, 0, 0));
}

TEST(ObjText, LastLineCompleteWithoutTrailingNewlineLoads) {
  const Mesh mesh = vkray::load_obj_text(tri_vertices + "f 1 2 3", "t.obj");
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_EQ(mesh.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
}

TEST(ObjErrors, VertexWithTwoCoordinates) {
  expect_error(text_error("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n"), "t.obj:2: ", "'v' needs 3 coordinates, got 2");
}

TEST(ObjErrors, VertexWithNan) {
  expect_error(text_error("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n"), "t.obj:3: ", "'nan' is not finite");
}

TEST(ObjErrors, VertexWithInf) {
  expect_error(text_error("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n"), "t.obj:2: ", "'inf' is not finite");
  expect_error(text_error("v 0 0 0\nv 1 0 0\nv 0 1 -infinity\nf 1 2 3\n"), "t.obj:3: ", "'-infinity' is not finite");
}

TEST(ObjErrors, VertexWithOverflowingNumber) {
  expect_error(text_error("v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n"), "t.obj:2: ", "1e999");
}

TEST(ObjErrors, VertexWithGarbage) {
  expect_error(text_error("v 0 0 0\nv 1 0 zero\nv 0 1 0\nf 1 2 3\n"), "t.obj:2: ", "'zero' is not a number");
}

TEST(ObjErrors, NormalWithTwoCoordinates) {
  expect_error(text_error(tri_vertices + "vn 0 1\nf 1//1 2//1 3//1\n"), "t.obj:4: ", "'vn' needs 3 coordinates, got 2");
}

TEST(ObjErrors, FaceIndexZero) {
  expect_error(text_error(tri_vertices + "f 0 1 2\n"), "t.obj:4: ", "vertex index 0 (OBJ indices start at 1)");
}

TEST(ObjErrors, FaceIndexOutOfRange) {
  expect_error(text_error(tri_vertices + "f 1 2 4\n"), "t.obj:4: ", "vertex index 4 is out of range (3 defined so far)");
}

TEST(ObjErrors, FaceIndexRefersToVertexDefinedLater) {
  expect_error(text_error("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n"), "t.obj:3: ", "vertex index 3 is out of range (2 defined so far)");
}

TEST(ObjErrors, NegativeFaceIndexOutOfRange) {
  expect_error(text_error(tri_vertices + "f -1 -2 -4\n"), "t.obj:4: ", "vertex index -4 is out of range (3 defined so far)");
}

TEST(ObjErrors, HugeNegativeFaceIndex) {
  // The most negative 64-bit integer: negating it overflows, so a check written as -index > n
  // would let it through.
  expect_error(text_error(tri_vertices + "f 1 2 -9223372036854775808\n"), "t.obj:4: ", "is out of range (3 defined so far)");
  expect_error(text_error(tri_vertices + "f 1 2 99999999999999999999\n"), "t.obj:4: ", "is not an integer vertex index");
}

TEST(ObjErrors, TexcoordAndNormalIndexOutOfRange) {
  expect_error(text_error(tri_vertices + "vt 0 0\nf 1/1 2/2 3/1\n"), "t.obj:5: ", "texture index 2 is out of range (1 defined so far)");
  expect_error(text_error(tri_vertices + "vn 0 0 1\nf 1//1 2//1 3//0\n"), "t.obj:5: ", "normal index 0 (OBJ indices start at 1)");
}

TEST(ObjErrors, FaceWithTwoVertices) {
  expect_error(text_error(tri_vertices + "f 1 2\n"), "t.obj:4: ", "a face needs at least 3 vertices, got 2");
}

TEST(ObjErrors, MixedReferenceFormsInOneFace) {
  expect_error(text_error(tri_vertices + "vt 0 0\nvn 0 0 1\nf 1/1/1 2//1 3/1/1\n"), "t.obj:6: ",
               "face vertex '2//1' has a different form than '1/1/1'");
  expect_error(text_error(tri_vertices + "vt 0 0\nf 1 2/1 3\n"), "t.obj:5: ", "face vertex '2/1' has a different form than '1'");
}

TEST(ObjErrors, MalformedFaceVertex) {
  expect_error(text_error(tri_vertices + "f 1 2 3/\n"), "t.obj:4: ", "malformed face vertex '3/'");
  expect_error(text_error(tri_vertices + "f 1 2 x\n"), "t.obj:4: ", "'x' is not an integer vertex index");
}

TEST(ObjErrors, FileCutOffMidLine) {
  const std::string message = text_error(tri_vertices + "f 1 2 3\nf 3 2");
  expect_error(message, "t.obj:5: ", "a face needs at least 3 vertices, got 2");
  EXPECT_NE(message.find("cut off"), std::string::npos) << message;
  EXPECT_NE(message.find("ends without a newline"), std::string::npos) << message;
}

TEST(ObjErrors, FileCutOffInsideFaceVertex) {
  // As in crytek-sponza-truncated.obj: the last vertex lost its normal index.
  const std::string message = text_error(tri_vertices + "vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1");
  expect_error(message, "t.obj:6: ", "has a different form");
  EXPECT_NE(message.find("cut off"), std::string::npos) << message;
}

TEST(ObjErrors, ErrorOnCompleteLineDoesNotClaimCutOff) {
  const std::string message = text_error(tri_vertices + "f 1 2\nf 1 2 3\n");
  expect_error(message, "t.obj:4: ", "got 2");
  EXPECT_EQ(message.find("cut off"), std::string::npos) << message;
}

TEST(ObjErrors, LineNumbersCountCrlfLines) {
  expect_error(text_error("v 0 0 0\r\n\r\nv 1 0 0\r\nv 0 1\r\nf 1 2 3\r\n"), "t.obj:4: ", "'v' needs 3 coordinates, got 2");
}

TEST(ObjErrors, ControlCharactersInTheMessageAreEscaped) {
  // Printed raw, a NUL ended the line at "t.obj:4: '3".
  expect_error(text_error(tri_vertices + std::string("f 1 2 3\0junk\n", 13)), "t.obj:4: ", "3\\x00junk");
}

TEST(ObjErrors, EmptyFile) {
  expect_error(text_error(""), "t.obj: ", "no vertices");
  expect_error(text_error("# only a comment\n\n"), "t.obj: ", "no vertices");
}

TEST(ObjErrors, NoFaces) {
  expect_error(text_error(tri_vertices), "t.obj: ", "no faces ('f' lines) found");
  expect_error(text_error(tri_vertices + "l 1 2\np 3\n"), "t.obj: ", "no faces");
}

TEST(ObjErrors, NameInMessageIsTheGivenName) {
  expect_error(text_error("v 1 0\n", "models/thing.obj"), "models/thing.obj:1: ", "needs 3 coordinates");
}

TEST_F(ObjFileTest, LoadsFile) {
  const auto path = write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  const Mesh mesh = vkray::load_obj_file(path);
  EXPECT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.triangles.size(), 2u);
}

TEST_F(ObjFileTest, ErrorNamesThePathAndLine) {
  const auto path = write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 5\n");
  expect_error(error_of([&] { vkray::load_obj_file(path); }), path.string() + ":4: ", "vertex index 5 is out of range");
}

TEST_F(ObjFileTest, TruncatedFile) {
  const auto path = write("cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2");
  const std::string message = error_of([&] { vkray::load_obj_file(path); });
  expect_error(message, path.string() + ":5: ", "cut off");
}

// A file is read a block at a time and checked as it comes: a fault on line 3 of a 64 GB file (a
// hole after it, which takes no disk) is reported there, where reading the whole file first ran out
// of memory.
TEST_F(ObjFileTest, AFaultEarlyInAHugeFileIsFoundWithoutReadingTheRest) {
  const auto path = write("huge.obj", "v 0 0 0\nv 1 0 0\nf 1 2 x\n");
  std::filesystem::resize_file(path, uintmax_t{64} << 30);
  expect_error(error_of([&] { vkray::load_obj_file(path); }), path.string() + ":3: ", "'x' is not an integer vertex index");
}

// No line of an OBJ file is longer than max_line_bytes: a longer one is refused, not buffered without end.
TEST_F(ObjFileTest, ALineLongerThanTheLimitIsRefused) {
  const auto path = write("long.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# " + std::string(vkray::max_line_bytes, ' ') + "\n");
  expect_error(error_of([&] { vkray::load_obj_file(path); }), path.string() + ":5: ", "a line longer than 1 MiB");
  expect_error(text_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# " + std::string(vkray::max_line_bytes, ' ') + "\n"), "t.obj:5: ",
               "a line longer than 1 MiB");
}

TEST_F(ObjFileTest, MissingFile) {
  const auto path = dir_ / "nope.obj";
  expect_error(error_of([&] { vkray::load_obj_file(path); }), path.string() + ": ", "no such OBJ file");
}

TEST_F(ObjFileTest, DirectoryIsNotAnObjFile) {
  const auto path = dir_ / "folder.obj";
  std::filesystem::create_directory(path);
  expect_error(error_of([&] { vkray::load_obj_file(path); }), path.string() + ": ", "is not a regular file");
}

TEST_F(ObjFileTest, EmptyFile) {
  const auto path = write("empty.obj", "");
  expect_error(error_of([&] { vkray::load_obj_file(path); }), path.string() + ": ", "no vertices");
}

}  // namespace
