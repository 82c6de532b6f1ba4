// Instances in the fp64 reference: a mesh stored once and placed by transforms renders as the scene
// with each placement's triangles written out (flattened), and an instance far from the origin at
// an extreme scale keeps the precision of its own size, exactly: rays taken into its mesh's
// coordinates by a power-of-two scale and an exact difference meet it as the mesh alone meets the
// same rays at home.
#include "engine/reference/reference.hpp"
#include "engine/scene/camera.hpp"
#include "engine/scene/mesh_generators.hpp"
#include "engine/scene/scene.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

using vkray::Instance;
using vkray::Mesh;
using vkray::ReferenceHit;
using vkray::ReferenceScene;
using vkray::Scene;

// A scene of an ordinary mesh, a sphere, a ground plane and a closed mesh placed by `placements`
// (meshes[1], instanced).
Scene placed_scene(const std::vector<Instance>& placements) {
  Scene scene;
  scene.meshes.push_back(vkray::make_sphere_mesh(500, glm::dvec3(-2.5, 0.5, 0.0), 0.7));
  Mesh placed = vkray::make_sphere_mesh(2000);
  placed.instanced = true;
  scene.meshes.push_back(placed);
  scene.spheres.push_back({glm::dvec3(2.5, 0.4, -1.0), 0.6});
  scene.planes.push_back({glm::dvec3(0.0, -1.5, 0.0), glm::dvec3(0.0, 1.0, 0.0)});
  scene.instances = placements;
  scene.camera = {glm::dvec3(0.5, 2.0, 7.0), glm::dvec3(0.0, 0.0, 0.0), glm::dvec3(0.0, 1.0, 0.0), 55.0};
  return scene;
}

// The same scene with every instance written out as a mesh of its own (after the others: mesh
// 2 + k is instance k), its positions placed in double; the instanced mesh, placed by none, is drawn
// nowhere.
Scene flattened(const Scene& scene) {
  Scene flat = scene;
  flat.instances.clear();
  for (const Instance& instance : scene.instances) {
    Mesh copy = scene.meshes[instance.mesh];
    copy.instanced = false;
    copy.mask = instance.mask;
    for (auto& position : copy.positions) position = vkray::placed(instance, position);
    flat.meshes.push_back(copy);
  }
  return flat;
}

Instance instance_of_mesh_1(const glm::dmat3& linear, const glm::dvec3& translation, vkray::Mask mask = vkray::every_mask_bit) {
  return {1, linear, translation, mask};
}

glm::dmat3 rotation_about_y(double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  return glm::dmat3(glm::dvec3(c, 0.0, -s), glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(s, 0.0, c));  // columns
}

// Rotated, sheared and unevenly scaled, and mirrored by a negative scale: each renders as its
// flattened copy. Distances agree to the rounding of placing positions in double against taking
// rays into the mesh (1e-12 relative is a thousand times that); normals, facing the ray, alike.
TEST(Instances, TheReferenceRendersThemAsTheFlattenedScene) {
  glm::dmat3 sheared(1.0);
  sheared[1][0] = 0.4;  // x += 0.4 y
  sheared = sheared * glm::dmat3(glm::dvec3(0.5, 0.0, 0.0), glm::dvec3(0.0, 1.3, 0.0), glm::dvec3(0.0, 0.0, 0.8));
  const glm::dmat3 mirrored = glm::dmat3(glm::dvec3(-0.6, 0.0, 0.0), glm::dvec3(0.0, 0.6, 0.0), glm::dvec3(0.0, 0.0, 0.6));
  const Scene scene = placed_scene({instance_of_mesh_1(rotation_about_y(0.7), glm::dvec3(0.0, 0.0, 0.0)),
                                    instance_of_mesh_1(sheared, glm::dvec3(0.3, 1.4, 1.5)),
                                    instance_of_mesh_1(mirrored, glm::dvec3(1.0, -0.6, 2.2))});
  Scene checked = scene;
  vkray::check_scene(checked);
  const Scene flat = flattened(scene);
  const ReferenceScene instanced_reference(scene), flat_reference(flat);
  constexpr uint32_t width = 120, height = 80;
  const auto instanced_hits = vkray::render_reference_hits(instanced_reference, scene.camera, width, height);
  const auto flat_hits = vkray::render_reference_hits(flat_reference, flat.camera, width, height);
  size_t on_instances = 0, on_mirrored = 0;
  for (size_t p = 0; p < instanced_hits.size(); ++p) {
    const ReferenceHit &a = instanced_hits[p], &b = flat_hits[p];
    SCOPED_TRACE("pixel " + std::to_string(p));
    ASSERT_EQ(a.kind, b.kind);
    if (a.kind == vkray::PrimitiveKind::none) continue;
    EXPECT_NEAR(a.t, b.t, 1e-12 * b.t);
    EXPECT_NEAR(glm::length(a.normal - b.normal), 0.0, 1e-12);
    if (a.kind != vkray::PrimitiveKind::triangle) {
      EXPECT_EQ(a.index, b.index);
      continue;
    }
    const vkray::ObjectPrimitive source = instanced_reference.source(a), flat_source = flat_reference.source(b);
    if (a.instance == vkray::no_object) {
      EXPECT_EQ(source, flat_source);
      continue;
    }
    ++on_instances;
    on_mirrored += a.instance == 2;
    EXPECT_EQ(source.object, 1u) << "an instance's hit names its mesh";
    EXPECT_EQ(flat_source.object, 2 + a.instance) << "and the copy written out for it";
    EXPECT_EQ(source.primitive, flat_source.primitive);
  }
  EXPECT_GT(on_instances, width * height / 20);
  EXPECT_GT(on_mirrored, 100u);
}

