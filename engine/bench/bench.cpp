#include "engine/bench/bench.hpp"

#include "engine/bench/bench_report.hpp"
#include "engine/bench/embree_baseline.hpp"
#include "engine/bench/scratch_folder.hpp"
#include "engine/io/image_io.hpp"
#include "engine/parallel.hpp"
#include "engine/stopwatch.hpp"
#include "engine/views/view_batch.hpp"
#include "engine/views/view_list.hpp"

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <filesystem>
#include <limits>
#include <optional>
#include <thread>

namespace vkray {
namespace {

size_t finite_primitives(const Scene& scene) { return scene.triangle_count() + scene.spheres.size(); }

// A search's row. Brute force only up to bench_brute_force_max_primitives; the packet walk with the
// double edge functions it takes, the automatic choice on CPU devices alone, so that a GPU with
// shaderFloat64 runs it too.
BenchVariant search_variant(const SearchInfo& search) {
  BenchVariant variant{search.name, search.description, {}, CpuBaseline::none, {}};
  variant.options.scene.search = search.search;
  if (search.search == PrimitiveSearch::bvh_packet) variant.options.shader.edges = EdgeArithmetic::double_products;
  const size_t max_primitives = search.search == PrimitiveSearch::brute_force ? bench_brute_force_max_primitives : SIZE_MAX;
  variant.applies = [max_primitives](const Scene& scene) {
    return finite_primitives(scene) > 0 && finite_primitives(scene) <= max_primitives;
  };
  return variant;
}

BenchVariant shader_variant(std::string name, std::string description, ShaderVariant shader,
                            std::function<bool(const Scene&)> applies = [](const Scene&) { return true; }) {
  BenchVariant variant{std::move(name), std::move(description), {}, CpuBaseline::none, std::move(applies)};
  variant.options.shader = shader;
  return variant;
}

}  // namespace

std::optional<BenchVariant> views_variant(const std::string& name) {
  uint32_t views = 0;
  char format[8] = "exr";
  int length = 0;
  if ((std::sscanf(name.c_str(), "views-%u%n", &views, &length) != 1 || size_t(length) != name.size()) &&
      (std::sscanf(name.c_str(), "views-%u-%7[a-z0-9]%n", &views, format, &length) != 2 || size_t(length) != name.size())) {
    return std::nullopt;
  }
  const std::optional<FileFormat> stored = file_format_from_name(format);
  if (views == 0 || !stored) return std::nullopt;
  BenchVariant variant{name,
                       std::to_string(views) + " orbiting views rendered and written in one run (" + format +
                           "): wall time a view",
                       {}, CpuBaseline::none, [](const Scene& scene) { return finite_primitives(scene) > 0; }};
  variant.orbit_views = views;
  variant.views_format = *stored;
  return variant;
}

namespace {

BenchVariant outputs_variant(const std::string& name, const std::string& description, AovSet extra) {
  BenchVariant variant{name, description, {}, CpuBaseline::none, [](const Scene&) { return true; }};
  variant.extra_outputs = extra;
  return variant;
}

BenchVariant cpu_baseline(std::string name, std::string description, CpuBaseline baseline) {
  BenchVariant variant{std::move(name), std::move(description), {}, baseline, [](const Scene& scene) {
                         return finite_primitives(scene) > 0;  // Embree has nothing to trace for planes alone
                       }};
  return variant;
}

// The views of a many-views row are written to a folder of their own under the system's temporary
// folder, removed afterwards.
BenchRow run_views_variant(GpuDevice& device, const Scene& scene, const BenchVariant& variant,
                           const std::vector<ReferenceHit>& reference) {
  const AovSet aovs{Aov::depth, Aov::normal};
  RendererOptions options = variant.options;
  options.first_aovs = aovs;
  Renderer renderer(device, scene, options);
  BenchRow row;
  row.variant = variant.name;
  row.stats = renderer.scene_stats();
  row.error = measure_error(renderer.render(scene.camera, scene.width, scene.height, aovs), reference);
  row.upload_ms = renderer.timings().upload_ms;
  row.bvh_build_ms = renderer.timings().bvh_build_ms + renderer.timings().structures_ms;
  row.pipeline_ms = renderer.timings().pipeline_ms + renderer.timings().pipeline_beside_upload_ms;
  const ScratchFolder scratch("vkray-bench-views-");
  const std::filesystem::path& folder = scratch.path();
  ViewBatch batch;
  batch.views = orbit_views(scene.camera, variant.orbit_views);
  batch.width = scene.width;
  batch.height = scene.height;
  batch.aovs = aovs;
  batch.exr = OutputPattern((folder / "view-{index:05}.exr").string(), "views");
  batch.manifest = folder / "manifest.jsonl";
  batch.overwrite = true;
  batch.output_settings.format = variant.views_format;
  const ViewBatchSummary summary = render_views(renderer, batch);
  const double ms_a_view = 1e3 * summary.seconds / summary.rendered;
  row.gpu = time_stats({ms_a_view});
  row.frame_median_ms = ms_a_view;
  row.mrays_per_s = static_cast<double>(scene.width) * scene.height / (ms_a_view * 1e3);
  return row;
}

// One row from two rounds of it: the GPU frames pooled; the one-off costs and the host's median
// frame at their least disturbed (the smallest); the error of the later round (the same shader
// gives the same pixels).
BenchRow pooled_rows(const BenchRow& earlier, BenchRow later) {
  const double rays = later.mrays_per_s * later.gpu.median_ms * 1e3;
  later.gpu = pooled_time_stats(earlier.gpu, later.gpu);
  later.mrays_per_s = rays / (later.gpu.median_ms * 1e3);
  later.gpu_frames = later.gpu.samples_ms.size();
  later.upload_ms = std::min(earlier.upload_ms, later.upload_ms);
  later.bvh_build_ms = std::min(earlier.bvh_build_ms, later.bvh_build_ms);
  later.pipeline_ms = std::min(earlier.pipeline_ms, later.pipeline_ms);
  later.frame_median_ms = std::min(earlier.frame_median_ms, later.frame_median_ms);
  if (earlier.sustained_ms > 0.0) later.sustained_ms = std::min(earlier.sustained_ms, later.sustained_ms);
  return later;
}

BenchRow run_variant(GpuDevice& device, const Scene& scene, const BenchVariant& variant, const BenchTiming& timing,
                     const ReferenceScene& reference_scene, const std::vector<ReferenceHit>& reference) {
  AovSet aovs{Aov::depth, Aov::normal};
  for (const OutputInfo& output : outputs()) {
    if (variant.extra_outputs.has(output.aov)) aovs.add(output.aov);
  }
  Renderer renderer(device, scene, variant.options);
  BenchRow row;
  row.variant = variant.name;
  row.stats = renderer.scene_stats();
  Frame frame = renderer.render(scene.camera, scene.width, scene.height, aovs);  // warm-up, creates the pipeline
  row.upload_ms = renderer.timings().upload_ms;
  row.bvh_build_ms = renderer.timings().bvh_build_ms + renderer.timings().structures_ms;
  row.pipeline_ms = renderer.timings().pipeline_ms;
  std::vector<double> frame_ms;
  const std::vector<double> gpu_ms = timed_runs(timing, [&] {
    const auto start = Clock::now();
    frame = renderer.render(scene.camera, scene.width, scene.height, aovs);
    frame_ms.push_back(elapsed_ms(start));
    return renderer.timings().has_gpu_times ? renderer.timings().dispatch_gpu_ms : frame_ms.back();
  });
  frame_ms.erase(frame_ms.begin(), frame_ms.end() - static_cast<std::ptrdiff_t>(gpu_ms.size()));  // the timed ones
  row.gpu = time_stats(gpu_ms);
  row.frame_median_ms = median(frame_ms);
  if (timing.sustained_burst_ms > 0.0 && scene.camera.projection == Projection::perspective) {
    // Three bursts of as many passes as keep the device busy that long, each sized by the last
    // pass time seen (the first burst brings the clocks up); the fastest is taken.
    constexpr double most_passes = 5000;
    auto passes_for = [&](double ms_a_pass) {
      return static_cast<uint32_t>(std::clamp(timing.sustained_burst_ms / std::max(ms_a_pass, 1e-3), 1.0, most_passes));
    };
    double last = row.gpu.min_ms;
    row.sustained_ms = std::numeric_limits<double>::infinity();
    for (int burst = 0; burst < 3; ++burst) {
      last = renderer.sustained_dispatch_ms(scene.camera, scene.width, scene.height, aovs, passes_for(last));
      row.sustained_ms = std::min(row.sustained_ms, last);
    }
  }
  row.mrays_per_s = static_cast<double>(frame.pixel_count()) / (row.gpu.median_ms * 1e3);
  row.unfinished_rays = renderer.timings().unfinished_rays;
  row.error = measure_error(frame, reference);
  if (!variant.extra_outputs.empty()) {
    row.outputs = measure_output_errors(
        frame, reference_frame(reference_scene, scene, reference, scene.camera, scene.width, scene.height, aovs));
  }
  return row;
}

}  // namespace

std::vector<double> timed_runs(const BenchTiming& timing, const std::function<double()>& frame) {
  // Far more than any timing needs: a bound on frames of a few microseconds.
  constexpr size_t most_frames = 100'000;
  for (const auto start = Clock::now(); elapsed_ms(start) < timing.warm_up_ms;) frame();
  std::vector<double> times;
  const auto start = Clock::now();
  while (times.size() < std::max(timing.frames, 1u) || (elapsed_ms(start) < timing.min_timed_ms && times.size() < most_frames)) {
    times.push_back(frame());
  }
  return times;
}

const std::vector<BenchVariant>& bench_variants() {
  auto has_spheres = [](const Scene& scene) { return !scene.spheres.empty(); };
  auto has_triangles = [](const Scene& scene) { return scene.triangle_count() > 0; };
  ShaderVariant naive_sphere, moller_trumbore, generic, stack_in_memory, scene_anchor, absolute, float64, naive;
  stack_in_memory.stack_in_registers = false;
  ShaderVariant float_edges, double_edges, storage_geometry;
  float_edges.edges = EdgeArithmetic::float_error_free;
  double_edges.edges = EdgeArithmetic::double_products;
  storage_geometry.storage_geometry = true;

  naive_sphere.sphere_formula = VKRAY_SPHERE_NAIVE;
  moller_trumbore.triangle_test = VKRAY_TRIANGLE_MOLLER_TRUMBORE;
  generic.generic = true;
  scene_anchor.coordinates = VKRAY_COORDINATES_SCENE_ANCHOR;
  absolute.coordinates = VKRAY_COORDINATES_ABSOLUTE;
  float64.precision = Precision::float64;
  naive.sphere_formula = VKRAY_SPHERE_NAIVE;
  naive.triangle_test = VKRAY_TRIANGLE_MOLLER_TRUMBORE;
  naive.coordinates = VKRAY_COORDINATES_ABSOLUTE;
  static const std::vector<BenchVariant> variants = {
      shader_variant("default", "what vkray render uses", ShaderVariant{}),
      shader_variant("generic", "not specialized: every primitive type and output, counts at run time", generic),
      shader_variant("stack-in-memory", "the tree walk's stack in an array, not registers", stack_in_memory,
                     [](const Scene& scene) {
                       return choose_search(scene.triangle_count(), scene.spheres.size()) != PrimitiveSearch::brute_force;
                     }),
      shader_variant("float-edges", "triangle edge functions in float with an error-free fallback (what GPUs run)",
                     float_edges, has_triangles),
      shader_variant("double-edges", "triangle edge functions from double products (what CPU devices run)", double_edges,
                     has_triangles),
      shader_variant("storage-geometry", "geometry read from storage buffers, not texel buffers (GPUs' usual fast path)",
                     storage_geometry),
      shader_variant("rows-8x8", "8x8 workgroups row by row instead of Morton order", with_workgroup(8, 8, false)),
      shader_variant("wg-16x16", "16x16 workgroups in Morton order", with_workgroup(16, 16, true)),
      shader_variant("wg-64x1", "64x1 workgroups", with_workgroup(64, 1, false)),
      shader_variant("naive-sphere", "textbook ray/sphere (b^2 - c)", naive_sphere, has_spheres),
      shader_variant("moller-trumbore", "Moeller-Trumbore triangles (not watertight)", moller_trumbore, has_triangles),
      shader_variant("scene-anchor", "float32 positions relative to the scene's centre, not the camera", scene_anchor),
      shader_variant("absolute", "float32 world coordinates", absolute),
      shader_variant("naive", "every textbook choice: b^2 - c spheres, Moeller-Trumbore, float32 world coordinates",
                     naive),
      shader_variant("float64", "the shader in double precision (--precision double)", float64),
      *views_variant("views-100"),
      cpu_baseline("embree-1", "Embree 3 on the CPU, all threads, one ray at a time", CpuBaseline::embree_single),
      cpu_baseline("embree-8", "Embree 3 on the CPU, all threads, packets of 8 rays", CpuBaseline::embree_packet),
  };
  // Then the outputs' rows, before Embree's: each camera output on its own, the ids and the surface
  // outputs each together, and every output.
  static const std::vector<BenchVariant> with_outputs = [] {
    // The default, then a row for each search (engine/render/search.hpp), then the shader's variants.
    std::vector<BenchVariant> all(variants.begin(), variants.begin() + 1);
    for (const SearchInfo& search : searches()) all.push_back(search_variant(search));
    all.insert(all.end(), variants.begin() + 1, variants.end() - 2);
    AovSet ids, surface, every;
    for (const OutputInfo& output : outputs()) {
      if (output.source == OutputSource::device) continue;
      every.add(output.aov);
      if (output.source == OutputSource::camera) {
        all.push_back(outputs_variant(std::string("+") + output.name, "the default with the " + std::string(output.name) + " output too",
                                      {output.aov}));
      }
      if (output.source == OutputSource::ids) ids.add(output.aov);
      if (output.source == OutputSource::surface) surface.add(output.aov);
    }
    all.push_back(outputs_variant("+ids", "the default with " + ids.names() + " too", ids));
    all.push_back(outputs_variant("+surface", "the default with " + surface.names() + " too", surface));
    all.push_back(outputs_variant("+every-output", "the default with every output too", every));
    all.insert(all.end(), variants.end() - 2, variants.end());
    return all;
  }();
  return with_outputs;
}

const BenchVariant& find_bench_variant(const std::string& name) {
  std::string known;
  for (const auto& variant : bench_variants()) {
    if (variant.name == name) return variant;
    known += (known.empty() ? "" : ", ") + variant.name;
  }
  throw InputError("--variants: unknown variant '" + name + "' (choose from " + known + ")");
}

BenchSceneRun::BenchSceneRun(const BenchScene& bench, const BenchSettings& settings)
    : scene_(bench.scene),
      timing_{settings.frames, settings.warm_up_ms, settings.min_timed_ms, settings.sustained_burst_ms},
      reference_scene_(bench.scene) {
  const Scene& scene = bench.scene;
  result_.name = bench.name;
  result_.hash = scene_hash(scene);
  result_.width = scene.width;
  result_.height = scene.height;
  result_.triangles = scene.triangle_count();
  result_.spheres = scene.spheres.size();
  result_.planes = scene.planes.size();

  const auto reference_start = Clock::now();
  reference_ = render_reference_hits(reference_scene_, scene.camera, scene.width, scene.height, settings.reference_progress);
  result_.reference_ms = elapsed_ms(reference_start);
  if (settings.float32_ray_error) {
    result_.float32_ray = measure_error(float32_ray_frame(reference_scene_, scene.camera, scene.width, scene.height), reference_);
  }
}

BenchRow BenchSceneRun::row(GpuDevice& device, const BenchVariant& variant) {
  if (variant.cpu != CpuBaseline::none) {
    if (!embree_) embree_ = trace_with_embree(scene_, scene_.width, scene_.height, timing_.frames);
    BenchRow row;
    row.variant = variant.name;
    row.on_gpu = false;
    row.bvh_build_ms = embree_->build_ms;
    row.gpu = variant.cpu == CpuBaseline::embree_single ? embree_->single : embree_->packet;
    row.mrays_per_s = static_cast<double>(scene_.width) * scene_.height / (row.gpu.median_ms * 1e3);
    row.error = measure_error(embree_->frame, reference_);
    row.gpu_frames = row.gpu.samples_ms.size();
    return row;
  }
  BenchRow row = variant.orbit_views > 0 ? run_views_variant(device, scene_, variant, reference_)
                                         : run_variant(device, scene_, variant, timing_, reference_scene_, reference_);
  row.gpu_frames = row.gpu.samples_ms.size();
  return row;
}

BenchSceneResult bench_scene(GpuDevice& device, const BenchScene& bench, const BenchSettings& settings) {
  BenchSceneRun run(bench, settings);
  BenchSceneResult& result = run.result();
  std::vector<const BenchVariant*> chosen;
  for (const auto& name : settings.variants) chosen.push_back(&find_bench_variant(name));
  if (settings.variants.empty()) {
    for (const auto& variant : bench_variants()) {
      if (variant.orbit_views == 0 && variant.extra_outputs.empty()) chosen.push_back(&variant);
    }
  }
  std::erase_if(chosen, [&](const BenchVariant* variant) {
    if (variant->applies(bench.scene)) return false;
    if (!settings.variants.empty()) result.skipped.push_back(variant->name + " (does not apply)");
    return true;
  });
  std::vector<std::optional<BenchRow>> rows(chosen.size());
  for (uint32_t round = 0; round < std::max(settings.rounds, 1u); ++round) {
    run.next_round();
    for (size_t k = 0; k < chosen.size(); ++k) {
      const size_t index = round % 2 == 0 ? k : chosen.size() - 1 - k;  // every other round backwards
      if (round > 0 && !rows[index]) continue;  // the device could not run it
      try {
        BenchRow row = run.row(device, *chosen[index]);
        rows[index] = rows[index] ? pooled_rows(*rows[index], std::move(row)) : std::move(row);
      } catch (const DeviceLostError&) {
        throw;  // nothing more can run on it
      } catch (const GpuError& error) {  // e.g. a workgroup shape or loop count this device lacks
        result.skipped.push_back(chosen[index]->name + " (" + error.what() + ")");
        rows[index].reset();
      }
    }
  }
  for (auto& row : rows) {
    if (row) result.rows.push_back(std::move(*row));
  }

  mark_pareto_front(result.rows);
  return std::move(result);
}

void mark_pareto_front(std::vector<BenchRow>& rows) {
  auto errors = [](const BenchRow& row) {
    return std::array<double, 3>{static_cast<double>(row.error.hit_mismatches), row.error.depth_p99, row.error.normal_deg_p99};
  };
  for (auto& row : rows) {
    const auto mine = errors(row);
    row.pareto = std::none_of(rows.begin(), rows.end(), [&](const BenchRow& other) {
      // Time by the spreads of the frames: overlapping ones are a tie, not a win for either.
      bool no_worse = !row.gpu.clearly_faster_than(other.gpu), better = other.gpu.clearly_faster_than(row.gpu);
      const auto theirs = errors(other);
      for (size_t k = 0; k < mine.size(); ++k) {
        no_worse = no_worse && theirs[k] <= mine[k];
        better = better || theirs[k] < mine[k];
      }
      return no_worse && better;
    });
  }
}

}  // namespace vkray
