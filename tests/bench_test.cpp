// The bench's figures: error metrics on synthetic image pairs with known answers, the Pareto front,
// the report's JSON (round trip, errors), CSV and comparison, scene hashes and suites. Host only.
#include "engine/bench/accuracy_report.hpp"
#include "engine/bench/bench_report.hpp"
#include "engine/reference/reference.hpp"
#include "tests/temp_dir_test.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

namespace vkray {
namespace {

constexpr uint32_t side = 4;
constexpr size_t pixels = side * side;
constexpr double true_depth = 2.0;

// Reference: every pixel hits at depth 2 with normal +z.
std::vector<ReferenceHit> reference_hits() {
  std::vector<ReferenceHit> hits(pixels);
  for (auto& hit : hits) hit = {true_depth, {0.0, 0.0, 1.0}, PrimitiveKind::sphere, 0};
  return hits;
}

// A frame equal to the reference, in float.
Frame matching_frame() {
  Frame frame(side, side, {Aov::depth, Aov::normal});
  frame.allocate();
  for (size_t p = 0; p < pixels; ++p) {
    frame.depth[p] = static_cast<float>(true_depth);
    frame.normal[2 * pixels + p] = 1.0f;
  }
  return frame;
}

void set_normal(Frame& frame, size_t p, double x, double y, double z) {
  frame.normal[p] = static_cast<float>(x);
  frame.normal[pixels + p] = static_cast<float>(y);
  frame.normal[2 * pixels + p] = static_cast<float>(z);
}

TEST(BenchErrorMetrics, IdenticalImagesHaveNoError) {
  const FrameError error = measure_error(matching_frame(), reference_hits());
  EXPECT_EQ(error.pixels, pixels);
  EXPECT_EQ(error.hit_mismatches, 0u);
  EXPECT_EQ(error.both_hit, pixels);
  EXPECT_EQ(error.depth_max, 0.0);
  EXPECT_EQ(error.normal_deg_max, 0.0);
}

TEST(BenchErrorMetrics, OneFlippedPixelIsOneMismatchAndLeavesTheRestAlone) {
  Frame frame = matching_frame();
  frame.depth[5] = std::numeric_limits<float>::infinity();
  set_normal(frame, 5, 0, 0, 0);
  FrameError error = measure_error(frame, reference_hits());
  EXPECT_EQ(error.hit_mismatches, 1u);
  EXPECT_EQ(error.both_hit, pixels - 1);
  EXPECT_EQ(error.depth_max, 0.0);

  // The other way: the reference misses a pixel the frame hits.
  std::vector<ReferenceHit> reference = reference_hits();
  reference[9] = ReferenceHit{};
  error = measure_error(matching_frame(), reference);
  EXPECT_EQ(error.hit_mismatches, 1u);
  EXPECT_EQ(error.both_hit, pixels - 1);
}

TEST(BenchErrorMetrics, KnownDepthOffsetGivesItsRelativeError) {
  // 2 + 2^-10 is exact in float: the relative error is exactly 2^-11 on every pixel.
  Frame frame = matching_frame();
  for (auto& depth : frame.depth) depth = 2.0f + 0x1p-10f;
  FrameError error = measure_error(frame, reference_hits());
  EXPECT_EQ(error.depth_p50, 0x1p-11);
  EXPECT_EQ(error.depth_p99, 0x1p-11);
  EXPECT_EQ(error.depth_max, 0x1p-11);

  // One pixel in 16 off by 2^-8 (relative): the median and the 99th percentile by nearest rank
  // (rank ceil(0.99 * 16) = 16, the largest) see it differently.
  frame = matching_frame();
  frame.depth[3] = 2.0f + 0x1p-7f;
  error = measure_error(frame, reference_hits());
  EXPECT_EQ(error.depth_p50, 0.0);
  EXPECT_EQ(error.depth_p99, 0x1p-8);
  EXPECT_EQ(error.depth_max, 0x1p-8);
}

TEST(BenchErrorMetrics, NormalRotatedByKnownAngle) {
  // Half the pixels' normals turned by 1 degree about y, the rest by 0.25 degrees about x.
  Frame frame = matching_frame();
  const double one_degree = std::numbers::pi / 180.0;
  for (size_t p = 0; p < pixels; ++p) {
    const double angle = p % 2 ? one_degree : 0.25 * one_degree;
    if (p % 2) {
      set_normal(frame, p, std::sin(angle), 0, std::cos(angle));
    } else {
      set_normal(frame, p, 0, std::sin(angle), std::cos(angle));
    }
  }
  const FrameError error = measure_error(frame, reference_hits());
  // Float rounding of the rotated normal moves its angle by at most about 2^-24 rad = 3.4e-6 deg.
  EXPECT_NEAR(error.normal_deg_p50, 0.25, 1e-5);
  EXPECT_NEAR(error.normal_deg_p99, 1.0, 1e-5);
  EXPECT_NEAR(error.normal_deg_max, 1.0, 1e-5);
  EXPECT_EQ(error.depth_max, 0.0);
}

// A row whose frames all took `ms`, or spread from `fastest` to `slowest` about it.
BenchRow row(const char* variant, double ms, size_t flips, double depth_p99, double normal_p99, double fastest = 0.0,
             double slowest = 0.0) {
  BenchRow result;
  result.variant = variant;
  result.gpu = time_stats({ms, fastest > 0.0 ? fastest : ms, slowest > 0.0 ? slowest : ms});
  result.error.hit_mismatches = flips;
  result.error.depth_p99 = depth_p99;
  result.error.normal_deg_p99 = normal_p99;
  return result;
}

TEST(BenchParetoFront, KeepsExactlyTheUndominatedRows) {
  std::vector<BenchRow> rows = {
      row("accurate", 10, 0, 1e-7, 1e-4),
      row("fast", 5, 0, 1e-5, 1e-4),
      row("slower-same-error", 12, 0, 1e-7, 1e-4),  // dominated by accurate
      row("fast-but-flips", 5, 3, 1e-5, 1e-4),      // dominated by fast
      row("best-normals", 20, 0, 1e-7, 1e-6),       // slowest, but no one has better normals
      row("tie-a", 7, 0, 1e-6, 1e-4),
      row("tie-b", 7, 0, 1e-6, 1e-4),  // equal rows do not dominate each other
  };
  mark_pareto_front(rows);
  const std::vector<bool> expected = {true, true, false, false, true, true, true};
  for (size_t k = 0; k < rows.size(); ++k) EXPECT_EQ(rows[k].pareto, expected[k]) << rows[k].variant;
}

// Under load one variant's frames spread widely: a median that looks faster is no win where the
// spreads overlap (issue 33: "+position", more work than default, showed 0.67x the time and took
// default's place on the front).
// Rounds pool a row's frames: the median, minimum and maximum of all of them, not of one round.
TEST(BenchStatistics, PooledRoundsGiveTheStatisticsOfEveryFrame) {
  const TimeStats first = time_stats({9.0, 8.0, 30.0}), second = time_stats({7.5, 10.0});
  const TimeStats both = pooled_time_stats(first, second);
  EXPECT_EQ(both.min_ms, 7.5);
  EXPECT_EQ(both.max_ms, 30.0);
  EXPECT_EQ(both.median_ms, 9.0);
  EXPECT_EQ(both.samples_ms.size(), 5u);
  EXPECT_EQ(pooled_time_stats(TimeStats{}, second).median_ms, second.median_ms);
}

TEST(BenchParetoFront, OverlappingSpreadsAreATieNotAWin) {
  std::vector<BenchRow> rows = {
      row("default", 12, 0, 1e-7, 1e-4, 8, 15),
      row("+position", 8, 0, 1e-7, 1e-4, 7.5, 13),  // overlaps default: neither is faster
      row("clearly-slower", 30, 0, 1e-7, 1e-4, 25, 35),  // its fastest frame is slower than their slowest
  };
  mark_pareto_front(rows);
  EXPECT_TRUE(rows[0].pareto);
  EXPECT_TRUE(rows[1].pareto);
  EXPECT_FALSE(rows[2].pareto);
  BenchSceneResult scene;
  scene.name = "built-in";
  scene.rows = rows;
  const std::string text = bench_table_rows(scene, false);
  const size_t position = text.find("+position          0.67x time alike ");
  ASSERT_NE(position, std::string::npos) << text;
  EXPECT_EQ(text.find("alike"), position + 30) << text;  // only there
  EXPECT_EQ(text.find("alike", position + 31), std::string::npos) << text;
  EXPECT_NE(text.find(" 7.50-13.00 "), std::string::npos) << text;  // the spread, in the table
}

// A report with every field set to a distinct value.
BenchReport sample_report() {
  BenchReport report;
  report.vkray_version = "1.2.3";
  report.git_commit = "0123456789abcdef";
  report.device = "Some GPU, \"quoted\"";
  report.device_type = "discrete";
  report.driver = "driver 1";
  report.api_version = "1.3.0";
  report.suite = "basic";
  report.frames = 7;
  BenchSceneResult scene;
  scene.name = "scene one";
  scene.hash = "00000000deadbeef";
  scene.width = 64;
  scene.height = 48;
  scene.triangles = 12;
  scene.spheres = 3;
  scene.planes = 1;
  scene.reference_ms = 4.5;
  scene.skipped = {"naive-sphere (does not apply)"};
  BenchRow gpu = row("default", 2.5, 1, 3e-7, 2e-5);
  gpu.stats.triangles = 12;
  gpu.stats.geometry_bytes = 1234;
  gpu.stats.bvh_nodes = 5;
  gpu.stats.bvh_depth = 3;
  gpu.stats.loop_budget = 65000;
  gpu.upload_ms = 0.5;
  gpu.bvh_build_ms = 0.25;
  gpu.pipeline_ms = 30.125;
  gpu.gpu.min_ms = 2.25;
  gpu.frame_median_ms = 3.5;
  gpu.mrays_per_s = 64 * 48 / 2.5e3;
  gpu.unfinished_rays = 2;
  gpu.error.pixels = 64 * 48;
  gpu.error.both_hit = 1000;
  gpu.error.depth_p50 = 1e-8;
  gpu.error.depth_max = 4e-6;
  gpu.error.normal_deg_p50 = 1e-6;
  gpu.error.normal_deg_max = 0.125;
  gpu.pareto = true;
  BenchRow cpu = row("embree-8", 1.5, 0, 2e-7, 3e-4);
  cpu.on_gpu = false;
  scene.rows = {gpu, cpu};
  report.scenes = {scene};
  return report;
}

class BenchReportTest : public test::TempDirTest {};

TEST_F(BenchReportTest, JsonRoundTripKeepsEveryField) {
  const BenchReport report = sample_report();
  const std::string json = bench_json(report);
  const auto path = write("bench.json", json);
  const BenchReport read = read_bench_json(path);
  EXPECT_EQ(bench_json(read), json);
  EXPECT_EQ(bench_csv(read), bench_csv(report));
  EXPECT_NE(json.find("\"schema\": \"vkray-bench-1\""), std::string::npos) << json;
}

TEST_F(BenchReportTest, BadJsonNamesTheFileAndTheField) {
  const auto not_json = write("not.json", "{ nope");
  try {
    read_bench_json(not_json);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(not_json.string()), std::string::npos) << error.what();
  }
  const auto other = write("other.json", R"({"camera": {}})");
  EXPECT_THROW(read_bench_json(other), InputError);

