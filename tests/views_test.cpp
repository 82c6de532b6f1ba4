// Many views, the parts the command line builds on (engine/views): views files, output names with
// the view's index, the manifest's records and their merging, and the generated cameras.
#include "engine/scene/camera.hpp"
#include "engine/views/manifest.hpp"
#include "engine/views/output_pattern.hpp"
#include "engine/views/view_batch.hpp"
#include "engine/views/view_list.hpp"
#include "tests/input_error_test.hpp"
#include "tests/temp_dir_test.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>
#include <sstream>

namespace vkray {
namespace {

using test::error_of;
using test::expect_error;

TEST(OutputPattern, IndexPlainPaddedAndBraces) {
  EXPECT_EQ(OutputPattern("out/v{index}.exr", "-o").path(42), "out/v42.exr");
  EXPECT_EQ(OutputPattern("out/v{index:05}.exr", "-o").path(42), "out/v00042.exr");
  EXPECT_EQ(OutputPattern("v{index:02}.exr", "-o").path(1234), "v1234.exr");  // wider than the padding
  EXPECT_EQ(OutputPattern("v{index:032}.exr", "-o").path(2), "v" + std::string(31, '0') + "2.exr");
  EXPECT_EQ(OutputPattern("v{index:099}.exr", "-o").path(4'294'967'295u), "v" + std::string(89, '0') + "4294967295.exr");
  EXPECT_EQ(OutputPattern("{{x}}-{index}-{index:03}.exr", "-o").path(7), "{x}-7-007.exr");
  EXPECT_FALSE(OutputPattern("render.exr", "-o").has_index());
  EXPECT_TRUE(OutputPattern("{index}.exr", "-o").has_index());
  expect_error(error_of([] { OutputPattern("v{i}.exr", "-o"); }), "-o: ", "unknown field {i}");
  expect_error(error_of([] { OutputPattern("v{index:5}.exr", "-o"); }), "-o: ", "unknown field {index:5}");
  expect_error(error_of([] { OutputPattern("v{index.exr", "--preview"); }), "--preview: ", "no '}'");
  expect_error(error_of([] { OutputPattern("v}.exr", "-o"); }), "-o: ", "no '{'");
}

TEST(Views, JsonArrayAndJsonLines) {
  const std::string a = R"({"from": [1, 2, 3], "to": [0, 0, 0], "fovy": 30})";
  const std::string b = R"({"from": [0, 0, 5], "to": [0, 1, 0], "up": [0, 0, 1], "fovy": 60})";
  const std::string byte_order_mark = "\xEF\xBB\xBF";
  for (const std::string& text : {"[" + a + ",\n" + b + "]", a + "\n\n" + b + "\n", "\n  [\n" + a + "," + b + "\n]  \n",
                                  byte_order_mark + "[\n" + a + ",\n" + b + "\n]", byte_order_mark + a + "\n" + b}) {
    const std::vector<View> views = parse_views(text, "views");
    ASSERT_EQ(views.size(), 2u) << text;
    EXPECT_EQ(views[0].camera.from, glm::dvec3(1, 2, 3));
    EXPECT_EQ(views[1].camera.up, glm::dvec3(0, 0, 1));
    EXPECT_EQ(views[1].camera.fovy_degrees, 60.0);
    EXPECT_TRUE(views[0].poses.empty() && views[1].poses.empty());
  }
}

TEST(Views, ErrorsNameTheLine) {
  const std::string good = R"({"from": [1, 2, 3], "to": [0, 0, 0], "fovy": 30})";
  expect_error(error_of([&] { parse_views(good + "\n" + R"({"from": [1, 2, 3], "fovy": 30})" + "\n", "v.jsonl"); }),
               "v.jsonl:2: ", "missing required key 'to'");
  expect_error(error_of([&] { parse_views("[\n" + good + ",\n\n 5\n]", "v.json"); }), "v.json:4: ", "expected an object");
  expect_error(error_of([&] { parse_views("[\n" + good + ",\n" + R"({"from": [1, 2, 3], "to": [1, 2, 3], "fovy": 30})" + "]", "v.json"); }),
               "v.json:3: ", "must differ");
  expect_error(error_of([&] { parse_views("[\n" + good + ",\n" + good, "v.json"); }), "v.json:", "invalid JSON");
  expect_error(error_of([&] { parse_views(good + "\n{\"from\": [1,\n", "v.jsonl"); }), "v.jsonl:2:13: ", "invalid JSON: syntax error");
  expect_error(error_of([] { parse_views("[]", "v.json"); }), "v.json: ", "no cameras");
  expect_error(error_of([&] { parse_views("[\n" + good + "]" + std::string(1, '\0') + "junk", "v.json"); }), "v.json:2:",
               "a NUL byte");  // nlohmann would stop at it, silently
  expect_error(error_of([] { parse_views("\n\n", "v.jsonl"); }), "v.jsonl: ", "no cameras");
  expect_error(error_of([] { load_views("/nonexistent/views.json"); }), "/nonexistent/views.json", "no such views file");
}

TEST(Views, AMillionCamerasInAnArrayAreReadInOnePass) {
  // Each element's line comes from the walk that finds the elements. Counted from the file's start
  // for each camera instead, 100k cameras took 52.8 s and a million would outlast ctest's timeout.
  const std::string good = R"({"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 30})";
  std::string text = "[\n";
  for (int k = 0; k < 999'999; ++k) text += good + ",\n";
  text += R"({"from": [0, 0, 5], "to": [0, 0, 5], "fovy": 30})" "\n]";
  expect_error(error_of([&] { parse_views(text, "v.json"); }), "v.json:1000001: ", "must differ");
}

TEST(Views, OrbitKeepsDistanceHeightAndFirstView) {
  Camera start;
  start.from = {3, 2, 4};
  start.to = {1, 1, 1};
  start.up = {0, 2, 0};
  start.fovy_degrees = 33;
  const std::vector<View> views = orbit_views(start, 8);
  ASSERT_EQ(views.size(), 8u);
  EXPECT_EQ(views[0].camera.from, start.from);
  for (const auto& [view, poses, source] : views) {
    EXPECT_NEAR(glm::length(view.from - view.to), glm::length(start.from - start.to), 1e-12);
    EXPECT_NEAR(view.from.y, start.from.y, 1e-12);
    EXPECT_EQ(view.to, start.to);
    EXPECT_EQ(view.fovy_degrees, 33.0);
  }
  // Half way round: the opposite side.
  EXPECT_NEAR(glm::length((views[4].camera.from - start.to) + (start.from - start.to) * glm::dvec3(1, 0, 1) -
                          glm::dvec3(0, start.from.y - start.to.y, 0)),
              0.0, 1e-12);
}

TEST(Views, SphereViewsFromAStraightDownCamera) {
  Camera start;  // looking along up: the lattice needs a side of its own
  start.from = {0, 5, 0};
  start.to = {0, 0, 0};
  const std::vector<View> views = sphere_views(start, 7);
  for (const auto& [view, poses, source] : views) {
    EXPECT_NEAR(glm::length(view.from), 5.0, 1e-12);
    EXPECT_TRUE(std::isfinite(make_camera_basis(view, 8, 8).right.x));
  }
}

// A view places instances by the scene file's transform objects; what it places is checked against
// the scene before any view renders, each error naming the view's line and entry.
TEST(Views, AViewPlacesInstancesAndEachErrorNamesItsLine) {
  const std::string camera = R"("from": [0, 1, 5], "to": [0, 0, 0], "fovy": 40)";
  const std::string text = "{" + camera + "}\n{" + camera + R"(, "instances": [{"instance": 1, "transform": {"scale": 2, "translate": [1, 2, 3]}}, )"
                           R"({"instance": 0, "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 90}}}]})" "\n";
  const std::vector<View> views = parse_views(text, "v.jsonl");
  ASSERT_EQ(views.size(), 2u);
  EXPECT_TRUE(views[0].poses.empty());
  ASSERT_EQ(views[1].poses.instances, (std::vector<uint32_t>{1, 0}));
  EXPECT_EQ(views[1].source, "v.jsonl:2");
  const glm::dmat4& scaled = views[1].poses.transforms[0];
  EXPECT_EQ(scaled, glm::dmat4(glm::dvec4(2, 0, 0, 0), glm::dvec4(0, 2, 0, 0), glm::dvec4(0, 0, 2, 0), glm::dvec4(1, 2, 3, 1)));
  const glm::dvec4 turned_x = views[1].poses.transforms[1] * glm::dvec4(1, 0, 0, 1);  // +x turned 90 degrees about +y: -z
  EXPECT_NEAR(glm::length(glm::dvec3(turned_x) - glm::dvec3(0, 0, -1)), 0.0, 1e-15);

  Scene scene;
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  mesh.instanced = true;
  scene.meshes.push_back(mesh);
  scene.instances = {Instance{}, Instance{}};
  check_view_poses(views, scene);
  const auto view_of = [&](const std::string& instances) {
    return parse_views("{" + camera + ", \"instances\": " + instances + "}", "v.jsonl");
  };
  expect_error(error_of([&] { check_view_poses(view_of(R"([{"instance": 2, "transform": {}}])"), scene); }),
               "v.jsonl:1: instances[0].instance: ", "2 is not an instance of the scene's 2 (0..1)");
  expect_error(error_of([&] { check_view_poses(view_of(R"([{"instance": 1, "transform": {}}, {"instance": 1, "transform": {}}])"), scene); }),
               "v.jsonl:1: instances[1].instance: ", "placed twice");
  expect_error(error_of([&] { check_view_poses(view_of(R"([{"instance": 0, "transform": {"translate": [1e16, 0, 0]}}])"), scene); }),
               "v.jsonl:1: instances[0].transform", "within 1e15");
  expect_error(error_of([&] { parse_views("{" + camera + R"(, "instances": [{"instance": 0}]})", "v.jsonl"); }), "v.jsonl:1: instances[0]: ",
               "missing required key 'transform'");
  expect_error(error_of([&] { parse_views("{" + camera + R"(, "instances": [{"instance": 0, "transform": {"scale": 0}}]})", "v.jsonl"); }),
               "v.jsonl:1: instances[0].transform.scale: ", "non-zero");
  expect_error(error_of([&] { parse_views("{" + camera + R"(, "instances": [{"instance": -1, "transform": {}}]})", "v.jsonl"); }),
               "v.jsonl:1: instances[0].instance: ", "out of range");
  scene.instances.clear();
  expect_error(error_of([&] { check_view_poses(views, scene); }), "v.jsonl:2: instances[0].instance: ", "(it places none)");
}