// Given rays: the count of crossings and the first four hits through two instances of a closed
// mesh, one mirrored, as through the flattened scene.
TEST(Instances, CrossingsAndFirstHitsCountEachInstance) {
  const glm::dmat3 mirrored(glm::dvec3(0.9, 0.0, 0.0), glm::dvec3(0.0, -0.9, 0.0), glm::dvec3(0.0, 0.0, 0.9));
  const Scene scene = placed_scene({instance_of_mesh_1(glm::dmat3(1.0), glm::dvec3(0.0, 0.0, 0.0)),
                                    instance_of_mesh_1(mirrored, glm::dvec3(0.0, 0.0, -3.0))});
  const Scene flat = flattened(scene);
  const ReferenceScene instanced_reference(scene), flat_reference(flat);
  for (const double x : {0.013, 0.31, -0.52, 0.77}) {
    const glm::dvec3 origin(x, 0.1, 5.0), dir(0.0, 0.0, -1.0);
    SCOPED_TRACE("x " + std::to_string(x));
    EXPECT_EQ(instanced_reference.count_crossings(origin, dir), flat_reference.count_crossings(origin, dir));
    EXPECT_EQ(instanced_reference.count_crossings(origin, dir), 4u) << "in and out of each";
    const auto first = instanced_reference.first_hits(origin, dir, vkray::no_hit, 4);
    const auto flat_first = flat_reference.first_hits(origin, dir, vkray::no_hit, 4);
    for (size_t k = 0; k < 4; ++k) {
      EXPECT_NEAR(first[k].t, flat_first[k].t, 1e-12 * flat_first[k].t);
      EXPECT_NEAR(glm::length(first[k].normal - flat_first[k].normal), 0.0, 1e-12);
      EXPECT_EQ(first[k].instance, k / 2) << "the first instance's two crossings, then the second's";
    }
  }
}

// An instance whose mask shares no bit with the rays' is left out, as a mesh's would be.
TEST(Instances, AMaskLeavesAnInstanceOut) {
  const Scene scene = placed_scene({instance_of_mesh_1(glm::dmat3(1.0), glm::dvec3(0.0), 0x02),
                                    instance_of_mesh_1(glm::dmat3(1.0), glm::dvec3(0.0, 0.0, -3.0), 0x01)});
  EXPECT_TRUE(scene.has_masks());
  const glm::dvec3 origin(0.0, 0.1, 5.0), dir(0.0, 0.0, -1.0);
  const ReferenceHit through_first = ReferenceScene(scene, 0x02).trace(origin, dir);
  EXPECT_EQ(through_first.instance, 0u);
  const ReferenceHit past_it = ReferenceScene(scene, 0x01).trace(origin, dir);
  EXPECT_EQ(past_it.instance, 1u);
  EXPECT_NEAR(past_it.t, 7.0, 0.02) << "the second sphere's front, 3 behind the first's";
  EXPECT_EQ(ReferenceScene(scene, 0x01).count_crossings(origin, dir), 2u);
}

