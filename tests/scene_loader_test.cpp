// Scene JSON loader: every bad input gives a one-line InputError that names the file and the JSON
// path (or line:column for invalid JSON); good inputs load with defaults, normalized plane normals
// and mesh transforms applied in the order scale -> rotate -> translate.
#include "tests/input_error_test.hpp"
#include "tests/temp_dir_test.hpp"
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/scene_loader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

namespace {

using vkray::test::error_of;
using vkray::test::expect_error;

using vkray::InputError;
using vkray::Scene;

const std::string camera = R"("camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 60})";

// A scene with the valid camera above plus `rest` (more top-level members).
std::string with_camera(const std::string& rest) { return "{" + camera + (rest.empty() ? "" : ", " + rest) + "}"; }

// An OBJ loader that must not be called.
vkray::Mesh no_obj(const std::filesystem::path& path) {
  ADD_FAILURE() << "unexpected OBJ load of " << path;
  throw InputError(path.string() + ": unexpected");
}

// A model file of one mesh, as an OBJ is.
using MeshLoader = std::function<vkray::Mesh(const std::filesystem::path&)>;

Scene parse(const std::string& json, const MeshLoader& load_obj = no_obj) {
  return vkray::parse_scene(json, "t.json", "/scenes",
                            [&](const std::filesystem::path& path) { return std::vector<vkray::Mesh>{load_obj(path)}; });
}

std::string parse_error(const std::string& json, const MeshLoader& load_obj = no_obj) {
  return error_of([&] { parse(json, load_obj); });
}

void expect_near(const glm::dvec3& actual, const glm::dvec3& expected, double tolerance = 1e-12) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

// One triangle, for the OBJ loader stand-in.
vkray::Mesh unit_triangle() {
  vkray::Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

const std::string triangle_obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

// ---- Instances -------------------------------------------------------------------------------

// A named mesh is placed by instances alone, each with the usual transform (scaled, rotated,
// translated) and a mask of its own; the others stay where they stand.
TEST(SceneJson, NamedMeshesArePlacedByInstances) {
  const Scene scene = parse(with_camera(R"("meshes": [
      {"positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]},
      {"name": "leaf", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]}],
    "instances": [{"mesh": "leaf"},
                  {"mesh": "leaf", "transform": {"scale": [2, 1, 1], "rotate": {"axis": [0, 0, 1], "degrees": 90},
                                                 "translate": [5, 0, 0]}, "mask": 4}])"));
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_FALSE(scene.meshes[0].instanced);
  EXPECT_TRUE(scene.meshes[1].instanced);
  ASSERT_EQ(scene.instances.size(), 2u);
  EXPECT_EQ(scene.instances[0].mesh, 1u);
  EXPECT_EQ(scene.instances[0].mask, vkray::every_mask_bit);
  EXPECT_EQ(scene.instances[1].mask, 4u);
  // (1, 0, 0) scaled to (2, 0, 0), turned to (0, 2, 0), moved to (5, 2, 0).
  expect_near(vkray::placed(scene.instances[1], {1.0, 0.0, 0.0}), {5.0, 2.0, 0.0});
  expect_near(vkray::placed(scene.instances[0], {1.0, 0.0, 0.0}), {1.0, 0.0, 0.0});
}

TEST(SceneJson, InstancesNameAMeshThatIsNamedOnce) {
  const std::string leaf = R"({"name": "leaf", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]})";
  expect_error(parse_error(with_camera(R"("meshes": [)" + leaf + R"(], "instances": [{"mesh": "leaves"}])")),
               "t.json: instances[0].mesh: ", "no mesh is named 'leaves' (named: 'leaf')");
  expect_error(parse_error(with_camera(R"("meshes": [)" + leaf + ", " + leaf + "]")), "t.json: meshes[1].name: ",
               "another mesh is named 'leaf'");
  expect_error(parse_error(with_camera(R"("meshes": [)" + leaf + R"(], "instances": [{"mesh": "leaf", "colour": 1}])")),
               "t.json: instances[0].colour: ", "unknown key 'colour'");
  expect_error(parse_error(with_camera(R"("meshes": [)" + leaf + R"(], "instances": [{"mesh": "leaf", "transform": {"scale": 0}}])")),
               "t.json: instances[0].transform.scale: ", "scale factors must be non-zero");
  expect_error(parse_error(with_camera(R"("meshes": [)" + leaf + R"(], "instances": [{"mesh": 3}])")),
               "t.json: instances[0].mesh: ", "expected a string");
  // Its instances' masks stand for a named mesh's own: one given to it would be ignored.
  const std::string masked_leaf = R"({"name": "leaf", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]], "mask": 3})";
  expect_error(parse_error(with_camera(R"("meshes": [)" + masked_leaf + R"(], "instances": [{"mesh": "leaf"}])")),
               "t.json: meshes[0].mask: ", "give each instance the mask");
}

// Each instance's transform is checked where the file places it, as Python's and the C API's are
// (hostile campaign 3: a scale of 1e39 crashed Embree's builder, 1e38 rendered every ray a miss).
TEST(SceneJson, InstanceTransformsAreCheckedWhereTheFilePlacesThem) {
  const std::string leaf = R"({"name": "leaf", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]})";
  const auto placed_by = [&](const std::string& transform) {
    return parse_error(with_camera(R"("meshes": [)" + leaf + R"(], "instances": [{"mesh": "leaf"}, {"mesh": "leaf", "transform": )" +
                                   transform + "}]"));
  };
  expect_error(placed_by(R"({"scale": 1e39})"), "t.json: instances[1].transform: ", "within 1e15");
  expect_error(placed_by(R"({"scale": 1e38})"), "t.json: instances[1].transform: ", "within 1e15");
  expect_error(placed_by(R"({"translate": [1e16, 0, 0]})"), "t.json: instances[1].transform: ", "within 1e15");
  expect_error(placed_by(R"({"scale": 1e14, "translate": [1e15, 0, 0]})"), "t.json: instances[1].transform: ",
               "the mesh's box placed");
  expect_error(placed_by(R"({"scale": 1e-120})"), "t.json: instances[1].transform: ", "cannot be inverted");
  expect_error(placed_by(R"({"scale": [1, 1, 1e-38]})"), "t.json: instances[1].transform: ", "flattens the mesh");
  expect_error(placed_by(R"({"scale": 1e-31})"), "t.json: instances[1].transform: ", "outside the 2^-100 .. 2^100");
  EXPECT_EQ(placed_by(R"({"scale": [1e-6, 1e-6, 1e-6], "translate": [1e5, 0, 0]})"), "");
}

// ---- Invalid JSON ----------------------------------------------------------------------------

TEST(SceneJson, InvalidJsonReportsLineAndColumn) {
  const std::string json = "{\n  \"camera\": {\"from\": [0, 0, 5],\n    \"to\": [0 0 0], \"fovy\": 60}\n}\n";
  expect_error(parse_error(json), "t.json:3:14: ", "invalid JSON: syntax error while parsing array");
}

TEST(SceneJson, InvalidJsonOnFirstLine) {
  expect_error(parse_error("{\"camera\" {}}"), "t.json:1:11: ", "invalid JSON: syntax error while parsing object separator");
}

TEST(SceneJson, AByteOrderMarkIsSkipped) {
  EXPECT_EQ(parse("\xEF\xBB\xBF" + with_camera("")).camera.from, glm::dvec3(0, 0, 5));
}

TEST(SceneJson, ANulByteIsRefusedNotTakenForTheEnd) {
  expect_error(parse_error(with_camera("") + std::string(1, '\0') + "\n}"), "t.json:1:", "a NUL byte");
}

TEST(SceneJson, EmptyText) { expect_error(parse_error(""), "t.json:1:1: ", "invalid JSON"); }

TEST(SceneJson, TrailingGarbage) { expect_error(parse_error(with_camera("") + "\n}"), "t.json:2:1: ", "invalid JSON"); }

TEST(SceneJson, UnterminatedDocument) {
  expect_error(parse_error("{\"camera\": {\"from\": [0, 0, 5]"), "t.json:1:", "invalid JSON");
}

TEST(SceneJson, NanLiteralIsInvalidJson) {
  expect_error(parse_error(with_camera("\"spheres\": [{\"center\": [0, 0, 0],\n \"radius\": NaN}]")), "t.json:2:", "invalid JSON");
}

TEST(SceneJson, TopLevelMustBeAnObject) {
  expect_error(parse_error("[1, 2]"), "t.json: top level: ", "expected an object, got [1,2]");
  expect_error(parse_error("null"), "t.json: top level: ", "expected an object, got null");
}

// ---- Wrong types -----------------------------------------------------------------------------

TEST(SceneJson, RadiusIsAString) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": "big"}])")),
               "t.json: spheres[0].radius: ", "expected a number, got \"big\"");
}

