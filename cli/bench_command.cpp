#include "cli/commands.hpp"
#include "cli/device_options.hpp"
#include "cli/progress.hpp"
#include "cli/scene_argument.hpp"
#include "engine/bench/accuracy_report.hpp"
#include "engine/bench/bench.hpp"
#include "engine/bench/bench_plot.hpp"
#include "engine/bench/bench_report.hpp"
#include "engine/bench/bench_suites.hpp"
#include "engine/bench/given_rays_bench.hpp"
#include "engine/bench/host_bench.hpp"
#include "engine/bench/instances_bench.hpp"
#include "engine/bench/moving_bench.hpp"
#include "engine/io/image_io.hpp"
#include "engine/typed_names.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace vkray::cli {
namespace {

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
};

// The options that decide what was measured, as a command: the accuracy document names it.
std::string command_line(const BenchOptions& options) {
  std::string line = "vkray bench";
  for (const auto& scene : options.scenes) line += " " + scene;
  if (!options.suite.empty()) line += " --suite " + options.suite;
  line += " --size " + options.size + " --frames " + std::to_string(options.frames) + " --rounds " +
          std::to_string(options.rounds);
  if (!options.variants.empty()) line += " --variants " + options.variants;
  if (!options.markdown.empty()) line += " --markdown " + options.markdown;
  return line;
}

int run_compare(const BenchOptions& options) {
  const BenchReport before = read_bench_json(options.compare[0]);
  const BenchReport after = read_bench_json(options.compare[1]);
  std::fputs(compare_bench(before, after).c_str(), stdout);
  return 0;
}

// --suite rays: every kind of given rays (ray_kinds) on each scene, a table row each; the files
// (--json, --csv) have every figure of each row.
int run_given_rays(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  BenchReport report = new_bench_report(device.info(), options.suite, options.frames);
  std::printf("vkray bench --suite rays on %s\n%zu scene%s, %zu rays a kind, %u timed calls after a first; times are medians\n%s",
              device.info().name.c_str(), scenes.size(), scenes.size() == 1 ? "" : "s", options.rays, options.frames,
              given_rays_table_header().c_str());
  std::fflush(stdout);
  BenchTiming timing;
  timing.frames = options.frames;
  for (const auto& scene : scenes) {
    for (const auto& kind : ray_kinds()) {
      const std::vector<GivenRay> rays = make_rays(kind.kind, scene.scene, options.rays);
      GivenRaysResult result{scene.name, scene_hash(scene.scene),
                             bench_given_rays(device, scene.scene, kind.name, rays, timing)};
      std::fputs(given_rays_table_row(scene.name, result.row).c_str(), stdout);
      std::fflush(stdout);
      report.given_rays.push_back(std::move(result));
    }
  }
  if (!options.json.empty()) write_text_file(options.json, given_rays_json(report));
  if (!options.csv.empty()) write_text_file(options.csv, given_rays_csv(report));
  return 0;
}

// --suite moving: each model's first mesh deformed, refitted against rebuilt, and rendered after
// (engine/bench/moving_bench.hpp), a table row each.
int run_moving(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  std::printf("vkray bench --suite moving on %s\n%zu model%s at %ux%u, every vertex moved by up to 1%% of the model's size; "
              "medians of %u calls after a first; render: GPU ms; the depth's relative error p99 against the reference, and the "
              "pixels outside the error envelope, on the refitted tree and on one built for the moved model\n%s",
              device.info().name.c_str(), scenes.size(), scenes.size() == 1 ? "" : "s", scenes.front().scene.width,
              scenes.front().scene.height, options.frames, moving_table_header().c_str());
  std::fflush(stdout);
  for (const auto& scene : scenes) {
    if (scene.scene.meshes.empty()) throw InputError(scene.name + ": --suite moving deforms a mesh; the scene has none");
    std::fputs(moving_table_row(scene.name, bench_moving(device, scene.scene, options.frames)).c_str(), stdout);
    std::fflush(stdout);
  }
  return 0;
}

// --suite instances: the suite's models placed --instances times, against the scene flattened,
// then every transform changed (engine/bench/instances_bench.hpp). The reference checks every 8th row.
int run_instances(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  std::vector<Scene> models;
  std::string names;
  for (const auto& scene : scenes) {
    if (scene.scene.meshes.empty()) throw InputError(scene.name + ": --suite instances places a mesh; the scene has none");
    models.push_back(scene.scene);
    names += (names.empty() ? "" : ", ") + scene.name;
  }
  const uint32_t width = scenes.front().scene.width, height = scenes.front().scene.height;
  std::printf("vkray bench --suite instances on %s\n%s, each scaled to a unit box, placed in turn at %ux%u; medians of %u calls "
              "after a first; render: GPU ms; errors against the reference on every 8th row\n",
              device.info().name.c_str(), names.c_str(), width, height, options.frames);
  std::fflush(stdout);
  const InstancesRow row = bench_instances(device, models, options.instances, width, height, options.frames, 8);
  std::fputs(instances_report(row).c_str(), stdout);
  return 0;
}