// The mesh at home seen from `from` (on +z, looking at the origin), and its instance placed at
// `translation` by the scale 2^`exponent` (mirrored in x where `mirror`), seen from the camera
// that transform takes `from` to. Every placed ray is the home ray scaled, taken back exactly (a
// power of two, and a difference of numbers within a factor two), so every distance is the home
// one times the scale to the last bit and every normal the home one (mirrored), to its rounding.
void expect_exact_at_scale(int exponent, const glm::dvec3& translation, bool mirror) {
  SCOPED_TRACE("scale 2^" + std::to_string(exponent) + (mirror ? ", mirrored" : ""));
  const double scale = std::ldexp(1.0, exponent);
  Scene home;
  home.meshes.push_back(vkray::make_sphere_mesh(3000));
  home.camera = {glm::dvec3(0.0, 0.0, 3.0), glm::dvec3(0.0), glm::dvec3(0.0, 1.0, 0.0), 50.0};
  Scene away = home;
  away.meshes[0].instanced = true;
  const glm::dvec3 axis_scale(mirror ? -scale : scale, scale, scale);
  away.instances.push_back({0, glm::dmat3(glm::dvec3(axis_scale.x, 0, 0), glm::dvec3(0, axis_scale.y, 0), glm::dvec3(0, 0, axis_scale.z)),
                            translation});
  away.camera = {translation + axis_scale * home.camera.from, translation, glm::dvec3(0.0, 1.0, 0.0), 50.0};
  ASSERT_EQ(away.camera.from - translation, axis_scale * home.camera.from) << "the camera's offset is exact";
  Scene checked = away;
  vkray::check_scene(checked);
  const ReferenceScene home_reference(home), away_reference(away);
  constexpr uint32_t width = 64, height = 48;
  const auto home_hits = vkray::render_reference_hits(home_reference, home.camera, width, height);
  const auto away_hits = vkray::render_reference_hits(away_reference, away.camera, width, height);
  size_t hits = 0;
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) {
      // Mirrored, the placed image is the home one turned left to right: a ray's uv.x is an odd
      // function of the column and the camera's right is (1, 0, 0), so pixel i's ray is home's
      // column width - 1 - i's with x negated, exactly.
      const ReferenceHit& a = away_hits[size_t{j} * width + i];
      const ReferenceHit& b = home_hits[size_t{j} * width + (mirror ? width - 1 - i : i)];
      SCOPED_TRACE("pixel " + std::to_string(i) + ", " + std::to_string(j));
      ASSERT_EQ(a.kind, b.kind);
      if (a.kind == vkray::PrimitiveKind::none) continue;
      ++hits;
      EXPECT_EQ(a.index, b.index);
      EXPECT_EQ(a.instance, 0u);
      const glm::dvec3 home_normal = mirror ? glm::dvec3(-b.normal.x, b.normal.y, b.normal.z) : b.normal;
      EXPECT_EQ(a.t, b.t * scale);
      // Normalized once more on the way back (to one rounding of unit length).
      EXPECT_NEAR(glm::length(a.normal - home_normal), 0.0, 4e-16);
    }
  }
  EXPECT_GT(hits, width * height / 4);
}

// 1e-6 and 1e6 across, 1e5 from the world's origin, and mirrored. Written out in the world's
// coordinates the small one would lose its shape: positions 1e5 out round to 1.5e-11, 1e-5 of
// its size, where rays taken into its mesh keep double's 1e-16 of it.
TEST(Instances, AnInstanceFarAwayAtAnExtremeScaleKeepsItsOwnPrecision) {
  const glm::dvec3 far_away(1e5, -3.0e4, 131072.5);
  expect_exact_at_scale(-20, far_away, false);
  expect_exact_at_scale(20, far_away, false);
  expect_exact_at_scale(-20, far_away, true);
}