TEST(SceneJson, CenterWithTwoNumbers) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [1, 2], "radius": 1}])")), "t.json: spheres[0].center: ",
               "expected 3 numbers [x, y, z], got [1,2]");
}

TEST(SceneJson, CenterWithFourNumbers) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [1, 2, 3, 4], "radius": 1}])")),
               "t.json: spheres[0].center: ", "expected 3 numbers");
}

TEST(SceneJson, CoordinateIsAString) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [1, 2, "3"], "radius": 1}])")),
               "t.json: spheres[0].center[2]: ", "expected a number, got \"3\"");
}

TEST(SceneJson, CenterIsAnObject) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": {"x": 1}, "radius": 1}])")), "t.json: spheres[0].center: ",
               "expected an array");
}

TEST(SceneJson, SpheresIsNotAnArray) {
  expect_error(parse_error(with_camera(R"("spheres": {"center": [0, 0, 0], "radius": 1})")), "t.json: spheres: ",
               "expected an array");
}

TEST(SceneJson, SphereIsNotAnObject) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": 1}, 7])")), "t.json: spheres[1]: ",
               "expected an object, got 7");
}

TEST(SceneJson, CameraIsANumber) {
  expect_error(parse_error(R"({"camera": 5})"), "t.json: camera: ", "expected an object, got 5");
}

TEST(SceneJson, FovyIsABoolean) {
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": true}})"), "t.json: camera.fovy: ",
               "expected a number, got true");
}

TEST(SceneJson, ObjIsNotAString) {
  expect_error(parse_error(with_camera(R"("meshes": [{"obj": 5}])")), "t.json: meshes[0].obj: ", "expected a string, got 5");
  expect_error(parse_error(with_camera(R"("meshes": [{"obj": "cow.obj\u0000junk"}])")), "t.json: meshes[0].obj: ",
               "a file name cannot hold a NUL character");
}

TEST(SceneJson, LongValueIsShortenedInMessage) {
  const std::string message =
      parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"}])"));
  expect_error(message, "t.json: spheres[0].radius: ", "...");
  EXPECT_LT(message.size(), 120u) << message;
}

TEST(SceneJson, DeeplyNestedValueDoesNotOverflowTheStack) {
  // The message shows the start of the offending value; printing it must not recurse per level.
  const size_t depth = 200000;
  const std::string nested = std::string(depth, '[') + std::string(depth, ']');
  expect_error(parse_error("{\"camera\": " + nested + "}"), "t.json: camera: ", "expected an object, got [[[[[[[[[[");
  expect_error(parse_error(with_camera("\"spheres\": [{\"center\": [0, " + nested + ", 0], \"radius\": 1}]")),
               "t.json: spheres[0].center[1]: ", "expected a number, got [[[[[[[[[[");
}