// --suite host: the host's stages alone on a frame made on the host, at --size: no device is opened.
int run_host_stages(const BenchOptions& options) {
  for (const auto& [value, name] : {std::pair{options.variants, "--variants"}, std::pair{options.markdown, "--markdown"},
                                    std::pair{options.plot, "--plot"}, std::pair{options.json, "--json"}, std::pair{options.csv, "--csv"}}) {
    if (!value.empty()) throw InputError(std::string(name) + ": not for --suite host, whose rows are the host's stages");
  }
  if (!options.scenes.empty()) throw InputError("--suite host makes its own frame: leave out the scenes");
  const auto [width, height] = parse_size(options.size);
  std::fputs(host_stages_table(bench_host_stages(width, height, options.frames), width, height).c_str(), stdout);
  return 0;
}

int run_bench(const BenchOptions& options) {
  if (!options.compare.empty()) return run_compare(options);
  if (options.suite == host_suite) return run_host_stages(options);
  if (options.suite == given_rays_suite) {
    for (const auto& [value, name] : {std::pair{options.variants, "--variants"},
                                      std::pair{options.markdown, "--markdown"}, std::pair{options.plot, "--plot"}}) {
      if (!value.empty()) throw InputError(std::string(name) + ": not for --suite rays, whose rows are kinds of rays, not variants");
    }
  }
  if (options.suite == moving_suite || options.suite == instances_suite) {
    for (const auto& [value, name] : {std::pair{options.variants, "--variants"}, std::pair{options.markdown, "--markdown"},
                                      std::pair{options.plot, "--plot"}, std::pair{options.json, "--json"}, std::pair{options.csv, "--csv"}}) {
      if (!value.empty()) throw InputError(std::string(name) + ": not for --suite " + options.suite + ", whose rows are a table of models");
    }
  }
  const auto [width, height] = parse_size(options.size);
  BenchSettings settings;
  settings.frames = options.frames;
  settings.rounds = options.rounds;
  settings.variants = split_list(options.variants);
  for (const auto& name : settings.variants) find_bench_variant(name);  // unknown names fail before any work
  settings.float32_ray_error = !options.markdown.empty();
  // Before any work: a bench must not run for minutes only to find it cannot be saved.
  for (const std::string& path : {options.json, options.csv, options.plot, options.markdown}) {
    if (!path.empty()) check_output_path(path);
  }

  std::vector<BenchScene> scenes;
  if (!options.suite.empty()) {
    std::vector<std::string> unreadable;
    scenes = bench_suite(options.suite, width, height, options.models, &unreadable);
    if (scenes.empty()) {
      throw InputError("--suite " + options.suite + ": no models in '" + options.models + "' (name the folder with --models)");
    }
    for (const auto& error : unreadable) std::fprintf(stderr, "vkray: skipped %s\n", error.c_str());
  }
  for (const auto& path : options.scenes) {
    scenes.push_back({std::filesystem::path(path).filename().string(), load_scene_argument(path, width, height)});
  }
  if (scenes.empty()) scenes.push_back({"built-in", load_scene_argument("", width, height)});
  if (options.suite == given_rays_suite) return run_given_rays(options, scenes);
  if (options.suite == moving_suite) return run_moving(options, scenes);
  if (options.suite == instances_suite) return run_instances(options, scenes);

  GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
  print_cpu_device_note(device.info());
  BenchReport report = new_bench_report(device.info(), options.suite, options.frames);
  // The count first: a suite of dozens of scenes at a full size runs for minutes.
  std::printf("vkray bench on %s\ndriver %s\ntransfer %s\n%zu scene%s at %ux%u, %u frame%s after a warm-up, in %u round%s\n%s%s",
              device.info().name.c_str(), device.info().driver.c_str(), device.transfer_description().c_str(),
              scenes.size(), scenes.size() == 1 ? "" : "s", width, height, options.frames, options.frames == 1 ? "" : "s",
              options.rounds, options.rounds == 1 ? "" : "s", bench_table_legend(options.wide).c_str(), bench_table_header(options.wide).c_str());
  std::fflush(stdout);
  for (const auto& scene : scenes) {
    ProgressLine progress("reference for " + scene.name);
    settings.reference_progress = progress.callback();
    report.scenes.push_back(bench_scene(device, scene, settings));
    std::fputs(bench_table_rows(report.scenes.back(), options.wide).c_str(), stdout);
    std::fflush(stdout);
  }

  if (!options.json.empty()) write_text_file(options.json, bench_json(report));
  if (!options.csv.empty()) write_text_file(options.csv, bench_csv(report));
  if (!options.markdown.empty()) write_text_file(options.markdown, accuracy_markdown(report, command_line(options)));
  if (!options.plot.empty() && !options.json.empty()) plot_bench(options.json, options.plot);
  if (!options.plot.empty() && options.json.empty()) {  // the script reads the report from a file
    const auto json_path = std::filesystem::temp_directory_path() / ("vkray-bench-" + std::to_string(getpid()) + ".json");
    struct RemoveOnExit {
      std::filesystem::path path;
      ~RemoveOnExit() { std::filesystem::remove(path); }
    } remove_report{json_path};
    write_text_file(json_path, bench_json(report));
    plot_bench(json_path, options.plot);
  }
  return 0;
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
  measuring.push_back(command->add_option("--suite", options->suite, std::string("Built-in scenes: ") + bench_suite_names));
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
      command->add_option("--models", options->models, "Folder of .obj files for --suite models and rays")->capture_default_str());
  measuring.push_back(command->add_option("--rays", options->rays, "Rays of each kind in --suite rays")
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