// Frame::bytes is what allocate() gives, for every output the table has, in float and in double.
TEST(ViewBatch, AFramesBytesAreWhatItsPlanesHold) {
  for (bool doubles : {false, true}) {
    AovSet every;
    for (const OutputInfo& output : outputs()) every.add(output.aov);
    for (AovSet aovs : {AovSet{Aov::depth}, AovSet{Aov::depth, Aov::normal}, AovSet{Aov::barycentric}, every}) {
      Frame frame(7, 5, aovs);
      frame.allocate(doubles);
      size_t held = (frame.depth64.size() + frame.normal64.size()) * sizeof(double);
      for (const OutputInfo& output : outputs()) {
        if (output.floats) held += (frame.*output.floats).size() * sizeof(float);
        if (output.integers) held += (frame.*output.integers).size() * sizeof(uint32_t);
      }
      EXPECT_EQ(Frame::bytes(7, 5, aovs, doubles), held) << aovs.names() << (doubles ? " in double" : "");
    }
  }
}

// One writer a host thread while 3 w + 2 frames fit in a quarter of the memory; one at least.
TEST(ViewBatch, WritersAreOneAThreadWhileAQuarterOfTheMemoryHoldsTheirFrames) {
  const uint64_t frame_1080p = Frame::bytes(1920, 1080, {Aov::depth, Aov::normal}, false);
  EXPECT_EQ(frame_1080p, 1920ull * 1080 * 4 * sizeof(float));
  EXPECT_EQ(writer_threads(16, frame_1080p, 128ull << 30), 16u);  // 1035 frames fit: the threads bound it
  EXPECT_EQ(writer_threads(2, frame_1080p, 128ull << 30), 2u);
  const uint64_t frame_8k = Frame::bytes(7680, 4320, {Aov::depth, Aov::normal}, false);  // 531 MB
  EXPECT_EQ(writer_threads(16, frame_8k, 16ull << 30), 2u);  // 4 GiB holds 8 frames: (8 - 2) / 3
  EXPECT_EQ(writer_threads(16, frame_8k, 8ull << 30), 1u);   // 4 frames: none by the formula, one still
  EXPECT_EQ(writer_threads(0, frame_1080p, 128ull << 30), 1u);  // hardware_concurrency() may say 0
  EXPECT_EQ(writer_threads(4, frame_1080p, 0), 1u);             // and sysconf nothing
}