// ---- Missing keys ----------------------------------------------------------------------------

TEST(SceneJson, MissingCamera) {
  expect_error(parse_error(R"({"spheres": []})"), "t.json: top level: ", "missing required key 'camera'");
  expect_error(parse_error("{}"), "t.json: top level: ", "missing required key 'camera'");
}

TEST(SceneJson, MissingCameraFields) {
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0]}})"), "t.json: camera: ",
               "missing required key 'fovy'");
  expect_error(parse_error(R"({"camera": {"to": [0, 0, 0], "fovy": 60}})"), "t.json: camera: ", "missing required key 'from'");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 0], "fovy": 60}})"), "t.json: camera: ", "missing required key 'to'");
}

TEST(SceneJson, MissingSphereRadius) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0]}])")), "t.json: spheres[0]: ",
               "missing required key 'radius'");
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": 1}, {"radius": 1}])")),
               "t.json: spheres[1]: ", "missing required key 'center'");
}

TEST(SceneJson, MissingPlaneNormal) {
  expect_error(parse_error(with_camera(R"("planes": [{"point": [0, 0, 0]}])")), "t.json: planes[0]: ",
               "missing required key 'normal'");
}

TEST(SceneJson, MissingMeshData) {
  expect_error(parse_error(with_camera(R"("meshes": [{}])")), "t.json: meshes[0]: ", "missing required key 'positions'");
  expect_error(parse_error(with_camera(R"("meshes": [{"positions": [[0, 0, 0]]}])")), "t.json: meshes[0]: ",
               "missing required key 'triangles'");
}

// ---- Unknown keys ----------------------------------------------------------------------------

TEST(SceneJson, UnknownTopLevelKeySuggestsNearestName) {
  expect_error(parse_error(with_camera(R"("sphere": [])")), "t.json: sphere: ", "unknown key 'sphere' (did you mean 'spheres'?)");
  expect_error(parse_error(with_camera(R"("mesh": [])")), "t.json: mesh: ", "(did you mean 'meshes'?)");
}

TEST(SceneJson, UnknownNestedKeySuggestsNearestName) {
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": 1}, {"center": [0, 0, 0], "raduis": 1}])")),
               "t.json: spheres[1].raduis: ", "unknown key 'raduis' (did you mean 'radius'?)");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fov": 60}})"), "t.json: camera.fov: ",
               "(did you mean 'fovy'?)");
  expect_error(parse_error(with_camera(R"("image": {"widht": 10})")), "t.json: image.widht: ", "(did you mean 'width'?)");
  expect_error(parse_error(with_camera(R"("meshes": [{"obj": "a.obj", "transform": {"translation": [0, 0, 0]}}])"),
                           [](const std::filesystem::path&) { return unit_triangle(); }),
               "t.json: meshes[0].transform.translation: ", "(did you mean 'translate'?)");
}

TEST(SceneJson, UnknownKeyFarFromAllNamesListsThem) {
  expect_error(parse_error(with_camera(R"("materials": [])")), "t.json: materials: ",
               "unknown key 'materials' (expected one of: camera, image, spheres, planes, meshes, instances)");
}

TEST(SceneJson, UnknownKeyWithNewlineKeepsMessageOnOneLine) {
  expect_error(parse_error(with_camera(R"("bad\nkey": 1)")), "t.json: bad\\nkey: ", "unknown key 'bad\\nkey'");
}

// ---- Numbers that are not finite -------------------------------------------------------------

TEST(SceneJson, OverflowingNumberIsNotFinite) {
  // nlohmann::json refuses 1e999 with out_of_range.406 (not a parse_error, and without a position);
  // the loader must turn that into an InputError that names the JSON path.
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": 1e999}])")), "t.json: spheres[0].radius: ",
               "number is not finite");
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, -1e999, 0], "radius": 1}])")),
               "t.json: spheres[0].center[1]: ", "number is not finite");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 1e400}})"), "t.json: camera.fovy: ",
               "number is not finite");
}

TEST(SceneJson, HugeIntegerIsNotFinite) {
  const std::string digits(400, '9');
  const std::string message = parse_error(with_camera("\"image\": {\"width\": " + digits + "}"));
  expect_error(message, "t.json: image.width: ", "number is not finite (number overflow parsing '999");
  EXPECT_LT(message.size(), 150u) << message;
  expect_error(parse_error(with_camera("\"meshes\": [{\"positions\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],\n \"triangles\": [[0, 1, 2], [0, 1, -" +
                                       digits + "]]}]")),
               "t.json: meshes[0].triangles[1][2]: ", "number is not finite");
  expect_error(parse_error("1e999"), "t.json: top level: ", "number is not finite (number overflow parsing '1e999')");
}

// ---- Value checks ----------------------------------------------------------------------------

TEST(SceneJson, RadiusMustBePositive) {
  const std::string two = R"({"center": [0, 0, 0], "radius": 1}, {"center": [1, 0, 0], "radius": 2}, )";
  expect_error(parse_error(with_camera("\"spheres\": [" + two + R"({"center": [0, 0, 0], "radius": 0}])")),
               "t.json: spheres[2].radius: ", "must be > 0, got 0");
  expect_error(parse_error(with_camera("\"spheres\": [" + two + R"({"center": [0, 0, 0], "radius": -1}])")),
               "t.json: spheres[2].radius: ", "must be > 0, got -1");
}

TEST(SceneJson, ZeroPlaneNormal) {
  expect_error(parse_error(with_camera(R"("planes": [{"point": [0, 0, 0], "normal": [0, 0, 0]}])")), "t.json: planes[0].normal: ",
               "must not be the zero vector");
}

TEST(SceneJson, ZeroUpVector) {
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "up": [0, 0, 0], "fovy": 60}})"),
               "t.json: camera.up: ", "must not be the zero vector");
}