  std::string json = bench_json(sample_report());
  const size_t field = json.find("\"gpu_median_ms\"");
  json.replace(field, std::string("\"gpu_median_ms\"").size(), "\"gpu_median\"");
  try {
    read_bench_json(write("missing.json", json));
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("scenes[0].rows[0].gpu_median_ms"), std::string::npos) << error.what();
  }
  EXPECT_THROW(read_bench_json(dir_ / "absent.json"), InputError);
}

TEST(BenchReport, CsvHasAHeaderAndALinePerRowWithEveryJsonField) {
  const BenchReport report = sample_report();
  const std::string csv = bench_csv(report);
  std::istringstream lines(csv);
  std::string header, line;
  std::getline(lines, header);
  size_t rows = 0;
  const size_t columns = static_cast<size_t>(std::count(header.begin(), header.end(), ',')) + 1;
  while (std::getline(lines, line)) {
    ++rows;
    // The device name holds a comma and quotes, written as "Some GPU, ""quoted""": one comma in a cell.
    EXPECT_EQ(static_cast<size_t>(std::count(line.begin(), line.end(), ',')), columns) << line;
  }
  EXPECT_EQ(rows, 2u);
  for (const char* field : {"scene_hash", "variant", "gpu_median_ms", "frame_median_ms", "mrays_per_s",
                            "hit_mismatches", "depth_rel_p99", "normal_deg_max", "pareto"}) {
    EXPECT_NE(header.find(field), std::string::npos) << field;
  }
}