TEST(Camera, PinholeModelProjectsEachPixelsRayOntoItsPixel) {
  Camera camera;
  camera.from = {1, 2, 3};
  camera.to = {-2, 0.5, -1};
  camera.up = {0.1, 1, 0};
  camera.fovy_degrees = 50;
  for (const auto& [width, height] : {std::pair{64u, 48u}, {30u, 70u}}) {
    const CameraBasis basis = make_camera_basis(camera, width, height);
    const PinholeIntrinsics k = pinhole_intrinsics(camera, width, height);
    const auto rt = world_to_camera(camera, width, height);
    for (const auto& [i, j] : {std::pair{0u, 0u}, {width - 1, 0u}, {5u, height - 1}, {width / 2, height / 3}}) {
      const glm::dvec3 p = camera.from + 7.5 * basis.direction(pixel_uv(i, j, width, height));
      double c[3];
      for (int r = 0; r < 3; ++r) c[r] = rt[r][0] * p.x + rt[r][1] * p.y + rt[r][2] * p.z + rt[r][3];
      EXPECT_NEAR(k.fx * c[0] / c[2] + k.cx, i, 1e-9);
      EXPECT_NEAR(k.fy * c[1] / c[2] + k.cy, j, 1e-9);
      EXPECT_GT(c[2], 0.0);  // in front
    }
  }
}

