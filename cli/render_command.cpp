#include "cli/commands.hpp"
#include "cli/device_options.hpp"
#include "cli/progress.hpp"
#include "cli/scene_argument.hpp"
#include "cli/views_options.hpp"
#include "engine/reference/compare.hpp"
#include "engine/host_memory.hpp"
#include "engine/io/image_io.hpp"
#include "engine/io/preview.hpp"
#include "engine/typed_names.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/scene/scene_or_model.hpp"
#include "engine/stopwatch.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <iostream>
#include <memory>
#include <optional>

namespace vkray::cli {
namespace {

struct RenderOptions {
  std::string scene_path;
  std::optional<std::string> camera;
  std::optional<std::string> view;
  std::string output = "render.exr";
  std::optional<std::string> preview;
  bool no_preview = false;
  std::optional<uint32_t> width, height;
  std::string aovs = "depth,normal";
  DeviceOptions device_options;
  bool timings = false;
  bool check = false;
  bool reference = false;
  std::string compression = default_exr_compression;
  std::string miss = "inf";
  std::string half;  // outputs stored as half floats
  std::string format = "exr";
  double depth_step = 0.001;
  std::string precision = "float";
  std::string traversal = "auto";
  uint32_t mask = every_mask_bit;  // the rays' (Renderer::set_ray_mask)
  ViewsOptions views;
  bool output_given = false;  // -o on the command line (many views default to view-{index:05}.exr)
};

AovSet parse_aov_list(const std::string& list) {
  AovSet aovs;
  for (const std::string& name : split_list(list)) {
    const auto aov = aov_from_name(name);
    if (!aov) throw InputError("--aov: " + unknown_output_message(name));
    aovs.add(*aov);
  }
  if (aovs.empty()) throw InputError("--aov: name at least one output (" + output_names() + ")");
  return aovs;
}

// --half: float outputs among --aov's, as the EXR stores them in half.
AovSet half_outputs(const std::string& list, const AovSet& aovs) {
  AovSet half;
  for (const std::string& name : split_list(list)) {
    const auto aov = aov_from_name(name);
    if (!aov) throw InputError("--half: " + unknown_output_message(name));
    if (!aovs.has(*aov)) throw InputError("--half: '" + name + "' is not among the outputs --aov writes");
    const bool integers = std::ranges::any_of(outputs(), [&](const OutputInfo& output) {
      return output.aov == *aov && output.integers != nullptr;
    });
    if (integers) throw InputError("--half: '" + name + "' holds integers; half stores floats");
    half.add(*aov);
  }
  return half;
}

// --miss: inf, -inf, nan or a finite number, as the float written.
float miss_value(const std::string& text) {
  if (text == "inf" || text == "+inf") return INFINITY;
  if (text == "-inf") return -INFINITY;
  if (text == "nan") return NAN;
  float value = 0.0f;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  const bool whole = end == text.data() + text.size();
  if (error == std::errc::result_out_of_range && whole) {
    throw InputError("--miss: '" + text + "' is beyond float32's range (magnitudes to 3.4e38; or inf, -inf)");
  }
  if (error != std::errc() || !whole || !std::isfinite(value)) {
    throw InputError("--miss: '" + text + "' is not inf, -inf, nan or a number");
  }
  return value;
}

// The settings of the written files, each option checked (InputError).
OutputSettings output_settings(const RenderOptions& options, const AovSet& aovs) {
  OutputSettings settings;
  const auto format = file_format_from_name(options.format);
  if (!format) throw InputError("--format: unknown '" + options.format + "' (choose from " + file_format_names + ")");
  settings.format = *format;
  if (settings.format == FileFormat::png16) check_png16_outputs(aovs);
  if (!(options.depth_step > 0.0 && std::isfinite(options.depth_step))) {
    throw InputError("--depth-step: must be a positive number, got " + std::to_string(options.depth_step));
  }
  settings.depth_step = options.depth_step;
  settings.compression = options.compression;
  settings.miss = miss_value(options.miss);
  settings.half = half_outputs(options.half, aovs);
  if (settings.format == FileFormat::png16 && !settings.half.empty()) {
    throw InputError("--half: --format png16 stores depths as 16-bit steps, not floats: leave out --half, or store them as exr or npy");
  }
  return settings;
}

// Usage errors that parsing cannot see. The output is always OpenEXR and the preview always PNG,
// so a name with another extension (x.jpg holding a PNG) would mislead whoever opens it; the two
// extensions also keep the preview from ever replacing the EXR. --check on uv alone would count
// every hit as a mismatch.
void check_render_options(const RenderOptions& options, const AovSet& aovs) {
  if (lower_extension(options.output) != ".exr") {
    throw InputError("-o/--output: '" + options.output + "' must end in .exr: " +
                     (options.format == "exr" ? std::string("the OpenEXR file")
                                              : "with --format " + options.format + " it names the view, whose outputs go beside it as "
                                                "NAME.OUTPUT." + (options.format == "npy" ? "npy" : "png") + " (view.exr: view.depth." +
                                                (options.format == "npy" ? "npy" : "png") + ")"));
  }
  if (options.preview && lower_extension(*options.preview) != ".png") {
    throw InputError("--preview: '" + *options.preview + "' must end in .png (the preview is an 8-bit PNG)");
  }
  if (!is_exr_compression(options.compression)) {
    std::string known;
    for (const char* name : exr_compressions) known += (known.empty() ? "" : ", ") + std::string(name);
    throw InputError("--compression: unknown '" + options.compression + "' (choose from " + known +
                     "; zip and zips also with a deflate level, zip:1 to zip:9)");
  }
  output_settings(options, aovs);  // refused here, before any work
  if (options.check && !aovs.needs_rays()) {
    throw InputError("--check compares depth and normal with the reference; add one of them to --aov");
  }
}

// png16 holds depths up to 65535 steps: say how many lay past (stored as 0, as misses are).
void print_png16_note(size_t pixels, uint32_t views, double depth_step) {
  std::printf("vkray: note: %zu depth sample%s%s lay past 65535 steps of --depth-step %g (depths beyond %g) and hold 0, as "
              "misses do: a larger --depth-step holds them\n",
              pixels, pixels == 1 ? "" : "s", views > 1 ? (" in " + std::to_string(views) + " views").c_str() : "", depth_step,
              65535.0 * depth_step);
}

// One line of --timings; `depth` 1 is a part of the total, 2 a part of the part above it.
void print_timing(int depth, const std::string& what, double ms, const std::string& note = "") {
  std::printf("%*s%-*s %10.1f ms%s\n", 2 * depth + 2, "", 28 - 2 * depth, what.c_str(), ms,
              note.empty() ? "" : ("  " + note).c_str());
}

// Many views in one run: the scene uploaded and the pipeline made once, the views written while the
// next ones render (engine/views/view_batch.hpp).
int run_render_views(const RenderOptions& options, const AovSet& aovs) {
  check_render_options(options, aovs);
  if (options.check || options.reference) throw InputError("--check and --reference render one view; leave out --views, --orbit and --sphere");
  if (options.no_preview) throw InputError("--no-preview: many views write no previews unless --preview names them");
  ViewBatch batch;
  batch.exr = OutputPattern(options.output_given ? options.output : "view-{index:05}.exr", "-o");
  if (options.preview) batch.png = OutputPattern(*options.preview, "--preview");
  batch.shard = parse_shard(options.views);
  batch.manifest = manifest_path(options.views, batch.shard, batch.exr);
  batch.output_settings = output_settings(options, aovs);
  batch.aovs = aovs;
  batch.overwrite = options.views.overwrite;
  if (options.views.views_file) batch.views = batch_views(options.views, Camera{});
  auto opening = std::async(std::launch::async, [&options] {
    return std::make_unique<GpuDevice>(options.device_options.device, options.device_options.transfer_mode());
  });
  Scene scene = load_scene_argument(options.scene_path, options.width, options.height, options.view);
  if (options.camera) apply_camera_option(*options.camera, scene.camera);
  if (!options.views.views_file) batch.views = batch_views(options.views, scene.camera);
  for (size_t k = 0; k < batch.views.size(); ++k) {
    check_camera_reach(batch.views[k].camera, scene.width, scene.height, "view " + std::to_string(k) + "'s camera");
  }
  check_view_poses(batch.views, scene);
  batch.width = scene.width;
  batch.height = scene.height;
  batch.scene = geometry_hash(scene);
  batch.mask = static_cast<Mask>(options.mask);
  print_mask_note(scene, options.mask);
  if (aovs.has(Aov::mesh_id)) batch.objects = object_names(scene);
  if (batch.views.size() > 1 && (!batch.exr.has_index() || (batch.png && !batch.png->has_index()))) {
    throw InputError(std::string(batch.exr.has_index() ? "--preview" : "-o") + ": '" +
                     (batch.exr.has_index() ? batch.png->text() : batch.exr.text()) + "' has no {index}, so the " +
                     std::to_string(batch.views.size()) + " views would overwrite one file (as out/view-{index:05}.exr)");
  }
  check_view_names(batch);
  // The tests' fault: the device lost before view k renders (tests/views/test_many_views.py).
  if (const char* view = std::getenv("VKRAY_TEST_LOSE_DEVICE_AT_VIEW"); view && *view) {
    batch.before_render = [at = std::stoul(view)](uint32_t index) {
      if (index == at) throw DeviceLostError("the device was lost (VKRAY_TEST_LOSE_DEVICE_AT_VIEW)");
    };
  }
  const std::unique_ptr<GpuDevice> device = opening.get();
  print_cpu_device_note(device->info());
  RendererOptions renderer_options;
  if (options.precision == "double") renderer_options.shader.precision = Precision::float64;
  renderer_options.scene.search = *traversal_from_name(options.traversal);
  renderer_options.first_aovs = aovs;
  Renderer renderer(*device, scene, renderer_options);
  ViewsProgress progress;
  const ViewBatchSummary summary = render_views(renderer, batch, std::ref(progress));
  std::printf("vkray: %u views written, %u complete already (shard %u of %u, %zu views in all), to %s on %s; manifest %s\n",
              summary.rendered, summary.skipped, batch.shard.index, batch.shard.count, batch.views.size(),
              batch.exr.text().c_str(), device->info().name.c_str(), batch.manifest.c_str());
  if (summary.beyond_png16_samples > 0) {
    print_png16_note(summary.beyond_png16_samples, summary.beyond_png16_views, batch.output_settings.depth_step);
  }
  if (options.timings && summary.rendered > 0) {
    std::printf("timings: %.2f s for %u views, %.2f views/s (%.1f ms a view); the device %.2f s of it, waiting for the "
                "%u writers %.2f s\n",
                summary.seconds, summary.rendered, summary.rendered / summary.seconds, 1e3 * summary.seconds / summary.rendered,
                summary.render_seconds, summary.writers, summary.queue_wait_seconds);
  }
  return 0;
}

// What --timings prints of one render: each part's wall clock, then the scene and cache on the device.
struct RenderRunTimings {
  double load_ms = 0.0, device_open_ms = 0.0, device_wait_ms = 0.0, upload_ms = 0.0, render_ms = 0.0;
  double write_ms = 0.0, total_ms = 0.0;
  std::optional<double> reference_ms, measure_ms;  // where the reference ran, the error was measured
  bool staging = false;
  std::optional<RenderTimings> gpu_timings;  // none for --reference
  std::optional<SceneStats> scene_stats;
  std::string pipeline_cache;  // what --timings says of the device's pipeline cache
};

void print_render_timings(const RenderRunTimings& run, bool no_preview) {
  std::printf("timings (wall clock unless said; an indented line is a part of the line above it, and a line "
              "'beside' another ran at the same time, on another thread):\n");
  print_timing(0, "total", run.total_ms, "from the start of 'render' to the files in place");
  print_timing(1, "scene load", run.load_ms, "reading and checking the scene, the OBJ files it names");
  if (run.gpu_timings) {
    print_timing(1, "device open", run.device_open_ms, "beside the scene load, on a second thread");
    print_timing(1, "waiting for the device", run.device_wait_ms, "what the device open took beyond the scene load");
    print_timing(1, "upload", run.upload_ms,
                 run.staging ? "the scene to the device, through staging buffers (--transfer)"
                             : "the scene to the device, into memory the host maps (--transfer)");
    if (run.scene_stats->bvh_nodes > 0) print_timing(2, "BVH build", run.gpu_timings->bvh_build_ms);
    if (run.scene_stats->search == PrimitiveSearch::ray_query) {
      print_timing(2, "acceleration structures", run.gpu_timings->structures_ms,
                   "built and compacted by the device (--traversal ray-query)");
    }
    if (run.gpu_timings->pipeline_beside_upload_ms > 0.0) {
      print_timing(2, "pipeline creation", run.gpu_timings->pipeline_beside_upload_ms,
                   "beside the BVH build and upload, on a second thread");
    }
    print_timing(1, "render", run.render_ms);
    if (run.gpu_timings->pipeline_ms > 0.0) print_timing(2, "pipeline creation", run.gpu_timings->pipeline_ms);
    char longest[64];
    std::snprintf(longest, sizeof longest, ", the longest %.1f ms (budget %.0f)", run.gpu_timings->longest_dispatch_ms,
                  default_dispatch_budget_ms);
    const std::string dispatches = std::to_string(run.gpu_timings->tiles) +
                                   (run.gpu_timings->tiles == 1 ? " dispatch" : " dispatches" + std::string(longest));
    if (run.gpu_timings->has_gpu_times) {
      print_timing(2, "dispatch (GPU time)", run.gpu_timings->dispatch_gpu_ms, dispatches + ", timestamp queries");
    } else {
      std::printf("      %-24s %13s  %s\n", "dispatch (GPU time)", "n/a", "(the device has no timestamps)");
    }
    std::string readback_note;
    if (const uint64_t bytes = run.gpu_timings->readback_bytes; bytes > 0 && run.gpu_timings->readback_ms > 0.0) {
      char rate[96];
      std::snprintf(rate, sizeof rate, "%.1f MiB copied by the device, %.2f GB/s", static_cast<double>(bytes) / (1 << 20),
                    static_cast<double>(bytes) / (run.gpu_timings->readback_ms * 1e6));
      readback_note = rate;
      if (run.gpu_timings->readback_in_place_bytes > 0) readback_note += "; the outputs straight into the frame (imported host memory)";
    }
    print_timing(2, "readback", run.gpu_timings->readback_ms, readback_note);
    if (run.gpu_timings->unfinished_rays > 0) {
      print_timing(2, "finishing rays on the CPU", run.gpu_timings->cpu_finish_ms,
                   std::to_string(run.gpu_timings->unfinished_rays) + " rays past the loop budget");
    }
  }
  if (run.reference_ms) print_timing(1, "reference (CPU)", *run.reference_ms);
  if (run.measure_ms) print_timing(1, "error measurement", *run.measure_ms);
  print_timing(1, "file writing", run.write_ms, no_preview ? "the EXR" : "the EXR and the PNG at the same time");
  if (run.scene_stats) {
    const SceneStats& stats = *run.scene_stats;
    std::printf("scene on the device: %u triangles, %u spheres, %.1f MiB", stats.triangles, stats.spheres,
                static_cast<double>(stats.geometry_bytes) / (1 << 20));
    if (stats.triangles > 0 && stats.spheres == 0) {
      std::printf(" (%.1f bytes a triangle)", static_cast<double>(stats.geometry_bytes) / stats.triangles);
    }
    if (stats.bvh_nodes > 0) {
      std::printf("; BVH of %u nodes, depth %u, walked %s", stats.bvh_nodes, stats.bvh_depth,
                  stats.search == PrimitiveSearch::bvh_packet ? "by packets of rays" : "per ray");
    }
    std::printf("\n");
  }
  if (!run.pipeline_cache.empty()) std::printf("pipeline cache: %s\n", run.pipeline_cache.c_str());
  std::printf("peak host memory: %.1f MiB\n", static_cast<double>(peak_host_memory_bytes()) / (1 << 20));
}

int run_render(const RenderOptions& options) {
  if (options.views.any()) return run_render_views(options, parse_aov_list(options.aovs));
  Stopwatch stopwatch;
  const AovSet aovs = parse_aov_list(options.aovs);
  check_render_options(options, aovs);
  const std::filesystem::path preview =
      options.preview.value_or(std::filesystem::path(options.output).replace_extension(".png").string());
  // Before any work: a render must not take minutes only to find it cannot be saved.
  const OutputSettings settings = output_settings(options, aovs);
  std::vector<NamedFile> files;
  for (const OutputFile& file : output_files(options.output, aovs, settings.format)) {
    files.push_back({file.path, settings.format == FileFormat::exr ? "the EXR" : "the " + std::string(output_info(file.aov).name) + " output"});
  }
  if (!options.no_preview) files.push_back({preview, "the preview"});
  refuse_one_file_twice(files);
  for (const NamedFile& file : files) check_output_path(file.path);
  // The device opens on a second thread while the scene loads: neither needs the other, and each
  // takes 50-250 ms (the first device open after boot is the slowest). A failure surfaces at get(),
  // after the scene's own errors.
  struct OpenedDevice {
    std::unique_ptr<GpuDevice> device;
    double open_ms = 0.0;
  };
  std::future<OpenedDevice> opening;
  if (!options.reference) {
    opening = std::async(std::launch::async, [&options] {
      Stopwatch open_watch;
      auto device = std::make_unique<GpuDevice>(options.device_options.device, options.device_options.transfer_mode());
      return OpenedDevice{std::move(device), open_watch.lap_ms()};
    });
  }
  Scene scene = load_scene_argument(options.scene_path, options.width, options.height, options.view);
  if (options.camera) apply_camera_option(*options.camera, scene.camera);
  check_scene_camera(scene, options.camera.has_value(), options.scene_path);
  print_mask_note(scene, options.mask);
  const double load_ms = stopwatch.lap_ms();

  Frame frame;
  RenderRunTimings run;
  run.load_ms = load_ms;
  std::string device_name = "CPU reference (double precision)";
  std::optional<ReferenceScene> reference_scene;
  std::optional<std::vector<ReferenceHit>> reference_hits;
  auto reference = [&]() -> const std::vector<ReferenceHit>& {
    if (!reference_hits) {
      Stopwatch reference_watch;
      reference_scene.emplace(scene, static_cast<Mask>(options.mask));
      reference_hits = render_reference_hits(*reference_scene, scene.camera,
                                             scene.width, scene.height);
      run.reference_ms = reference_watch.lap_ms();
    }
    return *reference_hits;
  };

  if (options.reference) {
    const std::vector<ReferenceHit>& hits = reference();
    frame = reference_frame(*reference_scene, scene, hits, scene.camera, scene.width, scene.height, aovs);
    stopwatch.lap_ms();
  } else {
    const OpenedDevice opened = opening.get();
    GpuDevice& device = *opened.device;
    device_name = device.info().name;
    run.staging = device.transfer() == TransferMode::staging;
    run.pipeline_cache = device.pipeline_cache_file().empty()
                         ? std::string("none (VKRAY_CACHE_DIR=off, or no home folder)")
                         : std::to_string(device.pipeline_cache_bytes_read()) + " bytes read from " +
                               device.pipeline_cache_file().string();
    print_cpu_device_note(device.info());
    run.device_open_ms = opened.open_ms;
    run.device_wait_ms = stopwatch.lap_ms();
    ProgressLine progress("building the BVH");
    RendererOptions renderer_options;
    renderer_options.scene.bvh.progress = progress.callback();
    if (options.precision == "double") renderer_options.shader.precision = Precision::float64;
    renderer_options.scene.search = *traversal_from_name(options.traversal);
    renderer_options.first_aovs = aovs;
    Renderer renderer(device, scene, renderer_options);
    renderer.set_ray_mask(static_cast<Mask>(options.mask));
    run.upload_ms = stopwatch.lap_ms();
    frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
    run.render_ms = stopwatch.lap_ms();
    run.gpu_timings = renderer.timings();
    run.scene_stats = renderer.scene_stats();
  }

  std::optional<FrameError> error, float32_ray_error, stored_error;
  if (options.check) {
    const std::vector<ReferenceHit>& hits = reference();
    Stopwatch measure_watch;
    error = measure_error(frame, hits);
    // Beside it, what the float32 rays cost on their own: flips there are the ray's, not the search's.
    if (options.precision != "double") {
      float32_ray_error =
          measure_error(float32_ray_frame(*reference_scene, scene.camera, scene.width, scene.height, frame.aovs), hits);
    }
    // And what the file holds, where --half rounds outputs further.
    if (!options.half.empty()) stored_error = measure_error(stored_as_half(frame, half_outputs(options.half, aovs)), hits);
    run.measure_ms = measure_watch.lap_ms();
  }
  stopwatch.lap_ms();

  const size_t beyond_png16 = write_outputs(options.output, options.no_preview ? nullptr : &preview, frame, settings);
  std::string written;
  for (const OutputFile& file : output_files(options.output, frame.aovs, settings.format)) {
    written += (written.empty() ? "" : ", ") + file.path.string();
  }
  if (!options.no_preview) written += " and " + preview.string();
  run.write_ms = stopwatch.lap_ms();
  run.total_ms = stopwatch.total_ms();

  std::printf("vkray: wrote %s (%ux%u, %s) on %s\n", written.c_str(), scene.width, scene.height,
              aovs.names().c_str(), device_name.c_str());
  if (!options.no_preview && std::ranges::count(preview_panels(frame), Aov::depth) > 0) {
    std::printf("preview: %s\n", depth_legend(finite_depth_range(frame)).c_str());
  }
  // A model is framed by vkray: say from where, ready to paste (to render it again, or a neighbour).
  if (is_model_extension(lower_extension(options.scene_path)) || options.view) std::printf("camera: %s\n", camera_option(scene.camera).c_str());
  if (beyond_png16 > 0) print_png16_note(beyond_png16, 1, settings.depth_step);
  if (error) std::printf("error vs. double-precision reference: %s\n", error->summary().c_str());
  if (stored_error) std::printf("as stored, with --half %s: %s\n", options.half.c_str(), stored_error->summary().c_str());
  if (float32_ray_error) {
    std::printf("float32 rays alone (the exact scene along the shader's float32 ray directions, the "
                "floor of every float32 search; --precision double has none): %s\n",
                float32_ray_error->summary().c_str());
  }
  if (options.timings) print_render_timings(run, options.no_preview);
  return 0;
}

}  // namespace

Action add_render_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand("render", "Render a scene (or the built-in one) to OpenEXR and a PNG preview.");
  auto options = std::make_shared<RenderOptions>();
  command->add_option("scene", options->scene_path,
                      "Scene file (.json) or model (.obj, .ply, .gltf, .glb: seen from a glTF's camera, else framed automatically); the built-in scene when omitted");
  command->add_option("--view", options->view,
                      "Frame the scene (a model, or a scene file's geometry) from a side: front (default for models), "
                      "back, left, right, top, bottom, or the direction X,Y,Z from its centre to the eye");
  command->add_option("--camera", options->camera,
                      "Override the camera: 'from=X,Y,Z to=X,Y,Z up=X,Y,Z fovy=DEGREES' (any of the keys), or the "
                      "scene file's camera as JSON '{\"from\": [0, 1, 5]}'");
  CLI::Option* output = command->add_option("-o,--output", options->output,
                                             "OpenEXR file to write; with many views a name holding {index} or "
                                             "{index:05} (default view-{index:05}.exr)")
                            ->capture_default_str();
  command->add_option("--width", options->width, "Image width in pixels (overrides the scene)");
  command->add_option("--height", options->height, "Image height in pixels (overrides the scene)");
  command->add_option("--aov", options->aovs, "Outputs to compute, comma-separated ('_' or '-' between words): " + output_names())
      ->capture_default_str();
  CLI::Option* preview = command->add_option("--preview", options->preview, "PNG preview to write (default: the output with .png)");
  command->add_flag("--no-preview", options->no_preview, "Write no PNG preview")->excludes(preview);
  command->add_option("--compression", options->compression,
                      "OpenEXR compression, all lossless: zip, zips, piz, rle, none (fastest, largest); zip and zips "
                      "also with a deflate level from 1 (fastest) to 9, as zip:9")
      ->capture_default_str();
  command->add_option("--format", options->format,
                      "How the outputs are stored: exr (one OpenEXR file), npy (a NumPy .npy an output, as OUTPUT.depth.npy "
                      "for -o OUTPUT.exr, bit for bit the EXR's values) or png16 (a 16-bit PNG a depth, in steps of --depth-step; "
                      "0 where there is none)")
      ->capture_default_str();
  command->add_option("--depth-step", options->depth_step,
                      "With --format png16: the depth of one step of the 16-bit value (0.001: millimetres of a scene in metres), "
                      "recorded in the PNG as vkray:depth_step")
      ->capture_default_str();
  command->add_option("--half", options->half,
                      "Outputs among --aov's stored as half floats (relative rounding up to 2^-11, infinity beyond "
                      "65504), comma-separated; --check then also gives the error of what the file holds");
  command->add_option("--miss", options->miss,
                      "Depth written where the ray hits nothing (Z and planar.Z; A is 0 there): inf, -inf, nan or a "
                      "number such as 0")
      ->capture_default_str();
  CLI::Option* device = add_device_options(command, options->device_options);
  CLI::Option* precision = command->add_option("--precision", options->precision,
                      "Shader arithmetic: float (float32, camera-relative) or double (float64: exact, slower; needs "
                      "shaderFloat64)")
      ->check(CLI::IsMember({"float", "double"}))
      ->capture_default_str();
  add_traversal_option(command, options->traversal);
  add_mask_option(command, options->mask);
  command->add_flag("--timings", options->timings, "Print where the time went");
  add_views_options(command, options->views);
  CLI::Option* check = command->add_flag("--check", options->check,
                    "Also render the double-precision CPU reference and print the GPU's error against it");
  // The reference runs on the CPU in double: no device, no shader precision, nothing to check it against.
  command->add_flag("--reference", options->reference, "Render with the double-precision CPU reference instead")
      ->excludes(check)
      ->excludes(device)
      ->excludes(precision);
  return [options, output] {
    options->output_given = output->count() > 0;
    return run_render(*options);
  };
}

}  // namespace vkray::cli