TEST(BenchReport, CompareGivesRatiosPerMatchingRow) {
  const BenchReport before = sample_report();
  BenchReport after = sample_report();
  after.scenes[0].rows[0].gpu.median_ms *= 2.0;     // twice the time
  after.scenes[0].rows[0].error.depth_p99 *= 0.5;   // half the error
  const std::string text = compare_bench(before, after);
  EXPECT_NE(text.find("2.000"), std::string::npos) << text;
  EXPECT_NE(text.find("0.500"), std::string::npos) << text;
  EXPECT_EQ(text.find("not compared"), std::string::npos) << text;
  after.scenes[0].name = "another scene";
  EXPECT_NE(compare_bench(before, after).find("no row in common"), std::string::npos);
}

// Two different meshes that share a file name (both "mesh.obj") are two scenes: their hashes
// differ, so no row pairs, and both are named as left out.
TEST(BenchReport, CompareNeverPairsScenesWhoseHashesDiffer) {
  BenchReport before = sample_report();
  BenchReport after = sample_report();
  before.scenes[0].name = after.scenes[0].name = "mesh.obj";
  after.scenes[0].hash = "ffffffffffffffff";
  const std::string text = compare_bench(before, after);
  EXPECT_NE(text.find("no row in common"), std::string::npos) << text;
  EXPECT_NE(text.find("not compared, only in A: mesh.obj (64x48, hash 00000000deadbeef)"), std::string::npos) << text;
  EXPECT_NE(text.find("not compared, only in B: mesh.obj (64x48, hash ffffffffffffffff)"), std::string::npos) << text;
  // A variant only one side ran is named too.
  after = sample_report();
  after.scenes[0].name = "mesh.obj";
  after.scenes[0].rows.pop_back();
  EXPECT_NE(compare_bench(before, after).find("not compared, only in A: mesh.obj embree-8"), std::string::npos);
}