class ManifestTest : public test::TempDirTest {};

ViewRecord record(uint32_t index, const std::filesystem::path& folder) {
  ViewRecord view;
  view.index = index;
  view.views = 3;
  view.exr = folder / ("v" + std::to_string(index) + ".exr");
  view.camera.from = {0, 0, 5.0 + index};
  view.width = 8;
  view.height = 6;
  return view;
}

std::string read(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

class ViewsFileTest : public test::TempDirTest {};

// JSON Lines are read and checked a line at a time: a fault on line 2 of a 64 GB file (a hole after
// it, which takes no disk) is reported there, where reading the whole file first ran out of memory.
TEST_F(ViewsFileTest, AFaultEarlyInHugeJsonLinesIsFoundWithoutReadingTheRest) {
  const auto path = write("huge.jsonl", "{\"from\": [0, 1, 5], \"to\": [0, 0, 0], \"fovy\": 40}\n{\"from\": [0, 1, 5]}\n");
  std::filesystem::resize_file(path, uintmax_t{64} << 30);
  expect_error(error_of([&] { load_views(path); }), path.string() + ":2: ", "missing required key 'to'");
}

// A JSON array is parsed whole, so one past 1 GiB is refused before a byte of it is read.
TEST_F(ViewsFileTest, AJsonArrayOverAGibibyteIsRefusedUnread) {
  const auto path = write("huge.json", "\xEF\xBB\xBF\n [{\"from\": [0, 1, 5], \"to\": [0, 0, 0], \"fovy\": 40},\n");
  std::filesystem::resize_file(path, (uintmax_t{1} << 30) + 1);
  expect_error(error_of([&] { load_views(path); }), path.string() + ": ", "write the cameras one a line (JSON Lines)");
  std::filesystem::resize_file(path, 200);  // the same start and a hole, below the limit: read, and refused
  expect_error(error_of([&] { load_views(path); }), path.string() + ":3:", "a NUL byte");
}

TEST_F(ManifestTest, ACutOffLastLineIsDroppedAndWritingGoesOn) {
  const auto path = dir_ / "manifest.jsonl";
  {
    ManifestWriter manifest(path, true);
    manifest.append(record(0, dir_));
    manifest.append(record(1, dir_));
  }
  const std::string whole = read(path);
  EXPECT_EQ(manifest_line_index(whole.substr(0, whole.find('\n'))), 0u);
  std::ofstream(path, std::ios::app) << manifest_line(record(2, dir_), dir_).substr(0, 30);  // killed mid-line
  {
    ManifestWriter manifest(path, false);
    EXPECT_TRUE(manifest.recorded(0) && manifest.recorded(1));
    EXPECT_FALSE(manifest.recorded(2));
    manifest.append(record(2, dir_));
  }
  EXPECT_EQ(read(path), whole + manifest_line(record(2, dir_), dir_) + "\n");
  EXPECT_NE(read(path).find("\"exr\":\"v2.exr\""), std::string::npos);  // relative to the manifest's folder
  ManifestWriter fresh(path, true);
  EXPECT_FALSE(fresh.recorded(0));
  EXPECT_EQ(read(path), "");
}

// A view's placed instances are recorded as 4 rows of 4 (the dataset's object poses), and a record
// with other poses, or none, is a change a resumed run refuses.
TEST_F(ManifestTest, PlacedInstancesAreRecordedAndTheirChangeCounts) {
  ViewRecord posed = record(0, dir_);
  posed.poses.instances = {3};
  glm::dmat4 transform(2.0);
  transform[3] = glm::dvec4(5.0, 6.0, 7.0, 1.0);
  posed.poses.transforms = {transform};
  const std::string line = manifest_line(posed, dir_);
  EXPECT_NE(line.find(R"("instances":[{"instance":3,"transform":[[2.0,0.0,0.0,5.0],[0.0,2.0,0.0,6.0],[0.0,0.0,2.0,7.0],[0.0,0.0,0.0,1.0]]}])"),
            std::string::npos) << line;
  EXPECT_EQ(manifest_line_index(line), 0u);
  EXPECT_EQ(record_changes(line, line), "");
  EXPECT_EQ(record_changes(line, manifest_line(record(0, dir_), dir_)), "the instances placed");
  posed.poses.transforms[0][3].x = 5.5;
  EXPECT_EQ(record_changes(line, manifest_line(posed, dir_)), "the instances placed");
}

// The default many-view run: `manifest.jsonl` and `view-00000.exr`, names without a folder.
TEST_F(ManifestTest, NamesWithoutAFolderAreTheWorkingFolders) {
  EXPECT_NE(manifest_line(record(0, ""), "").find("\"exr\":\"v0.exr\""), std::string::npos);
}

TEST_F(ManifestTest, AFileThatIsNotAManifestIsRefusedAndLeftAlone) {
  for (const std::string text : {"v 0 0 0\nv 1 0 0\n", "{\"from\": [0, 0, 5], \"to\": [0, 0, 0]}\n", "no newline"}) {
    const auto path = write("cams.jsonl", text);
    for (const bool fresh : {false, true}) {
      expect_error(error_of([&] { ManifestWriter manifest(path, fresh); }), path.string() + ": ",
                   "is not a manifest (its first line is no view record)");
      EXPECT_EQ(read(path), text);
    }
  }
  const auto fifo = dir_ / "fifo";  // opened, it would block until a writer came
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_error(error_of([&] { ManifestWriter manifest(fifo, true); }), fifo.string() + ": ", "not a regular file");
  // A first record cut off by a kill is a manifest still: the cut line goes, the run goes on.
  const auto cut = write("cut.jsonl", manifest_line(record(0, dir_), dir_).substr(0, 30));
  EXPECT_FALSE(ManifestWriter(cut, false).recorded(0));
  EXPECT_EQ(read(cut), "");
}

TEST_F(ManifestTest, ALineNestedTooDeepIsNoRecordAndNoCrash) {
  const std::string deep = R"({"index": 0, "exr": "v0.exr", "x": )" + std::string(200'000, '[') + std::string(200'000, ']') + "}";
  EXPECT_FALSE(manifest_line_index(deep));
  const auto path = write("deep.jsonl", deep + "\n");
  expect_error(error_of([&] { merge_manifests({path}, dir_ / "merged.jsonl"); }), path.string() + ":1: ", "not a view record");
  ViewRecord brackets = record(0, dir_);
  brackets.exr = dir_ / "[[[[[[[[[[[[.exr";  // inside a string: no nesting
  EXPECT_EQ(manifest_line_index(manifest_line(brackets, dir_)), 0u);
}

TEST_F(ManifestTest, MergeSortsJoinsCopiesAndRefusesConflicts) {
  const auto a = write("a.jsonl", manifest_line(record(2, dir_), dir_) + "\n" + manifest_line(record(0, dir_), dir_) + "\n");
  const auto b = write("b.jsonl", manifest_line(record(1, dir_), dir_) + "\n" + manifest_line(record(2, dir_), dir_) + "\n");
  EXPECT_EQ(merge_manifests({a, b}, dir_ / "merged.jsonl"), manifest_line(record(0, dir_), dir_) + "\n" + manifest_line(record(1, dir_), dir_) +
                                         "\n" + manifest_line(record(2, dir_), dir_) + "\n");
  ViewRecord other = record(1, dir_);
  other.camera.fovy_degrees = 10;
  const auto c = write("c.jsonl", "\n" + manifest_line(other, dir_) + "\n");
  expect_error(error_of([&] { merge_manifests({a, b, c}, dir_ / "merged.jsonl"); }), c.string() + ":2: ", "differs from its record at " + b.string() + ":1");
  const auto d = write("d.jsonl", "{\"index\": 3}\n");
  expect_error(error_of([&] { merge_manifests({d}, dir_ / "merged.jsonl"); }), d.string() + ":1: ", "not a view record");
  // An index past uint32 is no view's (it was cut to its low bits: "view 0 differs").
  const std::string line = manifest_line(record(0, dir_), dir_);
  const auto e = write("e.jsonl", "{\"index\":4294967296" + line.substr(line.find(',')) + "\n");
  expect_error(error_of([&] { merge_manifests({a, e}, dir_ / "merged.jsonl"); }), e.string() + ":1: ", "not a view record");
  expect_error(error_of([&] { merge_manifests({dir_}, dir_ / "merged.jsonl"); }), dir_.string() + ": ", "is a folder, not a manifest");
}

}  // namespace
}  // namespace vkray
