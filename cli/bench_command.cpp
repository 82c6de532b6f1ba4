#include "cli/commands.hpp"
#include "cli/scene_argument.hpp"
#include "engine/bench.hpp"
#include "engine/embree_baseline.hpp"
#include "engine/scene_loader.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace vkray::cli {
namespace {

struct BenchOptions {
  std::vector<std::string> scenes;
  std::string size = "1920x1080";
  uint32_t frames = 5;
  std::string variants = "bvh-per-ray,bvh-packet";
  std::string device;
  bool no_embree = false;
};

std::pair<uint32_t, uint32_t> parse_size(const std::string& text) {
  const size_t x = text.find('x');
  try {
    size_t used_w = 0, used_h = 0;
    if (x == std::string::npos) throw std::invalid_argument("no x");
    const unsigned long width = std::stoul(text.substr(0, x), &used_w);
    const unsigned long height = std::stoul(text.substr(x + 1), &used_h);
    if (used_w != x || used_h != text.size() - x - 1 || width > UINT32_MAX || height > UINT32_MAX) {
      throw std::invalid_argument("trailing text");
    }
    check_image_size(static_cast<uint32_t>(width), static_cast<uint32_t>(height));
    return {static_cast<uint32_t>(width), static_cast<uint32_t>(height)};
  } catch (const std::logic_error&) {
    throw InputError("--size: '" + text + "' is not WIDTHxHEIGHT, e.g. 1920x1080");
  }
}

std::vector<BenchVariant> parse_variants(const std::string& list) {
  std::vector<BenchVariant> chosen;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    const std::string name = list.substr(start, comma - start);
    std::string known;
    bool found = false;
    for (const auto& variant : bench_variants()) {
      known += (known.empty() ? "" : ", ") + variant.name;
      if (variant.name == name) chosen.push_back(variant), found = true;
    }
    if (!found) throw InputError("--variants: unknown variant '" + name + "' (choose from " + known + ")");
    start = comma + 1;
  }
  return chosen;
}

int run_bench(const BenchOptions& options) {
  const auto [width, height] = parse_size(options.size);
  const std::vector<BenchVariant> variants = parse_variants(options.variants);
  std::vector<std::pair<std::string, Scene>> scenes;
  if (options.scenes.empty()) scenes.emplace_back("default", load_scene_argument("", width, height));
  for (const auto& path : options.scenes) {
    scenes.emplace_back(std::filesystem::path(path).filename().string(), load_scene_argument(path, width, height));
  }

  GpuDevice device(options.device);
  std::printf("vkray bench on %s (%s), %ux%u, %u frames\n", device.info().name.c_str(), device.info().driver.c_str(),
              width, height, options.frames);
  std::printf("%-24s %-12s %9s %8s %9s %9s %9s %8s %8s %7s %9s %9s\n", "scene", "variant", "triangles", "B/tri",
              "build ms", "gpu med", "gpu min", "Mrays/s", "flips", "unfin.", "depth p99", "norm p99");
  for (auto& [name, scene] : scenes) {
    const ReferenceScene reference_scene(scene);
    const std::vector<ReferenceHit> reference =
        render_reference_hits(reference_scene, make_camera_basis(scene.camera, width, height), width, height);
    double best_vkray_ms = 0.0;
    for (const auto& variant : variants) {
      const BenchRow row = run_bench_variant(device, scene, variant, options.frames, reference);
      if (best_vkray_ms == 0.0 || row.dispatch_median_ms < best_vkray_ms) best_vkray_ms = row.dispatch_median_ms;
      const double bytes_per_triangle =
          row.stats.triangles ? static_cast<double>(row.stats.geometry_bytes) / row.stats.triangles : 0.0;
      std::printf("%-24s %-12s %9u %8.1f %9.1f %9.2f %9.2f %8.2f %8zu %7llu %9.2e %9.2e\n", name.c_str(),
                  row.variant.c_str(), row.stats.triangles, bytes_per_triangle, row.bvh_build_ms, row.dispatch_median_ms,
                  row.dispatch_min_ms, row.mrays_per_s, row.error.hit_mismatches,
                  static_cast<unsigned long long>(row.unfinished_rays), row.error.depth_p99, row.error.normal_deg_p99);
    }
    if (options.no_embree) continue;
    const EmbreeResult embree = trace_with_embree(scene, width, height, options.frames);
    const FrameError embree_error = measure_error(embree.frame, reference);
    const double pixels = static_cast<double>(width) * height;
    for (const auto& [mode, ms] : {std::pair{"embree-1", embree.single_ms}, std::pair{"embree-8", embree.packet_ms}}) {
      std::printf("%-24s %-12s %9s %8s %9.1f %9s %9.2f %8.2f %8zu %7s %9.2e %9.2e\n", name.c_str(), mode, "", "",
                  embree.build_ms, "", ms, pixels / (ms * 1e3), embree_error.hit_mismatches, "", embree_error.depth_p99,
                  embree_error.normal_deg_p99);
    }
    std::printf("%-24s vkray's fastest variant against Embree's packets on %u CPU threads: %.2fx the time\n", name.c_str(),
                embree.threads, best_vkray_ms / embree.packet_ms);
  }
  return 0;
}

}  // namespace

Action add_bench_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand("bench", "Time configurations of the renderer beside their error against the reference.");
  auto options = std::make_shared<BenchOptions>();
  command->add_option("scenes", options->scenes,
                      "Scene files (.json) or models (.obj, framed automatically); the built-in scene when none is given");
  command->add_option("--size", options->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  command->add_option("--frames", options->frames, "Timed frames per variant, after one warm-up")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100000u));
  command->add_option("--variants", options->variants, "Comma-separated: brute-force, bvh-per-ray, bvh-packet")
      ->capture_default_str();
  command->add_option("--device", options->device, "Use the Vulkan device whose name contains this text");
  command->add_flag("--no-embree", options->no_embree, "Leave out the Embree CPU baseline");
  return [options] { return run_bench(*options); };
}

}  // namespace vkray::cli