// The summary under a scene's rows follows the Pareto front: a fast row with a large error is shown
// with that error beside its time, against the default, never as "the fastest" alone.
TEST(BenchReport, SummaryListsTheParetoFrontWithTheErrorOfEachRow) {
  BenchSceneResult scene;
  scene.name = "built-in";
  scene.rows = {row("default", 10.0, 0, 1e-6, 0.05), row("naive", 8.0, 12, 1.1, 170.0), row("generic", 20.0, 0, 1e-6, 0.05),
                row("embree-8", 5.0, 3, 2e-7, 179.0)};
  scene.rows[3].on_gpu = false;
  mark_pareto_front(scene.rows);
  const std::string text = bench_table_rows(scene, false);
  EXPECT_EQ(text.find("fastest"), text.find("fastest first")) << text;
  const size_t front = text.find("built-in: Pareto front, fastest first; time against default");
  ASSERT_NE(front, std::string::npos) << text;
  const std::string summary = text.substr(front);
  const size_t embree = summary.find("embree-8"), naive = summary.find("naive"), ours = summary.find("  default");
  ASSERT_TRUE(embree != std::string::npos && naive != std::string::npos && ours != std::string::npos) << summary;
  EXPECT_TRUE(embree < naive && naive < ours) << summary;  // fastest first
  EXPECT_EQ(summary.find("generic"), std::string::npos) << summary;  // dominated by default
  EXPECT_NE(summary.find("naive              0.80x time            12 flips  depth p99 1.10e+00"), std::string::npos)
      << summary;
  EXPECT_NE(summary.find("default            1.00x time             0 flips  depth p99 1.00e-06"), std::string::npos)
      << summary;
}

// The default table fits 100 columns, with its legend above the header, not between it and the rows.
TEST(BenchReport, NarrowTableFitsOneHundredColumns) {
  const BenchReport report = sample_report();
  BenchSceneResult scene = report.scenes[0];
  scene.name = "a-model-with-a-long-file-name-from-a-dataset.obj";
  const std::string table = bench_table_legend(false) + bench_table_header(false) + bench_table_rows(scene, false);
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) EXPECT_LE(line.size(), 100u) << line;
  EXPECT_NE(table.find("\n...m-a-dataset.obj default *"), std::string::npos) << table;  // its end tells models apart
  const std::string wide = bench_table_header(true) + bench_table_rows(scene, true);
  EXPECT_NE(wide.find("depth max"), std::string::npos);
  EXPECT_NE(wide.find(scene.name), std::string::npos);
}

