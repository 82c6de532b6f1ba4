// `vkray bench`'s suites, each a row of bench_suites(): its name, what it measures, the options its
// rows take, its scenes and its runner. A new suite is a row there and a runner in a file of its own
// (cli/bench_*.cpp); the help text, the refusal of options a suite does not take and the dispatch
// all read the table.
#pragma once

#include "cli/device_options.hpp"
#include "engine/bench/bench_suites.hpp"

#include <span>
#include <string>
#include <vector>

namespace vkray::cli {

struct BenchOptions {
  std::vector<std::string> scenes;
  std::string suite;
  std::string size = "1920x1080";
  uint32_t frames = 5;
  uint32_t rounds = 2;
  std::string variants;
  DeviceOptions device_options;
  std::string models = "../shared/models";
  bool wide = false;
  std::string json, csv, plot, markdown;
  std::vector<std::string> compare;
  size_t rays = 1 << 20;  // a kind's rays in --suite rays
  uint32_t instances = 1000;  // --suite instances
  size_t points = 1 << 20;    // each set's points in --suite points
};

// The options beyond the scenes, --size, --frames, --models and the device's that a suite's rows
// can use; one it does not take is refused, naming it.
enum BenchTakes : uint32_t {
  takes_variants = 1u,  // --variants, --rounds, --wide: rows of shader variants
  takes_files = 2u,     // --json, --csv
  takes_report = 4u,    // --markdown, --plot: the accuracy document and the error-time plot
  takes_rays = 8u,      // --rays
  takes_instances = 16u,
  takes_no_scenes = 32u,  // it makes its own frame: scene arguments are refused
};

// A suite's runner: it opens the device it needs, measures and prints its table, and writes the
// files asked for; returns the exit code.
using BenchRunner = int (*)(const BenchOptions& options, const std::vector<BenchScene>& scenes);

struct BenchSuiteRow {
  const char* name;      // --suite
  const char* measures;  // the help text's line
  uint32_t takes;        // BenchTakes
  BenchSceneSet scenes;  // none for a suite that makes its own
  BenchRunner run;
};

// Every suite, in the order the help lists them.
std::span<const BenchSuiteRow> bench_suites();
// The suite named `name`; InputError naming the known ones for another.
const BenchSuiteRow& bench_suite_named(const std::string& name);
// The suites' names and what each measures, for --suite's help.
std::string bench_suites_help();

// The runners (cli/bench_*.cpp).
// Rows of shader variants on each scene (the default without --suite too): cli/bench_variants.cpp.
int run_variants(const BenchOptions& options, const std::vector<BenchScene>& scenes);
int run_given_rays(const BenchOptions& options, const std::vector<BenchScene>& scenes);
int run_moving(const BenchOptions& options, const std::vector<BenchScene>& scenes);
int run_instances(const BenchOptions& options, const std::vector<BenchScene>& scenes);
int run_points(const BenchOptions& options, const std::vector<BenchScene>& scenes);
int run_host_stages(const BenchOptions& options, const std::vector<BenchScene>& scenes);

}  // namespace vkray::cli