// The same key twice in one object is refused wherever it is, with the path of the second one;
// the same key in two different objects is fine.
TEST(SceneJson, DuplicateKeys) {
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40, "fovy": 50}})"),
               "t.json: camera.fovy: ", "the key 'fovy' appears twice in one object");
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": 1},
                                                         {"radius": 1, "center": [0, 0, 0], "radius": 2}])")),
               "t.json: spheres[1].radius: ", "appears twice");
  expect_error(parse_error(with_camera(R"("image": {"width": 8}, "image": {"height": 8})")), "t.json: image: ",
               "appears twice");
}

TEST(SceneJson, FromEqualsTo) {
  expect_error(parse_error(R"({"camera": {"from": [1, 2, 3], "to": [1, 2, 3], "fovy": 60}})"), "t.json: camera.to: ",
               "must differ from camera.from");
}

TEST(SceneJson, FovyOutOfRange) {
  for (const std::string fovy : {"0", "180", "-5", "200", "0.0", "180.0"}) {
    SCOPED_TRACE(fovy);
    expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": )" + fovy + "}}"), "t.json: camera.fovy: ",
                 "field of view must be in (0, 180) degrees, got " + fovy);
  }
}

TEST(SceneJson, FovyJustInsideRangeLoads) {
  for (const double fovy : {0.001, 179.999}) {
    const Scene scene = parse(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": )" + std::to_string(fovy) + "}}");
    EXPECT_DOUBLE_EQ(scene.camera.fovy_degrees, fovy);
  }
}

TEST(SceneJson, ImageSizeZero) {
  expect_error(parse_error(with_camera(R"("image": {"width": 0})")), "t.json: image: ", "image size 0x600 is outside");
  expect_error(parse_error(with_camera(R"("image": {"width": 10, "height": 0})")), "t.json: image: ", "image size 10x0 is outside");
}

TEST(SceneJson, ImageSizeNegative) {
  expect_error(parse_error(with_camera(R"("image": {"width": -5})")), "t.json: image.width: ", "width -5 is out of range 0..65536");
  expect_error(parse_error(with_camera(R"("image": {"height": -1})")), "t.json: image.height: ", "height -1 is out of range");
}

TEST(SceneJson, ImageSizeFractional) {
  expect_error(parse_error(with_camera(R"("image": {"width": 800.5})")), "t.json: image.width: ",
               "expected a whole number, got 800.5");
  expect_error(parse_error(with_camera(R"("image": {"height": "600"})")), "t.json: image.height: ",
               "expected a whole number, got \"600\"");
}

TEST(SceneJson, ImageSizeWholeFloatIsAccepted) {
  const Scene scene = parse(with_camera(R"("image": {"width": 640.0, "height": 4.8e2})"));
  EXPECT_EQ(scene.width, 640u);
  EXPECT_EQ(scene.height, 480u);
}

TEST(SceneJson, ImageSizeAbsurdlyLarge) {
  expect_error(parse_error(with_camera(R"("image": {"width": 100000})")), "t.json: image.width: ",
               "width 100000 is out of range 0..65536");
  expect_error(parse_error(with_camera(R"("image": {"width": 70000, "height": 70000})")), "t.json: image.width: ",
               "width 70000 is out of range");
  expect_error(parse_error(with_camera(R"("image": {"width": 100, "height": 1e10})")), "t.json: image.height: ",
               "out of range");
  expect_error(parse_error(with_camera(R"("image": {"width": 4294967296})")), "t.json: image.width: ", "out of range");
}

TEST(SceneJson, ImagePixelCountLimit) {
  // Each side within 65536, but more pixels than max_image_pixels (2^27).
  expect_error(parse_error(with_camera(R"("image": {"width": 65536, "height": 65536})")), "t.json: image: ",
               "image size 65536x65536 is outside");
  expect_error(parse_error(with_camera(R"("image": {"width": 65536, "height": 2049})")), "t.json: image: ",
               "image size 65536x2049 is outside");
  const Scene scene = parse(with_camera(R"("image": {"width": 65536, "height": 2048})"));
  EXPECT_EQ(scene.width, 65536u);
  EXPECT_EQ(scene.height, 2048u);
}

TEST(SceneJson, TriangleIndexOutOfRange) {
  const std::string positions = R"("positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]])";
  expect_error(parse_error(with_camera("\"meshes\": [{" + positions + R"(, "triangles": [[0, 1, 2], [0, 1, 3]]}])")),
               "t.json: meshes[0].triangles[1][2]: ", "vertex index 3 is out of range 0..2");
  expect_error(parse_error(with_camera("\"meshes\": [{" + positions + R"(, "triangles": [[0, -1, 2]]}])")),
               "t.json: meshes[0].triangles[0][1]: ", "vertex index -1 is out of range");
  expect_error(parse_error(with_camera("\"meshes\": [{" + positions + R"(, "triangles": [[0, 1.5, 2]]}])")),
               "t.json: meshes[0].triangles[0][1]: ", "expected a whole number, got 1.5");
  expect_error(parse_error(with_camera("\"meshes\": [{" + positions + R"(, "triangles": [[0, 1]]}])")),
               "t.json: meshes[0].triangles[0]: ", "expected 3 vertex indices [i, j, k], got [0,1]");
  expect_error(parse_error(with_camera("\"meshes\": [{" + positions + R"(, "triangles": []}])")),
               "t.json: meshes[0].triangles: ", "a mesh needs at least one triangle");
}

TEST(SceneJson, TriangleIndexWithNoPositions) {
  expect_error(parse_error(with_camera(R"("meshes": [{"positions": [], "triangles": [[0, 0, 0]]}])")),
               "t.json: meshes[0].triangles[0][0]: ", "vertex index 0 is out of range (there are none)");
}