TEST(BenchScenes, HashesAreDeterministicAndSeeEveryBit) {
  for (const BenchSceneSet scenes : {BenchSceneSet{basic_scenes}, BenchSceneSet{stiff_scenes}}) {
    const auto first = scenes(64, 48, {}, nullptr);
    const auto second = scenes(64, 48, {}, nullptr);
    ASSERT_EQ(first.size(), second.size());
    ASSERT_FALSE(first.empty());
    for (size_t k = 0; k < first.size(); ++k) {
      EXPECT_EQ(first[k].name, second[k].name);
      EXPECT_EQ(scene_hash(first[k].scene), scene_hash(second[k].scene)) << first[k].name;
    }
  }
  Scene scene = basic_scenes(64, 48)[0].scene;
  const std::string hash = scene_hash(scene);
  scene.spheres[0].radius = std::nextafter(scene.spheres[0].radius, 2.0);
  EXPECT_NE(scene_hash(scene), hash);
  scene = basic_scenes(64, 48)[0].scene;
  scene.width = 65;
  EXPECT_NE(scene_hash(scene), hash);
}

// The accuracy document judges each stiff case on the default row, on top of what the float32 ray
// alone costs, and names the command that made it.
TEST(AccuracyMarkdown, JudgesTheGoalsOnTopOfTheFloat32RayAndNamesTheCommand) {
  BenchReport report;
  auto stiff_scene = [](const char* name, double ulps, double ray_ulps) {
    BenchSceneResult scene;
    scene.name = name;
    scene.float32_ray.depth_ulp_p99 = ray_ulps;
    BenchRow ours = row("default", 2.0, 0, 1e-7, 1e-3);
    ours.error.depth_ulp_p99 = ulps;
    scene.rows.push_back(ours);
    return scene;
  };
  report.scenes.push_back(stiff_scene("far-sphere-1e-04", 3.9, 0.5));       // within 4 ulps
  report.scenes.push_back(stiff_scene("huge-sphere-ground", 19.0, 16.0));   // 3 ulps over the ray's 16
  report.scenes.push_back(stiff_scene("grazing-plane", 4.6, 0.5));          // 4.1 over: missed
  BenchSceneResult ordinary;
  ordinary.name = "default";
  ordinary.rows = {row("default", 11.0, 0, 1e-7, 1e-4), row("naive", 10.0, 0, 1e-6, 1e-3)};
  report.scenes.push_back(ordinary);
  const std::string text = accuracy_markdown(report, "vkray bench --suite accuracy");
  EXPECT_NE(text.find("`vkray bench --suite accuracy`"), std::string::npos);
  EXPECT_NE(text.find("2 of 3 stiff cases meet the goals"), std::string::npos) << text;
  EXPECT_NE(text.find("missed: grazing-plane"), std::string::npos) << text;
  EXPECT_NE(text.find("default 11.00 ms against 10.00 ms (+10%)"), std::string::npos) << text;
  // The goals paragraph whole (it runs past 512 characters), the table on a line of its own.
  EXPECT_NE(text.find("adds no more than the goal on top.\n\n| case |"), std::string::npos) << text;
}

// Without the models folder the accuracy suite says that it leaves the bunny out (it used to drop
// it silently); docs/bench.md states the stiff suite's size as the code has it.
TEST(BenchScenes, AccuracySuiteNamesTheMissingBunnyAndTheReadmeCountsTheStiffCases) {
  std::vector<std::string> skipped;
  const auto accuracy = accuracy_scenes(8, 8, "/nonexistent/vkray-models", &skipped);
  const size_t stiff = stiff_scenes(8, 8).size(), basic = basic_scenes(8, 8).size();
  EXPECT_EQ(accuracy.size(), stiff + basic);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_NE(skipped[0].find("stanford-bunny.obj: not in the models folder '/nonexistent/vkray-models'"),
            std::string::npos)
      << skipped[0];
  std::ifstream page(std::filesystem::path(__FILE__).parent_path().parent_path() / "docs" / "bench.md");
  const std::string text{std::istreambuf_iterator<char>(page), {}};
  EXPECT_NE(text.find("`stiff` (" + std::to_string(stiff) + " numerically hard cases"), std::string::npos);
}

TEST(BenchScenes, AbsentModelsFolder) {
  EXPECT_TRUE(model_folder_scenes(64, 48, "/nonexistent/vkray-models", nullptr).empty());
}

}  // namespace
}  // namespace vkray
