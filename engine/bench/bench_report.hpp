// What `vkray bench` writes: the table on the terminal, JSON and CSV with every figure (schema in
// docs/bench.md), and the comparison of two JSON files. Reading and writing a report are
// in this one file so the schema cannot drift between them.
#pragma once

#include "engine/bench/bench.hpp"
#include "engine/bench/given_rays_bench.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace vkray {

inline constexpr const char* bench_schema = "vkray-bench-1";
inline constexpr const char* given_rays_schema = "vkray-bench-rays-1";  // --suite rays

// A row of --suite rays, with the scene it ran on (scene_hash).
struct GivenRaysResult {
  std::string scene, scene_hash;
  GivenRaysRow row;
};

struct BenchReport {
  std::string vkray_version;
  std::string git_commit;  // of the build; "unknown" outside a git checkout
  std::string device, device_type, driver, api_version;
  std::string suite;  // empty when scenes were named on the command line
  uint32_t frames = 0;
  std::vector<BenchSceneResult> scenes;
  std::vector<GivenRaysResult> given_rays;  // --suite rays has these rows instead of scenes
};

// This build's version and the git commit it was built from ("unknown" outside a checkout).
std::string build_version();
std::string build_commit();

// An empty report of this build (version, commit) on this device.
BenchReport new_bench_report(const GpuDeviceInfo& device, std::string suite, uint32_t frames);

// 64-bit FNV-1a over everything that decides the image (camera, size, every primitive's doubles),
// as 16 hex digits: two runs timed the same scene when their hashes match.
std::string scene_hash(const Scene& scene);

// The readable table: a legend, a header, then each scene's rows ("*": on the Pareto front) and its
// Pareto front, fastest first, with the time against `default` and the error each row comes with.
// Narrow fits 100 columns; wide has every column the terminal shows (the files have them all).
std::string bench_table_legend(bool wide);
std::string bench_table_header(bool wide);
std::string bench_table_rows(const BenchSceneResult& scene, bool wide);

std::string bench_json(const BenchReport& report);
std::string bench_csv(const BenchReport& report);
// --suite rays' files: the report's given_rays, every figure of each row.
std::string given_rays_json(const BenchReport& report);
std::string given_rays_csv(const BenchReport& report);

// Throws InputError naming the file (and the field) when it is not a bench JSON file.
BenchReport read_bench_json(const std::filesystem::path& path);

// Per row present in both (same scene name, size, hash and variant): time and error of `after`
// against `before`, as ratios; then every scene and row that could not be paired.
std::string compare_bench(const BenchReport& before, const BenchReport& after);

}  // namespace vkray