TEST(SceneJson, ObjAndPositionsBothGiven) {
  expect_error(parse_error(with_camera(R"("meshes": [{"obj": "a.obj", "positions": [[0, 0, 0]], "triangles": [[0, 0, 0]]}])")),
               "t.json: meshes[0]: ", "give either 'model' or 'positions' and 'triangles', not both");
  expect_error(parse_error(with_camera(R"("meshes": [{"obj": "a.obj", "triangles": [[0, 0, 0]]}])")), "t.json: meshes[0]: ",
               "not both");
}

TEST(SceneJson, ModelAndItsOlderNameObjAreOneKey) {
  const auto loader = [](const std::filesystem::path&) { return unit_triangle(); };
  EXPECT_EQ(parse(with_camera(R"("meshes": [{"model": "a.obj"}, {"obj": "b.obj"}])"), loader).meshes.size(), 2u);
  expect_error(parse_error(with_camera(R"("meshes": [{"model": "a.obj", "obj": "b.obj"}])"), loader), "t.json: meshes[0]: ",
               "give 'model' ('obj' is its older name), not both");
  expect_error(parse_error(with_camera(R"("meshes": [{"model": "a.stl"}])"), loader), "t.json: meshes[0].model: ",
               "unknown kind of model '.stl' (a model is .obj, .ply, .gltf or .glb)");
}

TEST(SceneJson, ObjLoaderErrorIsWrappedWithJsonPath) {
  const auto failing = [](const std::filesystem::path& path) -> vkray::Mesh { throw InputError(path.string() + ":7: broken"); };
  expect_error(parse_error(with_camera(R"("meshes": [{"obj": "ok.obj"}, {"obj": "sub/bad.obj"}])"),
                           [&](const std::filesystem::path& path) {
                             return path.filename() == "ok.obj" ? unit_triangle() : failing(path);
                           }),
               "t.json: meshes[1].obj: ", "/scenes/sub/bad.obj:7: broken");
}

TEST(SceneJson, TransformChecks) {
  const std::string mesh = R"("meshes": [{"obj": "a.obj", "transform": )";
  const auto loader = [](const std::filesystem::path&) { return unit_triangle(); };
  expect_error(parse_error(with_camera(mesh + R"({"scale": 0}}])"), loader), "t.json: meshes[0].transform.scale: ",
               "scale factors must be non-zero");
  expect_error(parse_error(with_camera(mesh + R"({"scale": [1, 0, 1]}}])"), loader), "t.json: meshes[0].transform.scale: ",
               "scale factors must be non-zero");
  expect_error(parse_error(with_camera(mesh + R"({"scale": [1, 2]}}])"), loader), "t.json: meshes[0].transform.scale: ",
               "expected 3 numbers");
  expect_error(parse_error(with_camera(mesh + R"({"rotate": {"axis": [0, 0, 0], "degrees": 10}}}])"), loader),
               "t.json: meshes[0].transform.rotate.axis: ", "must not be the zero vector");
  expect_error(parse_error(with_camera(mesh + R"({"rotate": {"axis": [0, 0, 1]}}}])"), loader),
               "t.json: meshes[0].transform.rotate: ", "missing required key 'degrees'");
  expect_error(parse_error(with_camera(mesh + R"({"translate": [1, 2, 1e999]}}])"), loader),
               "t.json: meshes[0].transform.translate[2]: ", "not finite");
}

// ---- Good inputs -----------------------------------------------------------------------------

TEST(SceneJson, Defaults) {
  const Scene scene = parse(R"({"camera": {"from": [1, 2, 3], "to": [4, 5, 6], "fovy": 50}})");
  EXPECT_EQ(scene.width, 800u);
  EXPECT_EQ(scene.height, 600u);
  EXPECT_EQ(scene.camera.from, glm::dvec3(1, 2, 3));
  EXPECT_EQ(scene.camera.to, glm::dvec3(4, 5, 6));
  EXPECT_EQ(scene.camera.up, glm::dvec3(0, 1, 0));
  EXPECT_EQ(scene.camera.fovy_degrees, 50.0);
  EXPECT_TRUE(scene.spheres.empty());
  EXPECT_TRUE(scene.planes.empty());
  EXPECT_TRUE(scene.meshes.empty());
}

TEST(SceneJson, ImageWithOnlyWidthKeepsDefaultHeight) {
  const Scene scene = parse(with_camera(R"("image": {"width": 320})"));
  EXPECT_EQ(scene.width, 320u);
  EXPECT_EQ(scene.height, 600u);
}

TEST(SceneJson, FullScene) {
  const Scene scene = parse(R"({
    "camera": {"from": [0, 1, 5], "to": [0, 1, 0], "up": [0, 0, 2], "fovy": 35.5},
    "image": {"width": 64, "height": 48},
    "spheres": [{"center": [1, 2, 3], "radius": 0.25}, {"center": [-1, 0, 0], "radius": 4}],
    "planes": [{"point": [0, -1, 0], "normal": [0, 1, 0]}],
    "meshes": [{"positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], "triangles": [[0, 1, 2], [0, 2, 3]]}]
  })");
  EXPECT_EQ(scene.camera.up, glm::dvec3(0, 0, 2));
  EXPECT_EQ(scene.camera.fovy_degrees, 35.5);
  EXPECT_EQ(scene.width, 64u);
  EXPECT_EQ(scene.height, 48u);
  ASSERT_EQ(scene.spheres.size(), 2u);
  EXPECT_EQ(scene.spheres[0].center, glm::dvec3(1, 2, 3));
  EXPECT_EQ(scene.spheres[0].radius, 0.25);
  EXPECT_EQ(scene.spheres[1].radius, 4.0);
  ASSERT_EQ(scene.planes.size(), 1u);
  EXPECT_EQ(scene.planes[0].point, glm::dvec3(0, -1, 0));
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].positions.size(), 4u);
  ASSERT_EQ(scene.meshes[0].triangles.size(), 2u);
  EXPECT_EQ(scene.meshes[0].triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(scene.triangle_count(), 2u);
}