// What check_scene refuses, naming the instance.
TEST(Instances, BadInstancesAreRefusedByName) {
  const auto refusal = [](Scene scene) {
    try {
      vkray::check_scene(scene);
    } catch (const vkray::InputError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  const Instance good = instance_of_mesh_1(glm::dmat3(1.0), glm::dvec3(0.0));
  Instance singular = good;
  singular.linear[2] = glm::dvec3(0.0);
  EXPECT_NE(refusal(placed_scene({good, singular})).find("instances[1].transform: cannot be inverted"), std::string::npos);
  Instance of_plain_mesh = good;
  of_plain_mesh.mesh = 0;
  EXPECT_NE(refusal(placed_scene({of_plain_mesh})).find("instances[0].mesh: 0 is not an instanced mesh"), std::string::npos);
  Instance out_of_range = good;
  out_of_range.mesh = 7;
  EXPECT_NE(refusal(placed_scene({out_of_range})).find("instances[0].mesh: 7"), std::string::npos);
  Instance too_far = good;
  too_far.translation = glm::dvec3(0.0, 0.0, 1e15);
  EXPECT_NE(refusal(placed_scene({too_far})).find("instances[0].transform: the mesh's box placed"), std::string::npos);
  Instance not_finite = good;
  not_finite.linear[0][0] = std::nan("");
  EXPECT_NE(refusal(placed_scene({not_finite})).find("instances[0].transform"), std::string::npos);
  EXPECT_EQ(refusal(placed_scene({good})), "");
  // A mask of the instanced mesh's own would be ignored (its instances' stand for it): refused.
  Scene masked_mesh = placed_scene({good});
  masked_mesh.meshes[1].mask = 2;
  EXPECT_NE(refusal(masked_mesh).find("meshes[1].mask: the mesh is drawn by its instances"), std::string::npos);
}

glm::dmat3 scale_matrix(const glm::dvec3& s) { return glm::dmat3(glm::dvec3(s.x, 0, 0), glm::dvec3(0, s.y, 0), glm::dvec3(0, 0, s.z)); }

// Placements float32 shaders walk as the reference does, and those they cannot (hostile campaign
// 3): a scale along the mesh's axes, then a rotation, spreads a mesh coordinate's rounding over 3 of
// the world's (each column's length times its row's is 1), at any ratio; an uneven scale along
// turned axes (after the rotation, or between a rotation and its inverse) in proportion to its
// ratio; a shear less than its length's; a flattening beyond 2^32 or an inverse beyond float32's
// exponents is refused however it is composed.
TEST(Instances, Float32WalksWhatIsAcceptedAsTheReferenceDoes) {
  const glm::dmat3 turn = rotation_about_y(0.7) * glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, std::cos(0.3), std::sin(0.3)),
                                                             glm::dvec3(0, -std::sin(0.3), std::cos(0.3)));
  for (const glm::dvec3& s : {glm::dvec3(1.0), glm::dvec3(1e-20), glm::dvec3(1e3, 1e-3, 2.0), glm::dvec3(1e6), glm::dvec3(1.0, 1.0, 0x1p-31),
                              glm::dvec3(-3.0, 2.0, 1.0)}) {
    SCOPED_TRACE("scale " + std::to_string(s.x) + ", " + std::to_string(s.y) + ", " + std::to_string(s.z));
    EXPECT_EQ(vkray::float32_placement_fault(turn * scale_matrix(s)), "");
  }
  EXPECT_EQ(vkray::float32_placement_fault(scale_matrix(glm::dvec3(-2.0)) * turn), "");  // even: the order does not matter
  EXPECT_NE(vkray::float32_placement_fault(scale_matrix({1e3, 1e-3, 2.0}) * turn).find("across rotated axes"), std::string::npos);
  glm::dmat3 shear(1.0);
  shear[1][0] = 1.0;  // x += y
  EXPECT_EQ(vkray::float32_placement_fault(shear * scale_matrix({0.5, 1.3, 0.8})), "");
  // A board 1 x 1 x 0.01 turned after it is scaled in turned axes: its coordinates' roundings reach ~70x.
  const glm::dmat3 across = turn * scale_matrix({1.0, 1.0, 0.01}) * glm::transpose(turn);
  EXPECT_NE(vkray::float32_placement_fault(across).find("scales or shears across rotated axes"), std::string::npos);
  EXPECT_EQ(vkray::float32_placement_fault(turn * scale_matrix({1.0, 1.0, 0.5}) * glm::transpose(turn)), "");
  // The campaign's: a scale of 1e-38 on one axis (float32 took its inverse's 1e38 to inf), and a
  // condition number of 4e12.
  EXPECT_NE(vkray::float32_placement_fault(scale_matrix({1.0, 1.0, 1e-38})).find("flattens the mesh"), std::string::npos);
  EXPECT_NE(vkray::float32_placement_fault(turn * scale_matrix({2e6, 1.0, 5e-7})).find("flattens the mesh"), std::string::npos);
  EXPECT_NE(vkray::float32_placement_fault(scale_matrix(glm::dvec3(1e-31))).find("row 0 reaches"), std::string::npos);
  EXPECT_NE(vkray::float32_placement_fault(scale_matrix(glm::dvec3(1e31))).find("row 0 reaches"), std::string::npos);
}

