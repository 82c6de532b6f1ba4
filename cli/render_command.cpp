#include "cli/commands.hpp"
#include "cli/progress.hpp"
#include "cli/scene_argument.hpp"
#include "engine/compare.hpp"
#include "engine/host_memory.hpp"
#include "engine/image_io.hpp"
#include "engine/reference.hpp"
#include "engine/renderer.hpp"
#include "engine/scene_loader.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

namespace vkray::cli {
namespace {

struct RenderOptions {
  std::string scene_path;
  std::optional<std::string> camera;
  std::string output = "render.exr";
  std::optional<std::string> preview;
  bool no_preview = false;
  std::optional<uint32_t> width, height;
  std::string aovs = "depth,normal";
  std::string device;
  bool timings = false;
  bool check = false;
  bool reference = false;
  std::string compression = default_exr_compression;
  std::string precision = "float";
};

AovSet parse_aov_list(const std::string& list) {
  AovSet aovs;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    const std::string name = list.substr(start, comma - start);
    const auto aov = aov_from_name(name);
    if (!aov) throw InputError("--aov: unknown output '" + name + "' (choose from " + aov_names_help + ")");
    aovs.add(*aov);
    start = comma + 1;
  }
  return aovs;
}

class Stopwatch {
 public:
  double lap_ms() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

void print_timing(const char* what, double ms) { std::printf("  %-22s %10.3f ms\n", what, ms); }

// Usage errors that parsing cannot see. The output is always OpenEXR: the image writer picks the
// format from the extension, so another one would silently write a different (8-bit, lossy) format,
// or the preview would overwrite it. --check on uv alone would count every hit as a mismatch.
void check_render_options(const RenderOptions& options, const AovSet& aovs) {
  std::string extension = std::filesystem::path(options.output).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".exr") throw InputError("-o/--output: '" + options.output + "' must end in .exr (OpenEXR)");
  if (options.preview && !options.no_preview &&
      std::filesystem::path(*options.preview).lexically_normal() == std::filesystem::path(options.output).lexically_normal()) {
    throw InputError("--preview: '" + *options.preview + "' is the OpenEXR output; give another file");
  }
  if (!is_exr_compression(options.compression)) {
    std::string known;
    for (const char* name : exr_compressions) known += (known.empty() ? "" : ", ") + std::string(name);
    throw InputError("--compression: unknown '" + options.compression + "' (choose from " + known + ")");
  }
  if (options.check && !options.reference && !aovs.needs_rays()) {
    throw InputError("--check compares depth and normal with the reference; add one of them to --aov");
  }
}

int run_render(const RenderOptions& options) {
  Stopwatch stopwatch;
  const AovSet aovs = parse_aov_list(options.aovs);
  check_render_options(options, aovs);
  const std::filesystem::path preview =
      options.preview.value_or(std::filesystem::path(options.output).replace_extension(".png").string());
  // Before any work: a render must not take minutes only to find it cannot be saved.
  check_output_path(options.output);
  if (!options.no_preview) check_output_path(preview);
  Scene scene = load_scene_argument(options.scene_path, options.width, options.height);
  if (options.camera) apply_camera_option(*options.camera, scene.camera);
  const double load_ms = stopwatch.lap_ms();

  Frame frame;
  std::optional<RenderTimings> gpu_timings;
  std::optional<SceneStats> scene_stats;
  double reference_ms = 0.0;
  double device_ms = 0.0;
  std::string device_name = "CPU reference (double precision)";
  std::optional<std::vector<ReferenceHit>> reference_hits;
  auto reference = [&]() -> const std::vector<ReferenceHit>& {
    if (!reference_hits) {
      Stopwatch reference_watch;
      const ReferenceScene reference_scene(scene);
      reference_hits = render_reference_hits(reference_scene, make_camera_basis(scene.camera, scene.width, scene.height),
                                             scene.width, scene.height);
      reference_ms = reference_watch.lap_ms();
    }
    return *reference_hits;
  };

  if (options.reference) {
    frame = reference_frame(reference(), scene.width, scene.height, aovs);
  } else {
    GpuDevice device(options.device);
    device_name = device.info().name;
    device_ms = stopwatch.lap_ms();
    ProgressLine progress("building the BVH");
    RendererOptions renderer_options;
    renderer_options.scene.bvh.progress = progress.callback();
    if (options.precision == "double") renderer_options.shader.precision = Precision::float64;
    Renderer renderer(device, scene, renderer_options);
    frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
    gpu_timings = renderer.timings();
    scene_stats = renderer.scene_stats();
  }
  const double render_ms = stopwatch.lap_ms();

  std::optional<FrameError> error;
  if (options.check && !options.reference) error = measure_error(frame, reference());
  stopwatch.lap_ms();

  std::string written = options.output;
  write_outputs(options.output, options.no_preview ? nullptr : &preview, frame, options.compression);
  if (!options.no_preview) written += " and " + preview.string();
  const double write_ms = stopwatch.lap_ms();

  std::printf("vkray: wrote %s (%ux%u, %s) on %s\n", written.c_str(), scene.width, scene.height,
              aovs.names().c_str(), device_name.c_str());
  if (error) std::printf("error vs. double-precision reference: %s\n", error->summary().c_str());
  if (options.timings) {
    std::printf("timings:\n");
    print_timing("scene load", load_ms);
    if (gpu_timings) {
      print_timing("device open", device_ms);
      print_timing("upload", gpu_timings->upload_ms);
      if (scene_stats->bvh_nodes > 0) print_timing("  of which BVH build", gpu_timings->bvh_build_ms);
      print_timing("pipeline creation", gpu_timings->pipeline_ms);
      if (gpu_timings->has_gpu_times) {
        print_timing("dispatch (GPU)", gpu_timings->dispatch_gpu_ms);
      } else {
        std::printf("  %-22s %13s\n", "dispatch (GPU)", "n/a (device has no timestamps)");
      }
      print_timing("readback", gpu_timings->readback_ms);
      print_timing("render (wall)", render_ms);
      std::printf("  %-22s %10u\n", "tiles", gpu_timings->tiles);
      if (gpu_timings->unfinished_rays > 0) {
        std::printf("  %-22s %10llu (finished on the CPU in %.3f ms)\n", "rays past loop budget",
                    static_cast<unsigned long long>(gpu_timings->unfinished_rays), gpu_timings->cpu_finish_ms);
      }
    }
    if (reference_hits) print_timing("reference (CPU)", reference_ms);
    print_timing("file writing", write_ms);
    if (scene_stats) {
      const SceneStats& stats = *scene_stats;
      std::printf("scene on the device: %u triangles, %u spheres, %.1f MiB", stats.triangles, stats.spheres,
                  static_cast<double>(stats.geometry_bytes) / (1 << 20));
      if (stats.triangles > 0 && stats.spheres == 0) {
        std::printf(" (%.1f bytes a triangle)", static_cast<double>(stats.geometry_bytes) / stats.triangles);
      }
      if (stats.bvh_nodes > 0) std::printf("; BVH of %u nodes, depth %u", stats.bvh_nodes, stats.bvh_depth);
      std::printf("\n");
    }
    std::printf("peak host memory: %.1f MiB\n", static_cast<double>(peak_host_memory_bytes()) / (1 << 20));
  }
  return 0;
}

}  // namespace