TEST(SceneJson, PlaneNormalsAreNormalized) {
  const Scene scene = parse(with_camera(R"("planes": [{"point": [1, 2, 3], "normal": [0, 0, 5]},
                                                      {"point": [0, 0, 0], "normal": [3, -4, 0]}])"));
  ASSERT_EQ(scene.planes.size(), 2u);
  EXPECT_EQ(scene.planes[0].point, glm::dvec3(1, 2, 3));
  expect_near(scene.planes[0].normal, {0, 0, 1}, 1e-15);
  expect_near(scene.planes[1].normal, {0.6, -0.8, 0}, 1e-15);
}

TEST(SceneJson, TransformOrderIsScaleRotateTranslate) {
  // (1, 1, 1) scaled by (2, 3, 4) is (2, 3, 4); rotated 90 degrees about +z, (x, y) -> (-y, x), it
  // is (-3, 2, 4); translated by (1, 2, 3) it is (-2, 4, 7).
  const Scene scene = parse(with_camera(R"("meshes": [{
      "positions": [[1, 1, 1], [0, 0, 0], [1, 0, 0]], "triangles": [[0, 1, 2]],
      "transform": {"translate": [1, 2, 3], "rotate": {"axis": [0, 0, 2], "degrees": 90}, "scale": [2, 3, 4]}}])"));
  ASSERT_EQ(scene.meshes.size(), 1u);
  const auto& p = scene.meshes[0].positions;
  ASSERT_EQ(p.size(), 3u);
  expect_near(p[0], {-2, 4, 7});
  expect_near(p[1], {1, 2, 3});
  expect_near(p[2], {1, 4, 3});
}

TEST(SceneJson, UniformScaleAsNumber) {
  const Scene scene = parse(with_camera(R"("meshes": [{
      "positions": [[2, 4, -6], [0, 0, 0], [1, 0, 0]], "triangles": [[0, 1, 2]], "transform": {"scale": 0.5}}])"));
  expect_near(scene.meshes[0].positions[0], {1, 2, -3}, 0);
  expect_near(scene.meshes[0].positions[2], {0.5, 0, 0}, 0);
}

TEST(SceneJson, NegativeScaleMirrors) {
  const Scene scene = parse(with_camera(R"("meshes": [{
      "positions": [[2, 4, -6], [0, 0, 0], [1, 0, 0]], "triangles": [[0, 1, 2]], "transform": {"scale": [-1, 1, 2]}}])"));
  expect_near(scene.meshes[0].positions[0], {-2, 4, -12}, 0);
}

TEST(SceneJson, RotationAboutYFollowsRightHandRule) {
  const Scene scene = parse(with_camera(R"("meshes": [{
      "positions": [[1, 0, 0], [0, 0, 1], [0, 1, 0]], "triangles": [[0, 1, 2]],
      "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90}}}])"));
  expect_near(scene.meshes[0].positions[0], {0, 0, -1});
  expect_near(scene.meshes[0].positions[1], {1, 0, 0});
  expect_near(scene.meshes[0].positions[2], {0, 1, 0});
}

// An OBJ's normals go through the inverse transpose: scaled by (1, 4, 1), the normal (1, 1, 0) of
// the plane x + y = 1 becomes (1, 1/4, 0), the normal of that plane stretched (x + y / 4 = 1); then
// rotated 90 degrees about +z, (-1/4, 1, 0).
TEST(SceneJson, TransformTurnsObjNormalsByTheInverseTranspose) {
  const Scene scene = parse(with_camera(R"("meshes": [{"obj": "n.obj", "transform": {"scale": [1, 4, 1],
                                           "rotate": {"axis": [0, 0, 1], "degrees": 90}}}])"),
                            [](const std::filesystem::path&) {
                              return vkray::load_obj_text("v 1 0 0\nv 0 1 0\nv 1 0 1\nvn 1 1 0\nf 1//1 2//1 3//1\n", "n.obj");
                            });
  ASSERT_EQ(scene.meshes[0].normals.size(), 1u);
  expect_near(scene.meshes[0].normals[0], {-0.25, 1, 0});
}

TEST(SceneJson, TransformAppliesToObjMeshes) {
  std::vector<std::filesystem::path> loaded;
  const Scene scene = parse(with_camera(R"("meshes": [{"obj": "models/tri.obj", "transform": {"scale": 3, "translate": [0, 0, 1]}}])"),
                            [&](const std::filesystem::path& path) {
                              loaded.push_back(path);
                              return unit_triangle();
                            });
  ASSERT_EQ(loaded.size(), 1u);
  EXPECT_EQ(loaded[0], std::filesystem::path("/scenes/models/tri.obj"));
  ASSERT_EQ(scene.meshes.size(), 1u);
  ASSERT_EQ(scene.meshes[0].positions.size(), 3u);
  EXPECT_EQ(scene.meshes[0].positions[1], glm::dvec3(3, 0, 1));
  EXPECT_EQ(scene.meshes[0].triangles.size(), 1u);
}

