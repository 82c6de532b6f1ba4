// `vkray bench`: its options, and the dispatch to the suite named (cli/bench_suites.hpp), or to rows of
// shader variants on the scenes given.
#include "cli/bench_suites.hpp"
#include "cli/commands.hpp"
#include "cli/device_options.hpp"
#include "cli/scene_argument.hpp"
#include "engine/bench/bench.hpp"
#include "engine/bench/bench_report.hpp"
#include "engine/io/image_io.hpp"
#include "engine/typed_names.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace vkray::cli {
namespace {

int run_compare(const BenchOptions& options) {
  const BenchReport before = read_bench_json(options.compare[0]);
  const BenchReport after = read_bench_json(options.compare[1]);
  std::fputs(compare_bench(before, after).c_str(), stdout);
  return 0;
}

// Rows of variants on the scenes given (or the built-in one), without --suite.
constexpr uint32_t scene_files_take = takes_variants | takes_files | takes_report;

int run_bench(const BenchOptions& options) {
  if (!options.compare.empty()) return run_compare(options);
  const BenchSuiteRow* suite = options.suite.empty() ? nullptr : &bench_suite_named(options.suite);
  const uint32_t takes = suite ? suite->takes : scene_files_take;
  // What the suite's rows cannot use is refused before any work, naming it.
  const std::string rows = suite ? std::string(", whose rows are ") + suite->measures : "";
  const auto refuse = [&](const std::string& value, const char* name, uint32_t taken_by) {
    if (!value.empty() && !(takes & taken_by)) throw InputError(std::string(name) + ": not for --suite " + options.suite + rows);
  };
  refuse(options.variants, "--variants", takes_variants);
  refuse(options.json, "--json", takes_files);
  refuse(options.csv, "--csv", takes_files);
  refuse(options.markdown, "--markdown", takes_report);
  refuse(options.plot, "--plot", takes_report);
  if ((takes & takes_no_scenes) && !options.scenes.empty()) {
    throw InputError("--suite " + options.suite + " makes its own frame: leave out the scenes");
  }
  const auto [width, height] = parse_size(options.size);
  for (const auto& name : split_list(options.variants)) find_bench_variant(name);  // unknown names fail before any work
  // Before any work: a bench must not run for minutes only to find it cannot be saved.
  for (const std::string& path : {options.json, options.csv, options.plot, options.markdown}) {
    if (!path.empty()) check_output_path(path);
  }

  std::vector<BenchScene> scenes;
  if (suite && suite->scenes) {
    std::vector<std::string> unreadable;
    scenes = suite->scenes(width, height, options.models, &unreadable);
    if (scenes.empty()) {
      throw InputError("--suite " + options.suite + ": no models in '" + options.models + "' (name the folder with --models)");
    }
    for (const auto& error : unreadable) std::fprintf(stderr, "vkray: skipped %s\n", error.c_str());
  }
  for (const auto& path : options.scenes) {
    scenes.push_back({std::filesystem::path(path).filename().string(), load_scene_argument(path, width, height)});
  }
  if (scenes.empty() && !(takes & takes_no_scenes)) scenes.push_back({"built-in", load_scene_argument("", width, height)});
  return suite ? suite->run(options, scenes) : run_variants(options, scenes);
}

}  // namespace

Action add_bench_command(CLI::App& app) {
  CLI::App* command =
      app.add_subcommand("bench", "Time configurations of the renderer beside their error against the reference.");
  auto options = std::make_shared<BenchOptions>();
  std::vector<CLI::Option*> measuring;
  measuring.push_back(command->add_option("scenes", options->scenes,
                                          "Scene files (.json) or models (.obj, .ply, .gltf, .glb, framed automatically); the built-in "
                                          "scene when neither these nor --suite are given"));
  measuring.push_back(command->add_option("--suite", options->suite, bench_suites_help()));
  measuring.push_back(command->add_option("--size", options->size, "Image size WIDTHxHEIGHT")->capture_default_str());
  measuring.push_back(command->add_option("--frames", options->frames, "Timed frames per variant, after one warm-up")
                          ->capture_default_str()
                          ->check(CLI::Range(1u, 100000u)));
  measuring.push_back(command->add_option("--rounds", options->rounds,
                                          "Rounds over the variants, every other one in reverse order; each row's frames "
                                          "pooled over them (its spread too), so noise spreads over every row")
                          ->capture_default_str()
                          ->check(CLI::Range(1u, 1000u)));
  std::string variant_names;
  for (const auto& variant : bench_variants()) variant_names += "\n  " + variant.name + ": " + variant.description;
  measuring.push_back(command->add_option("--variants", options->variants,
                                          "Comma-separated variants; default: every one that applies to the scene:" +
                                              variant_names));
  measuring.push_back(add_device_options(command, options->device_options));
  measuring.push_back(
      command->add_option("--models", options->models, "Folder of .obj files for --suite models, rays and points")->capture_default_str());
  measuring.push_back(command->add_option("--rays", options->rays, "Rays of each kind in --suite rays")
                          ->capture_default_str()
                          ->check(CLI::Range(size_t{1}, size_t{1} << 26)));
  measuring.push_back(command->add_option("--points", options->points, "Points of each set in --suite points")
                          ->capture_default_str()
                          ->check(CLI::Range(size_t{1}, size_t{1} << 26)));
  measuring.push_back(command->add_option("--instances", options->instances, "Instances in --suite instances")
                          ->capture_default_str()
                          ->check(CLI::Range(1u, 1000000u)));
  measuring.push_back(command->add_flag("--wide", options->wide,
                                        "Print every column (about 160 characters wide; the default fits 100)"));
  measuring.push_back(
      command->add_option("--json", options->json, "Write every figure as JSON (schema: docs/bench.md)"));
  measuring.push_back(command->add_option("--csv", options->csv, "Write every figure as CSV, a line per row"));
  measuring.push_back(command->add_option("--markdown", options->markdown,
                                          "Write the accuracy document (docs/accuracy.md) of this run: use with --suite "
                                          "accuracy"));
  measuring.push_back(
      command->add_option("--plot", options->plot, "Plot error against time as PNG (needs python3-matplotlib)"));
  CLI::Option* compare =
      command->add_option("--compare", options->compare, "Compare two JSON files of earlier runs (A B): ratios B/A")
          ->expected(2);
  // --compare reads two finished runs and measures nothing: an option of a run beside it would be ignored.
  for (CLI::Option* option : measuring) compare->excludes(option);
  return [options] { return run_bench(*options); };
}

}  // namespace vkray::cli