Action add_render_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand("render", "Render a scene (or the built-in one) to OpenEXR and a PNG preview.");
  auto options = std::make_shared<RenderOptions>();
  command->add_option("scene", options->scene_path,
                      "Scene file (.json) or model (.obj, framed automatically); the built-in course scene when omitted");
  command->add_option("--camera", options->camera,
                      "Override the camera: 'from=X,Y,Z to=X,Y,Z up=X,Y,Z fovy=DEGREES', any of the keys");
  command->add_option("-o,--output", options->output, "OpenEXR file to write")->capture_default_str();
  command->add_option("--width", options->width, "Image width in pixels (overrides the scene)");
  command->add_option("--height", options->height, "Image height in pixels (overrides the scene)");
  command->add_option("--aov", options->aovs, std::string("Outputs to compute, comma-separated: ") + aov_names_help)
      ->capture_default_str();
  command->add_option("--preview", options->preview, "PNG preview to write (default: the output with .png)");
  command->add_flag("--no-preview", options->no_preview, "Write no PNG preview");
  command->add_option("--compression", options->compression,
                      "OpenEXR compression, all lossless: zip (default), zips, piz, rle, none (fastest, largest)");
  command->add_option("--device", options->device, "Use the Vulkan device whose name contains this text");
  command->add_option("--precision", options->precision,
                      "Shader arithmetic: float (float32, camera-relative) or double (float64: exact, slower; needs "
                      "shaderFloat64)")
      ->check(CLI::IsMember({"float", "double"}))
      ->capture_default_str();
  command->add_flag("--timings", options->timings, "Print where the time went");
  command->add_flag("--check", options->check,
                    "Also render the double-precision CPU reference and print the GPU's error against it");
  command->add_flag("--reference", options->reference, "Render with the double-precision CPU reference instead");
  return [options] { return run_render(*options); };
}

}  // namespace vkray::cli