TEST(SceneJson, DefaultScene) {
  const Scene scene = vkray::default_scene();
  EXPECT_EQ(scene.width, 800u);
  EXPECT_EQ(scene.height, 600u);
  EXPECT_EQ(scene.camera.from, glm::dvec3(0.0, 1.8, 6.0));
  EXPECT_EQ(scene.camera.fovy_degrees, 45.0);
  ASSERT_EQ(scene.spheres.size(), 1u);
  EXPECT_EQ(scene.spheres[0].radius, 0.9);
  ASSERT_EQ(scene.planes.size(), 1u);
  EXPECT_EQ(scene.planes[0].normal, glm::dvec3(0, 1, 0));
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.meshes[0].positions.size(), 5u);
  EXPECT_EQ(scene.meshes[0].triangles.size(), 6u);
  // The OBJ cube: 8 vertices, 6 quads -> 12 triangles, scaled by 0.7, turned 30 degrees about +y
  // and moved by (0.4, 0, -1.6).
  ASSERT_EQ(scene.meshes[1].positions.size(), 8u);
  EXPECT_EQ(scene.meshes[1].triangles.size(), 12u);
  const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
  const glm::dvec3 v(-0.7, 0.0, -0.7);  // first cube vertex (-1, 0, -1) after scaling
  expect_near(scene.meshes[1].positions[0], glm::dvec3(c * v.x + s * v.z, v.y, -s * v.x + c * v.z) + glm::dvec3(0.4, 0.0, -1.6));
  EXPECT_EQ(scene.triangle_count(), 18u);
}

// ---- Files -----------------------------------------------------------------------------------

class SceneFileTest : public vkray::test::TempDirTest {};

TEST_F(SceneFileTest, RelativeObjPathResolvesAgainstSceneFolder) {
  write("models/tri.obj", triangle_obj);
  write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  const auto scene_path = write("scene.json", with_camera(R"("meshes": [{"obj": "models/tri.obj"}, {"obj": "quad.obj",
      "transform": {"translate": [0, 0, 2]}}])"));
  const Scene scene = vkray::load_scene_file(scene_path);
  ASSERT_EQ(scene.meshes.size(), 2u);
  EXPECT_EQ(scene.meshes[0].positions.size(), 3u);
  EXPECT_EQ(scene.meshes[0].triangles.size(), 1u);
  ASSERT_EQ(scene.meshes[1].positions.size(), 4u);
  EXPECT_EQ(scene.meshes[1].triangles.size(), 2u);
  EXPECT_EQ(scene.meshes[1].positions[2], glm::dvec3(1, 1, 2));
}

TEST_F(SceneFileTest, RelativeObjPathDoesNotDependOnWorkingDirectory) {
  write("sub/tri.obj", triangle_obj);
  const auto scene_path = write("sub/scene.json", with_camera(R"("meshes": [{"obj": "tri.obj"}])"));
  const auto old_cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir_);
  const std::string message = error_of([&] { EXPECT_EQ(vkray::load_scene_file("sub/scene.json").meshes.size(), 1u); });
  std::filesystem::current_path(old_cwd);
  EXPECT_EQ(message, "");
  EXPECT_EQ(vkray::load_scene_file(scene_path).meshes.size(), 1u);
}

TEST_F(SceneFileTest, AbsoluteObjPath) {
  const auto obj = write("elsewhere/tri.obj", triangle_obj);
  const auto scene_path = write("scenes/scene.json", with_camera("\"meshes\": [{\"obj\": \"" + obj.generic_string() + "\"}]"));
  EXPECT_EQ(vkray::load_scene_file(scene_path).meshes.at(0).triangles.size(), 1u);
}

TEST_F(SceneFileTest, MissingObjFile) {
  const auto scene_path = write("scene.json", with_camera(R"("meshes": [{"obj": "tri.obj"}, {"obj": "missing.obj"}])"));
  write("tri.obj", triangle_obj);
  expect_error(error_of([&] { vkray::load_scene_file(scene_path); }), scene_path.string() + ": meshes[1].obj: ",
               (dir_ / "missing.obj").string() + ": no such OBJ file");
}

TEST_F(SceneFileTest, ObjIsADirectory) {
  std::filesystem::create_directories(dir_ / "folder.obj");
  const auto scene_path = write("scene.json", with_camera(R"("meshes": [{"obj": "folder.obj"}])"));
  expect_error(error_of([&] { vkray::load_scene_file(scene_path); }), scene_path.string() + ": meshes[0].obj: ",
               (dir_ / "folder.obj").string() + ": is not a regular file");
}

TEST_F(SceneFileTest, BadObjReportsSceneJsonPathAndObjLine) {
  write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  const auto scene_path = write("scene.json", with_camera(R"("meshes": [{"obj": "bad.obj"}])"));
  expect_error(error_of([&] { vkray::load_scene_file(scene_path); }), scene_path.string() + ": meshes[0].obj: ",
               (dir_ / "bad.obj").string() + ":4: vertex index 4 is out of range");
}

TEST_F(SceneFileTest, MissingSceneFile) {
  const auto path = dir_ / "nope.json";
  expect_error(error_of([&] { vkray::load_scene_file(path); }), path.string() + ": ", "no such scene file");
}

TEST_F(SceneFileTest, SceneFileIsADirectory) {
  expect_error(error_of([&] { vkray::load_scene_file(dir_); }), dir_.string() + ": ", "is not a regular file");
}

TEST_F(SceneFileTest, InvalidJsonInFile) {
  const auto path = write("scene.json", "{\n  \"camera\": {\"from\": [0, 0, 5], \"to\": [0, 0, 0], \"fovy\": 60},\n  \"spheres\": [,]\n}\n");
  expect_error(error_of([&] { vkray::load_scene_file(path); }), path.string() + ":3:15: ", "invalid JSON: syntax error while parsing value - unexpected ','");
}

TEST_F(SceneFileTest, ErrorInFileNamesFileAndPath) {
  const auto path = write("scene.json", with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": -2}])"));
  expect_error(error_of([&] { vkray::load_scene_file(path); }), path.string() + ": spheres[0].radius: ", "must be > 0, got -2");
}

