// Rows of shader variants on each scene, each timed beside its error against the reference (engine/bench/bench.hpp):
// the suites basic, scaling, stiff, accuracy and models, and scene files named without --suite.
#include "cli/bench_suites.hpp"
#include "cli/progress.hpp"
#include "cli/scene_argument.hpp"
#include "engine/bench/accuracy_report.hpp"
#include "engine/bench/bench.hpp"
#include "engine/bench/bench_plot.hpp"
#include "engine/bench/bench_report.hpp"
#include "engine/io/image_io.hpp"
#include "engine/typed_names.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace vkray::cli {
namespace {

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

}  // namespace

int run_variants(const BenchOptions& options, const std::vector<BenchScene>& scenes) {
  const auto [width, height] = parse_size(options.size);
  BenchSettings settings;
  settings.frames = options.frames;
  settings.rounds = options.rounds;
  settings.variants = split_list(options.variants);
  settings.float32_ray_error = !options.markdown.empty();
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

}  // namespace vkray::cli