// An instance costs its box's eight corners, not its vertices: the scene's box is the placed boxes'
// (a rotated instance's a little larger than its vertices'), and the anchor and radius follow it.
TEST(Instances, TheScenesBoxTakesEachPlacementsBoxCorners) {
  const Instance turned = instance_of_mesh_1(rotation_about_y(0.7), glm::dvec3(10.0, 0.0, 0.0));
  Scene scene = placed_scene({turned});
  scene.meshes.erase(scene.meshes.begin());  // the placed mesh alone, now meshes[0]
  scene.spheres.clear();
  scene.instances[0].mesh = 0;
  const std::vector<vkray::Bounds> boxes = vkray::instanced_mesh_boxes(scene);
  const vkray::Bounds expected_box = [&] {
    vkray::Bounds box;
    for (int k = 0; k < 8; ++k) box.add(vkray::placed(scene.instances[0], boxes[0].corner(k)));
    return box;
  }();
  const vkray::Bounds found = vkray::finite_bounds(scene);
  EXPECT_EQ(found.lower, expected_box.lower);
  EXPECT_EQ(found.upper, expected_box.upper);
  double corner_radius = 0.0;
  for (int k = 0; k < 8; ++k) corner_radius = std::max(corner_radius, glm::length(expected_box.corner(k) - glm::dvec3(10.0, 0.0, 0.0)));
  EXPECT_LE(vkray::scene_radius(scene, glm::dvec3(10.0, 0.0, 0.0)), corner_radius);
  for (const glm::dvec3& p : scene.meshes[0].positions) {  // and still every vertex where it is drawn
    EXPECT_LE(glm::length(vkray::placed(scene.instances[0], p) - glm::dvec3(10.0, 0.0, 0.0)),
              vkray::scene_radius(scene, glm::dvec3(10.0, 0.0, 0.0)));
  }
}

// Moving an instanced mesh's vertices is checked where its instances place them, and an instance
// listed twice in one set_transforms is refused; either leaves the scene as it was.
TEST(Instances, MovedVerticesAndTransformsAreCheckedWhereTheyArePlaced) {
  Scene scene = placed_scene({instance_of_mesh_1(scale_matrix(glm::dvec3(1e10)), glm::dvec3(0.0))});
  std::vector<glm::dvec3> moved = scene.meshes[1].positions;
  for (glm::dvec3& p : moved) p *= 1e6;  // 1e6 itself, 1e16 where the instance places it
  const std::vector<glm::dvec3> before = scene.meshes[1].positions;
  const std::string refused = [&] {
    try {
      vkray::move_vertices(scene, 1, moved);
    } catch (const vkray::InputError& error) {
      return std::string(error.what());
    }
    return std::string();
  }();
  EXPECT_NE(refused.find("instances[0].transform: the mesh's box placed"), std::string::npos) << refused;
  EXPECT_EQ(scene.meshes[1].positions, before);

  const uint32_t twice[] = {0, 0};
  const glm::dmat4 transforms[] = {glm::dmat4(1.0), glm::dmat4(2.0)};
  const std::string duplicate = [&] {
    try {
      vkray::set_instance_transforms(scene, twice, transforms);
    } catch (const vkray::InputError& error) {
      return std::string(error.what());
    }
    return std::string();
  }();
  EXPECT_NE(duplicate.find("instances[1]: instance 0 is placed twice (entries 0 and 1)"), std::string::npos) << duplicate;
  EXPECT_EQ(scene.instances[0].linear, scale_matrix(glm::dvec3(1e10)));
}

// A named mesh no instance places is drawn nowhere: no triangle counts (the device has nothing to
// build a tree from), as the reference has none.
TEST(Instances, AMeshNoInstancePlacesHasNoDrawnTriangle) {
  Scene scene = placed_scene({});
  EXPECT_EQ(scene.drawn_triangle_count(), scene.meshes[0].triangles.size());
  scene.instances.push_back(instance_of_mesh_1(glm::dmat3(1.0), glm::dvec3(0.0)));
  EXPECT_EQ(scene.drawn_triangle_count(), scene.meshes[0].triangles.size() + scene.meshes[1].triangles.size());
}

}  // namespace