// Scenes built in code (Python's vkray.Scene) reach check_scene with any double: a NaN in any
// coordinate is refused, not only in the first one.
TEST(CheckScene, ANanInAnyCoordinateIsRefused) {
  for (int axis = 0; axis < 3; ++axis) {
    Scene vertex = vkray::default_scene();
    vertex.meshes[0].positions[1][axis] = NAN;
    expect_error(error_of([&] { vkray::check_scene(vertex); }), "meshes[0]", "finite");
    Scene sphere = vkray::default_scene();
    sphere.spheres[0].center[axis] = NAN;
    expect_error(error_of([&] { vkray::check_scene(sphere); }), "spheres[0].center: ", "finite");
    Scene up = vkray::default_scene();
    up.camera.up[axis] = NAN;
    expect_error(error_of([&] { vkray::check_scene(up); }), "camera.up: ", "finite");
  }
}

}  // namespace

// Finite but extreme values: directions of any magnitude normalize exactly; positions and radii
// beyond the supported magnitude (float32 squares would overflow on the GPU) are refused.
TEST(SceneJson, ExtremeMagnitudes) {
  const Scene scene = parse(R"({"camera": {"from": [0, 0, 1e-170], "to": [0, 0, 0], "up": [0, 1e-300, 0], "fovy": 45},
    "planes": [{"point": [0, 0, 0], "normal": [0, 1e200, 0]}, {"point": [0, 0, 0], "normal": [3e-200, 0, 4e-200]}],
    "meshes": [{"positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]],
                "transform": {"rotate": {"axis": [0, 0, 1e-310], "degrees": 90}}}]})");
  expect_near(scene.planes[0].normal, {0, 1, 0});
  expect_near(scene.planes[1].normal, {0.6, 0, 0.8});
  expect_near(scene.meshes[0].positions[1], {0, 1, 0});
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 2e15, 0], "radius": 1}])")), "t.json: spheres[0].center[1]: ",
               "magnitude above the supported");
  expect_error(parse_error(with_camera(R"("spheres": [{"center": [0, 0, 0], "radius": 1e16}])")), "t.json: spheres[0].radius: ",
               "magnitude above the supported");
  expect_error(parse_error(with_camera(R"("meshes": [{"positions": [[0, 0, 0], [1e10, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]],
                                         "transform": {"scale": 1e10}}])")),
               "t.json: meshes[0]: ", "vertex 1 lies beyond the supported coordinate magnitude");
}

// Cameras as vision code gives them: OpenCV's intrinsics in place of fovy, its [R t] in place of
// from, to and up.
TEST(SceneJson, CameraFromIntrinsicsAndWorldToCamera) {
  const Scene scene = parse(R"({"camera": {"world_to_camera": [[1, 0, 0, 0], [0, -1, 0, 1], [0, 0, -1, 5], [0, 0, 0, 1]],
                                           "intrinsics": {"fx": 500, "fy": 510, "cx": 319.5, "cy": 240}}})");
  EXPECT_EQ(scene.camera.from, glm::dvec3(0, 1, 5));
  EXPECT_EQ(scene.camera.to, glm::dvec3(0, 1, 4));
  EXPECT_EQ(scene.camera.up, glm::dvec3(0, 1, 0));
  ASSERT_TRUE(scene.camera.intrinsics);
  EXPECT_EQ(*scene.camera.intrinsics, (vkray::PinholeIntrinsics{500, 510, 319.5, 240}));
}

TEST(SceneJson, CameraIntrinsicsAndMatrixChecks) {
  const std::string rotation = R"([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])";
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 1], "world_to_camera": )" + rotation + R"(, "fovy": 40}})"),
               "t.json: camera.world_to_camera: ", "give either world_to_camera or from, to and up, not both (from given)");
  expect_error(parse_error(R"({"camera": {"world_to_camera": [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "fovy": 40}})"),
               "t.json: camera.world_to_camera: ", "must be a rotation");
  expect_error(parse_error(R"({"camera": {"world_to_camera": [[1, 0, 0, 1e300], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "fovy": 40}})"),
               "t.json: camera.world_to_camera: ", "places the camera beyond the supported coordinate magnitude");
  expect_error(parse_error(R"({"camera": {"world_to_camera": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "fovy": 40}})"),
               "t.json: camera.world_to_camera: ", "expected 4 rows of 4 numbers");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fovy": 40,
                                          "intrinsics": {"fx": 1, "fy": 1, "cx": 0, "cy": 0}}})"),
               "t.json: camera.intrinsics: ", "give either fovy or intrinsics, not both");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0], "intrinsics": {"fx": 0, "fy": 1, "cx": 0, "cy": 0}}})"),
               "t.json: camera.intrinsics.fx: ", "focal length must be > 0 pixels");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 1], "to": [0, 0, 0], "intrinsics": {"fx": 1, "fy": 1, "cx": 0}}})"),
               "t.json: camera.intrinsics: ", "missing required key 'cy'");
}

TEST(SceneJson, OrthographicAndEquirectangularCameras) {
  const Scene ortho = parse(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "orthographic", "view_height": 3}})");
  EXPECT_EQ(ortho.camera.projection, vkray::Projection::orthographic);
  EXPECT_EQ(ortho.camera.view_height, 3.0);
  const Scene panorama = parse(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "equirectangular"}})");
  EXPECT_EQ(panorama.camera.projection, vkray::Projection::equirectangular);
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "orthographic"}})"),
               "t.json: camera: ", "an orthographic camera needs view_height");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "fisheye"}})"),
               "t.json: camera.projection: ", "unknown projection 'fisheye' (perspective, orthographic, equirectangular)");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "equirectangular", "fovy": 40}})"),
               "t.json: camera.fovy: ", "fovy describes a perspective camera");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "orthographic", "view_height": -1}})"),
               "t.json: camera.view_height: ", "must be in (0, 1e15]");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "view_height": 3}})"),
               "t.json: camera.view_height: ", "view_height describes an orthographic camera; this one is perspective");
  expect_error(parse_error(R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "projection": "equirectangular", "view_height": 3}})"),
               "t.json: camera.view_height: ", "this one is equirectangular");
}
