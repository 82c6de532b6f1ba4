#include "engine/bench/gpu_report.hpp"

#include "engine/bench/bench.hpp"
#include "engine/bench/bench_report.hpp"
#include "engine/bench/given_rays_bench.hpp"
#include "engine/bench/stiff_cases.hpp"
#include "engine/reference/envelope.hpp"
#include "engine/render/renderer.hpp"
#include "engine/render/search.hpp"
#include "engine/scene/scene_or_model.hpp"
#include "engine/stopwatch.hpp"
#include "engine/vulkan/raycast_pipeline.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <optional>
#include <ostream>
#include <thread>

namespace vkray {
namespace {

using Json = nlohmann::ordered_json;

// What --precision double promises (docs/precision.md): the report measures whether this device keeps it.
constexpr double float64_promise = 1e-12;

// The models the report renders, by file name in the models folder; a generated mesh where the
// folder lacks them (engine/bench/bench_suites.cpp, the basic suite).
constexpr const char* report_models[] = {"stanford-bunny.obj", "stanford-dragon-100k.obj"};
constexpr const char* stand_in_model = "sphere-mesh-80k";

// The sizes, rays and views of a report (ReportSettings::reduced).
struct ReportScale {
  uint32_t small_width, small_height, large_width, large_height, huge_width, huge_height;
  uint32_t check_width, check_height;  // the models' checks: every pixel against the envelope
  uint32_t frames;
  double warm_up_ms, min_timed_ms, sustained_burst_ms;  // BenchTiming: a GPU's clocks rise under load
  size_t rays;
  uint32_t views, views_width, views_height;
  double timeout_s;  // a group's, the checks twice that
};

ReportScale scale_of(const ReportSettings& settings) {
  if (settings.reduced) return {320, 180, 640, 360, 1280, 720, 160, 90, 2, 0.0, 0.0, 20.0, 65536, 8, 320, 180, 90.0};
  return {1920, 1080, 3840, 2160, 7680, 4320, 640, 360, 10, 300.0, 300.0, 200.0, 1u << 20, 100, 1920, 1080, 150.0};
}

BenchTiming timing_of(const ReportSettings& settings) {
  const ReportScale scale = scale_of(settings);
  return {scale.frames, scale.warm_up_ms, scale.min_timed_ms, scale.sustained_burst_ms};
}

// The stiff cases at the tests' size (tests/stiff_cases_test.cpp); cases about image sizes keep
// theirs, and the reduced report leaves out those above a million pixels (lavapipe takes a minute).
constexpr uint32_t stiff_width = 64, stiff_height = 48;

std::vector<StiffCase> report_stiff_cases(const ReportSettings& settings) {
  std::vector<StiffCase> cases = stiff_cases(stiff_width, stiff_height);
  if (settings.reduced) {
    std::erase_if(cases, [](const StiffCase& stiff) { return size_t{stiff.scene.width} * stiff.scene.height > 1'000'000; });
  }
  return cases;
}

// The default, a row for each search (engine/render/search.hpp), then `layouts`: what the checks and
// the bench try, every traversal and geometry layout a device may take.
std::vector<std::string> default_searches_and(std::initializer_list<const char*> layouts) {
  std::vector<std::string> rows = {"default"};
  for (const SearchInfo& search : searches()) rows.emplace_back(search.name);
  rows.insert(rows.end(), layouts.begin(), layouts.end());
  return rows;
}
const std::vector<std::string> check_variants = default_searches_and({"float-edges", "double-edges", "storage-geometry"});
const std::vector<std::string> bench_rows = default_searches_and(
    {"float-edges", "double-edges", "storage-geometry", "wg-16x16", "wg-64x1", "float64", "embree-1", "embree-8"});
const std::vector<std::string> huge_rows = {"default", "per-ray", "packet", "storage-geometry", "embree-8"};
const std::vector<std::string> transfers = {"staging", "direct"};

// The models present, or the stand-in.
std::vector<std::string> model_names(const ReportSettings& settings) {
  std::vector<std::string> names;
  for (const char* model : report_models) {
    std::error_code error;
    if (std::filesystem::is_regular_file(settings.models_dir / model, error)) names.push_back(model);
  }
  if (names.empty()) names.push_back(stand_in_model);
  return names;
}

// A group's scene and size are in its id: SECTION-SCENE-WxH; SCENE is a model's file name, the
// stand-in's name or a scene file's index in ReportSettings::scene_files ("scene0").
struct GroupScene {
  std::string scene;
  uint32_t width = 0, height = 0;
};

std::string group_id(const std::string& section, const std::string& scene, uint32_t width, uint32_t height) {
  return section + "-" + scene + "-" + std::to_string(width) + "x" + std::to_string(height);
}

GroupScene parse_group_scene(const std::string& id) {
  const size_t size_at = id.rfind('-');
  const size_t scene_at = id.find('-');
  GroupScene result;
  result.scene = id.substr(scene_at + 1, size_at - scene_at - 1);
  const std::string size = id.substr(size_at + 1);
  result.width = static_cast<uint32_t>(std::stoul(size.substr(0, size.find('x'))));
  result.height = static_cast<uint32_t>(std::stoul(size.substr(size.find('x') + 1)));
  return result;
}

Scene load_group_scene(const ReportSettings& settings, const std::string& scene, uint32_t width, uint32_t height) {
  if (scene == stand_in_model) {
    for (auto& bench : basic_scenes(width, height)) {
      if (bench.name == stand_in_model) return std::move(bench.scene);
    }
    throw std::logic_error("the basic suite has no " + std::string(stand_in_model));
  }
  if (scene.starts_with("scene")) return load_scene_or_model(settings.scene_files.at(std::stoul(scene.substr(5))), width, height);
  return load_scene_or_model(settings.models_dir / scene, width, height);
}

std::string scene_label(const ReportSettings& settings, const std::string& scene) {
  if (scene.starts_with("scene")) return settings.scene_files.at(std::stoul(scene.substr(5))).filename().string();
  return scene;
}

// One row's line: where it belongs, how it ended, and its figures.
Json row_head(const ReportGroup& group, size_t row, const std::string& status, const std::string& reason = {}) {
  Json line = {{"group", group.id}, {"section", group.section}, {"row", group.rows.at(row)}, {"status", status}};
  if (!reason.empty()) line["reason"] = reason;
  return line;
}

void emit(std::ostream& out, const Json& line) {
  out << line.dump() << '\n';
  out.flush();
}

Json error_json(const FrameError& error) {
  return {{"pixels", error.pixels},
          {"hit_mismatches", error.hit_mismatches},
          {"nan_pixels", error.nan_pixels},
          {"depth_rel_p99", error.depth_p99},
          {"depth_rel_max", error.depth_max},
          {"normal_deg_p99", error.normal_deg_p99},
          {"normal_deg_max", error.normal_deg_max}};
}

// Why `variant` cannot run on `device` (empty where it can): the traversal's needs, float64.
std::string variant_obstacle(const BenchVariant& variant, const GpuDeviceInfo& device) {
  if (variant.cpu != CpuBaseline::none) return {};
  const ShaderVariant& shader = variant.options.shader;
  const bool doubles = shader.precision == Precision::float64 ||
                       resolve_edges(device, shader.edges) == EdgeArithmetic::double_products;
  if (doubles && !device.shader_float64) return device.name + " has no float64 arithmetic in shaders (shaderFloat64)";
  return search_obstacle(variant.options.scene.search, device, shader);
}

Json device_json(GpuDevice& device, const std::string& device_choice) {
  const GpuDeviceInfo& d = device.info();
  const std::vector<GpuDeviceInfo> devices = list_gpu_devices();
  Json listed = Json::array();
  for (const auto& other : devices) listed.push_back(other.name + " (" + other.type + ")");
  return {{"name", d.name},
          {"type", d.type},
          {"driver", d.driver},
          {"api_version", d.api_version},
          {"uuid", d.uuid},
          {"subgroup_size", d.subgroup_size},
          {"shader_float64", d.shader_float64},
          {"fast_float64", d.fast_float64},
          {"ray_query", d.ray_query},
          {"timestamps", d.timestamp_period_ns > 0.0},
          {"max_storage_buffer_range", d.max_storage_buffer_range},
          {"max_loop_iterations", d.max_loop_iterations},
          {"favours_packet_walk", d.favours_packet_walk},
          {"transfer_auto", automatic_transfer(d).mode == TransferMode::direct ? "direct" : "staging"},
          {"transfer_auto_reason", automatic_transfer(d).reason},
          {"transfer", device.transfer_description()},
          {"validation", device.validation()},
          {"overridden", d.overridden},
          {"asked_for", device_choice},
          {"listed", listed},
          {"vulkan_loader", vulkan_loader_description()},
          {"cpu_note", cpu_device_note(d)},
          {"host_threads", std::thread::hardware_concurrency()}};
}

void run_check(const ReportGroup& group, size_t index, GpuDevice& device, const ReportSettings& settings,
               std::ostream& out) {
  const std::string& row = group.rows[index];
  const ReportScale scale = scale_of(settings);
  Json line = row_head(group, index, "ok");
  if (row.starts_with("stiff/")) {
    const std::string name = row.substr(6);
    const std::vector<StiffCase> cases = report_stiff_cases(settings);
    const auto stiff = std::find_if(cases.begin(), cases.end(), [&](const StiffCase& c) { return c.name == name; });
    if (stiff == cases.end()) throw std::logic_error("no stiff case " + name);
    Renderer renderer(device, stiff->scene);
    const Frame frame = renderer.render(stiff->scene.camera, stiff->scene.width, stiff->scene.height, {Aov::depth, Aov::normal});
    // Above a million pixels every 64th row, as the tests check them.
    const uint32_t row_step = frame.pixel_count() > 1'000'000 ? 64 : 1;
    const EnvelopeReport report = check_against_reference(stiff->scene, frame, row_step);
    line["what"] = stiff->what;
    line["width"] = stiff->scene.width, line["height"] = stiff->scene.height;
    line["envelope_failures"] = report.failures;
    line["pass"] = report.failures == 0 && report.stats.nan_pixels == 0;
    line["error"] = error_json(report.stats);
    if (!report.first_failures.empty()) line["first_failure"] = report.first_failures.front();
    emit(out, line);
    return;
  }
  const bool float64 = row.starts_with("float64/");
  const std::string model = float64 ? row.substr(8) : row.substr(0, row.find('/'));
  const BenchVariant& variant = find_bench_variant(float64 ? "float64" : row.substr(row.find('/') + 1));
  if (const std::string obstacle = variant_obstacle(variant, device.info()); !obstacle.empty()) {
    emit(out, row_head(group, index, "skipped", obstacle));
    return;
  }
  const Scene scene = load_group_scene(settings, model, scale.check_width, scale.check_height);
  if (!variant.applies(scene)) {
    emit(out, row_head(group, index, "skipped", "does not apply to this scene"));
    return;
  }
  Renderer renderer(device, scene, variant.options);
  const Frame frame = renderer.render(scene.camera, scene.width, scene.height, {Aov::depth, Aov::normal});
  line["width"] = scene.width, line["height"] = scene.height;
  line["search"] = traversal_name(renderer.scene_stats().search);
  if (float64) {
    const ReferenceScene reference(scene);
    const FrameError error = measure_error(frame, render_reference_hits(reference, scene.camera, scene.width, scene.height));
    line["promise"] = float64_promise;
    line["pass"] = error.hit_mismatches == 0 && error.depth_max <= float64_promise;
    line["error"] = error_json(error);
  } else {
    const EnvelopeReport report = check_against_reference(scene, frame);
    line["envelope_failures"] = report.failures;
    line["pass"] = report.failures == 0 && report.stats.nan_pixels == 0;
    line["error"] = error_json(report.stats);
    if (!report.first_failures.empty()) line["first_failure"] = report.first_failures.front();
  }
  emit(out, line);
}

Json bench_row_json(const BenchRow& row) {
  return {{"on_gpu", row.on_gpu},
          {"search", row.on_gpu ? traversal_name(row.stats.search) : "embree"},
          {"gpu_median_ms", row.gpu.median_ms},
          {"gpu_min_ms", row.gpu.min_ms},
          {"gpu_sustained_ms", row.sustained_ms},
          {"frame_median_ms", row.frame_median_ms},
          {"mrays_per_s", row.mrays_per_s},
          {"upload_ms", row.upload_ms},
          {"pipeline_ms", row.pipeline_ms},
          {"geometry_bytes", row.stats.geometry_bytes},
          {"error", error_json(row.error)}};
}

void run_bench_group(const ReportGroup& group, size_t first, GpuDevice& device, const ReportSettings& settings,
                     std::ostream& out, const std::function<bool(size_t)>& skip_failed) {
  const GroupScene where = parse_group_scene(group.id);
  const BenchScene bench{scene_label(settings, where.scene), load_group_scene(settings, where.scene, where.width, where.height)};
  BenchSettings bench_settings;
  bench_settings.frames = scale_of(settings).frames;
  bench_settings.warm_up_ms = scale_of(settings).warm_up_ms;
  bench_settings.min_timed_ms = scale_of(settings).min_timed_ms;
  bench_settings.sustained_burst_ms = scale_of(settings).sustained_burst_ms;
  BenchSceneRun run(bench, bench_settings);
  for (size_t index = first; index < group.rows.size(); ++index) {
    if (skip_failed(index)) continue;
    const std::string& name = group.rows[index];
    const std::optional<BenchVariant> views = views_variant(name);
    const BenchVariant variant = views ? *views : find_bench_variant(name);
    if (!variant.applies(bench.scene)) {
      emit(out, row_head(group, index, "skipped", "does not apply to this scene"));
      continue;
    }
    if (const std::string obstacle = variant_obstacle(variant, device.info()); !obstacle.empty()) {
      emit(out, row_head(group, index, "skipped", obstacle));
      continue;
    }
    Json line = row_head(group, index, "ok");
    line["scene"] = bench.name;
    line["width"] = where.width, line["height"] = where.height;
    line["triangles"] = bench.scene.triangle_count();
    line["reference_ms"] = run.result().reference_ms;
    try {
      const BenchRow row = run.row(device, variant);
      line.update(bench_row_json(row));
      if (variant.orbit_views > 0) line["views"] = variant.orbit_views, line["views_per_s"] = 1e3 / row.gpu.median_ms;
    } catch (const DeviceLostError&) {
      throw;
    } catch (const GpuError& error) {
      line = row_head(group, index, "failed", error.what());
    }
    emit(out, line);
  }
}

// The same frames with each transfer: what reading the outputs back costs (the frame's wall time
// against its GPU time).
void run_transfer(const ReportGroup& group, size_t index, const std::string& device_choice, const ReportSettings& settings,
                  std::ostream& out) {
  const GroupScene where = parse_group_scene(group.id);
  const Scene scene = load_group_scene(settings, where.scene, where.width, where.height);
  GpuDevice device(device_choice, group.rows[index] == "direct" ? TransferMode::direct : TransferMode::staging);
  Renderer renderer(device, scene);
  const AovSet aovs{Aov::depth, Aov::normal};
  renderer.render(scene.camera, scene.width, scene.height, aovs);  // the first frame: the pipeline
  // Two timed frames, and more within the timing's time: reading a discrete GPU's memory directly
  // takes seconds a frame.
  BenchTiming timing = timing_of(settings);
  timing.frames = 2;
  std::vector<double> gpu_ms, readback_ms;
  const std::vector<double> frame_ms = timed_runs(timing, [&] {
    const auto start = Clock::now();
    renderer.render(scene.camera, scene.width, scene.height, aovs);
    gpu_ms.push_back(renderer.timings().dispatch_gpu_ms);
    readback_ms.push_back(renderer.timings().readback_ms);
    return elapsed_ms(start);
  });
  gpu_ms.erase(gpu_ms.begin(), gpu_ms.end() - static_cast<std::ptrdiff_t>(frame_ms.size()));
  readback_ms.erase(readback_ms.begin(), readback_ms.end() - static_cast<std::ptrdiff_t>(frame_ms.size()));
  Json line = row_head(group, index, "ok");
  line["scene"] = scene_label(settings, where.scene);
  line["width"] = where.width, line["height"] = where.height;
  line["transfer"] = device.transfer_description();
  line["frame_median_ms"] = median(frame_ms);
  line["gpu_median_ms"] = median(gpu_ms);
  line["readback_median_ms"] = median(readback_ms);
  // The frame's outputs over the readback's time: what the link (staging) or the host's copy (direct) moved.
  line["readback_gb_per_s"] = static_cast<double>(Frame::bytes(where.width, where.height, aovs, false)) /
                              (median(readback_ms) * 1e6);
  line["readback_in_place"] = renderer.timings().readback_in_place_bytes > 0;
  emit(out, line);
}

void run_rays(const ReportGroup& group, size_t index, GpuDevice& device, const ReportSettings& settings, std::ostream& out) {
  const GroupScene where = parse_group_scene(group.id);
  const Scene scene = load_group_scene(settings, where.scene, where.width, where.height);
  const std::string& kind = group.rows[index];
  const std::vector<GivenRay> rays = make_rays(*ray_kind_from_name(kind), scene, scale_of(settings).rays);
  const GivenRaysRow row = bench_given_rays(device, scene, kind, rays, timing_of(settings));
  Json line = row_head(group, index, "ok");
  line["scene"] = scene_label(settings, where.scene);
  line["rays"] = row.rays;
  line["walk"] = row.walk;
  line["vkray_median_ms"] = row.vkray.median_ms, line["vkray_min_ms"] = row.vkray.min_ms;
  line["embree_median_ms"] = row.embree.median_ms, line["embree_min_ms"] = row.embree.min_ms;
  line["embree_threads"] = row.embree_threads;
  line["hit_mismatches"] = row.hit_mismatches, line["both_hit"] = row.both_hit;
  line["t_rel_p99"] = row.t_rel_p99, line["t_rel_max"] = row.t_rel_max;
  line["embree_hit_mismatches"] = row.embree_hit_mismatches, line["embree_t_rel_p99"] = row.embree_t_rel_p99;
  emit(out, line);
}

}  // namespace

std::string report_row_variant(const ReportGroup& group, const std::string& row) {
  if (group.section == "checks") {
    if (row.starts_with("stiff/")) return "default";
    if (row.starts_with("float64/")) return "float64";
    return row.substr(row.find('/') + 1);
  }
  return row;
}

std::vector<ReportGroup> report_plan(const ReportSettings& settings) {
  const ReportScale scale = scale_of(settings);
  const std::vector<std::string> models = model_names(settings);
  auto checks = [&](const std::string& transfer) {
    ReportGroup group{"checks-" + transfer, "checks", {}, 2 * scale.timeout_s};
    for (const StiffCase& stiff : report_stiff_cases(settings)) group.rows.push_back("stiff/" + stiff.name);
    for (const std::string& model : models) {
      for (const std::string& variant : check_variants) group.rows.push_back(model + "/" + variant);
    }
    group.rows.push_back("float64/" + models.front());
    return group;
  };
  std::vector<std::string> scenes = models;
  for (size_t k = 0; k < settings.scene_files.size(); ++k) scenes.push_back("scene" + std::to_string(k));
  auto bench = [&](std::vector<ReportGroup>& plan, uint32_t width, uint32_t height) {
    for (const std::string& scene : scenes) plan.push_back({group_id("bench", scene, width, height), "bench", bench_rows, scale.timeout_s});
  };
  std::vector<std::string> kinds;
  for (const auto& kind : ray_kinds()) kinds.push_back(kind.name);
  // Most telling first, where the time may not hold them all: staging is what a discrete GPU takes,
  // so its checks come first and the direct transfer's last.
  std::vector<ReportGroup> plan;
  plan.push_back({"device", "device", {"device"}, 60.0});
  plan.push_back(checks("staging"));
  bench(plan, scale.small_width, scale.small_height);
  plan.push_back({group_id("rays", models.front(), scale.small_width, scale.small_height), "rays", kinds, scale.timeout_s});
  plan.push_back({group_id("views", models.front(), scale.views_width, scale.views_height), "views",
                  {"views-" + std::to_string(scale.views), "views-" + std::to_string(scale.views) + "-npy"}, scale.timeout_s});
  plan.push_back({group_id("transfer", models.front(), scale.large_width, scale.large_height), "transfer", transfers, scale.timeout_s});
  for (const auto& [width, height] : {std::pair{scale.large_width, scale.large_height}, {scale.huge_width, scale.huge_height}}) {
    plan.push_back({group_id("process", models.front(), width, height), "process", {"render"}, scale.timeout_s});
  }
  bench(plan, scale.large_width, scale.large_height);
  plan.push_back({group_id("bench", models.front(), scale.huge_width, scale.huge_height), "bench", huge_rows, scale.timeout_s});
  plan.push_back(checks("direct"));
  return plan;
}

void run_report_group(const ReportSettings& settings, const ReportGroup& group, size_t first,
                      const std::string& device_choice, std::ostream& out) {
  // Rows of variants that ended an earlier group's process, skipped up front; the rest run below.
  ReportGroup runs = group;
  for (size_t index = first; index < group.rows.size(); ++index) {
    const std::string variant = report_row_variant(group, group.rows[index]);
    const auto& failed = settings.failed_variants;
    if (std::find(failed.begin(), failed.end(), variant) != failed.end()) runs.rows[index].clear();
  }
  auto skip_failed = [&](size_t index) {
    if (!runs.rows[index].empty()) return false;
    emit(out, row_head(group, index, "skipped",
                       "'" + report_row_variant(group, group.rows[index]) +
                           "' ended its process in an earlier group of this report (see that group's failed row)"));
    return true;
  };
  if (group.section == "process") throw std::logic_error("the report's process rows are run by the CLI, which starts processes");
  if (group.section == "transfer") {
    for (size_t index = first; index < group.rows.size(); ++index) {
      if (!skip_failed(index)) run_transfer(group, index, device_choice, settings, out);
    }
    return;
  }
  const TransferMode transfer = group.id == "checks-direct"    ? TransferMode::direct
                                : group.id == "checks-staging" ? TransferMode::staging
                                                               : TransferMode::automatic;
  GpuDevice device(device_choice, transfer);
  if (group.section == "device") {
    Json line = row_head(group, 0, "ok");
    line["device"] = device_json(device, device_choice);
    emit(out, line);
  } else if (group.section == "bench" || group.section == "views") {
    run_bench_group(group, first, device, settings, out, skip_failed);
  } else {
    for (size_t index = first; index < group.rows.size(); ++index) {
      if (skip_failed(index)) continue;
      try {
        if (group.section == "checks") {
          run_check(group, index, device, settings, out);
        } else {
          run_rays(group, index, device, settings, out);
        }
      } catch (const DeviceLostError&) {
        throw;
      } catch (const GpuError& error) {
        emit(out, row_head(group, index, "failed", error.what()));
      }
    }
  }
}

std::optional<std::vector<std::string>> report_process_arguments(const ReportSettings& settings, const ReportGroup& group) {
  const GroupScene where = parse_group_scene(group.id);
  if (where.scene == stand_in_model) return std::nullopt;
  return std::vector<std::string>{"render", (settings.models_dir / where.scene).string(), "--width", std::to_string(where.width),
                                  "--height", std::to_string(where.height)};
}

std::string report_process_row(const ReportGroup& group, size_t row, const std::string& command, const ProcessTimes& times) {
  const GroupScene where = parse_group_scene(group.id);
  Json line = row_head(group, row, "ok");
  line["scene"] = where.scene;
  line["width"] = where.width, line["height"] = where.height;
  line["command"] = command;
  line["wall_median_ms"] = median(times.wall_ms);
  line["wall_min_ms"] = *std::min_element(times.wall_ms.begin(), times.wall_ms.end());
  line["peak_bytes"] = times.peak_bytes;
  line["output_bytes"] = Frame::bytes(where.width, where.height, AovSet{Aov::depth, Aov::normal}, false);
  return line.dump();
}

std::string report_unfinished_row(const ReportGroup& group, size_t row, const std::string& status,
                                  const std::string& reason) {
  return row_head(group, row, status, reason).dump();
}

std::string report_json(const std::vector<std::string>& row_lines, const std::string& command, double seconds) {
  Json rows = Json::array();
  Json device = Json::object();
  for (const std::string& line : row_lines) {
    Json row = Json::parse(line);
    if (row.value("section", "") == "device" && row.contains("device")) device = row["device"];
    rows.push_back(std::move(row));
  }
  const Json report = {{"schema", report_schema}, {"vkray_version", build_version()}, {"git_commit", build_commit()},
                       {"command", command},      {"seconds", seconds},              {"device", device},
                       {"rows", rows}};
  return report.dump(2) + "\n";
}

namespace {

std::string format(const char* pattern, auto... values) {
  const int size = std::snprintf(nullptr, 0, pattern, values...);
  std::string text(static_cast<size_t>(std::max(size, 0)), '\0');
  std::snprintf(text.data(), text.size() + 1, pattern, values...);
  return text;
}

bool row_passed(const Json& row) {
  const std::string status = row.value("status", "");
  if (status == "skipped") return true;
  return status == "ok" && row.value("pass", true);
}

std::string ms(double value) { return value >= 100.0 ? format("%.0f", value) : value >= 10.0 ? format("%.1f", value) : format("%.2f", value); }

}  // namespace

bool report_passed(const std::string& json_text) {
  const Json report = Json::parse(json_text);
  return std::all_of(report["rows"].begin(), report["rows"].end(), row_passed);
}

std::string report_markdown(const std::string& json_text) {
  const Json report = Json::parse(json_text);
  const Json& device = report["device"];
  std::map<std::string, std::vector<const Json*>> by_section;
  for (const Json& row : report["rows"]) by_section[row.value("section", "")].push_back(&row);
  std::string text = "# vkray on " + device.value("name", std::string("(no device)")) + "\n\n";
  if (!device.empty()) {
    text += format("%s device, %s; Vulkan %s; subgroups of %u; shaderFloat64 %s; ray queries %s; "
                   "transfer %s; validation layer %s; Vulkan loader: %s; host: %u threads.\n\n",
                   device.value("type", "").c_str(), device.value("driver", "").c_str(),
                   device.value("api_version", "").c_str(), device.value("subgroup_size", 0u),
                   device.value("shader_float64", false) ? "yes" : "no", device.value("ray_query", false) ? "yes" : "no",
                   device.value("transfer", "").c_str(), device.value("validation", false) ? "on" : "off (not installed)",
                   device.value("vulkan_loader", "").c_str(), device.value("host_threads", 0u));
    if (!device.value("overridden", std::string()).empty()) {
      text += "Described as overridden by VKRAY_DEVICE_OVERRIDE=" + device.value("overridden", std::string()) + ".\n\n";
    }
  }
  text += format("vkray %s (commit %.12s), `%s`, %.0f s in all.\n\n", report.value("vkray_version", "").c_str(),
                 report.value("git_commit", "").c_str(), report.value("command", "").c_str(), report.value("seconds", 0.0));

  auto unfinished = [&](const std::vector<const Json*>& rows) {
    std::string lines;
    for (const Json* row : rows) {
      const std::string status = row->value("status", "");
      if (status != "ok" && status != "skipped") {
        lines += "- " + row->value("group", "") + " / " + row->value("row", "") + ": **" + status + "**: " +
                 row->value("reason", "") + "\n";
      }
    }
    return lines;
  };

  // Correctness.
  const auto& checks = by_section["checks"];
  size_t passed = 0, ran = 0, skipped = 0;
  std::string failures;
  for (const Json* row : checks) {
    if (row->value("status", "") == "skipped") {
      ++skipped;
      continue;
    }
    ++ran;
    if (row_passed(*row)) {
      ++passed;
    } else if (row->value("status", "") == "ok") {
      failures += "- " + row->value("group", "") + " / " + row->value("row", "") + ": " +
                  std::to_string(row->value("envelope_failures", 0u)) + " pixels outside the envelope" +
                  (row->contains("first_failure") ? " (first: " + (*row)["first_failure"].get<std::string>() + ")" : "") + "\n";
    }
  }
  text += "## Correctness\n\n";
  text += format("%zu of %zu checks passed (every pixel within the reference's error envelope; the stiff cases and "
                 "the models with every traversal and geometry layout this device runs, with staging and with direct "
                 "transfers); %zu not run here (the device refuses them: reasons in the JSON).\n\n",
                 passed, ran, skipped);
  text += failures + unfinished(checks);
  for (const Json* row : checks) {
    if (!row->value("row", "").starts_with("float64/") || row->value("status", "") != "ok") continue;
    const double worst = (*row)["error"].value("depth_rel_max", 0.0);
    text += format("\nfloat64 (`--precision double`, %s, %s): depth within %.2e of the reference at worst, %zu flips: "
                   "%s the 1e-12 of docs/precision.md.\n",
                   row->value("row", "").substr(8).c_str(), row->value("group", "").c_str(), worst,
                   (*row)["error"].value("hit_mismatches", size_t{0}), worst <= float64_promise ? "within" : "**outside**");
  }

  // The bench, a table a scene and size, and the fastest rows without flips.
  text += "\n## Bench\n\n**sustained**: GPU time a frame in passes back to back with nothing read back, the fastest of "
          "three bursts (the device's clocks up); **frame**: GPU time of a frame rendered alone and read back (the median "
          "of the timed ones: a GPU left idle between such frames may slow its clocks); Embree rows: the CPU's wall "
          "time on every host thread. Errors against the double-precision reference of the same frame.\n\n";
  text += "| scene | size | row | sustained ms | frame ms | Mrays/s | flips | depth p99 | normal p99 (deg) | time / default |\n"
          "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  // The time a row is compared by: sustained where measured.
  auto row_ms = [](const Json& row) {
    const double sustained = row.value("gpu_sustained_ms", 0.0);
    return sustained > 0.0 ? sustained : row.value("gpu_median_ms", 0.0);
  };
  std::map<std::string, double> default_ms;
  for (const Json* row : by_section["bench"]) {
    if (row->value("status", "") == "ok" && row->value("row", "") == "default") default_ms[row->value("group", "")] = row_ms(*row);
  }
  struct Best {
    std::string row;
    double ms = 0.0, flips = 0.0;
  };
  std::map<std::string, Best> best;  // by group
  for (const Json* row : by_section["bench"]) {
    if (row->value("status", "") != "ok") continue;
    const Json& error = (*row)["error"];
    const double time = row_ms(*row);
    const std::string group = row->value("group", "");
    const double base = default_ms.count(group) ? default_ms[group] : 0.0;
    const double sustained = row->value("gpu_sustained_ms", 0.0);
    text += format("| %s | %ux%u | %s | %s | %s | %.0f | %zu | %.2e | %.2e | %s |\n", row->value("scene", "").c_str(),
                   row->value("width", 0u), row->value("height", 0u), row->value("row", "").c_str(),
                   sustained > 0.0 ? ms(sustained).c_str() : "", ms((*row)["gpu_median_ms"]).c_str(),
                   static_cast<double>(row->value("width", 0u)) * row->value("height", 0u) / (time * 1e3),
                   error.value("hit_mismatches", size_t{0}), error.value("depth_rel_p99", 0.0),
                   error.value("normal_deg_p99", 0.0), base > 0.0 ? format("%.2f", time / base).c_str() : "");
    // The fastest float32 row among those with the fewest flips.
    const double flips = static_cast<double>(error.value("hit_mismatches", size_t{0}));
    if (row->value("on_gpu", false) && row->value("row", "") != "float64" &&
        (!best.count(group) || flips < best[group].flips || (flips == best[group].flips && time < best[group].ms))) {
      best[group] = {row->value("row", ""), time, flips};
    }
  }
  text += "\nFastest float32 row with the fewest flips, a scene and size:";
  for (const auto& [group, winner] : best) text += " " + group.substr(6) + ": " + winner.row + ";";
  text += "\n" + unfinished(by_section["bench"]);

  text += "\n## Transfer\n\n| scene | size | transfer | frame ms | GPU ms | readback ms | readback GB/s |\n"
          "| --- | --- | --- | ---: | ---: | ---: | ---: |\n";
  for (const Json* row : by_section["transfer"]) {
    if (row->value("status", "") != "ok") continue;
    text += format("| %s | %ux%u | %s%s | %s | %s | %s | %.1f |\n", row->value("scene", "").c_str(), row->value("width", 0u),
                   row->value("height", 0u), row->value("transfer", "").c_str(),
                   row->value("readback_in_place", false) ? "; straight into the frame" : "",
                   ms((*row)["frame_median_ms"]).c_str(), ms((*row)["gpu_median_ms"]).c_str(),
                   ms((*row)["readback_median_ms"]).c_str(), row->value("readback_gb_per_s", 0.0));
  }
  text += unfinished(by_section["transfer"]);

  text += "\n## Whole processes\n\nA user's `vkray render` of the model (EXR and PNG preview), the pipeline cache warm: "
          "wall time of the whole process (median of the timed runs) and its peak resident memory against the frame's "
          "output bytes (depth and normal).\n\n| command | wall ms | peak MiB | peak / output bytes |\n| --- | ---: | ---: | ---: |\n";
  for (const Json* row : by_section["process"]) {
    if (row->value("status", "") != "ok") continue;
    const double peak = row->value("peak_bytes", 0.0), output = row->value("output_bytes", 1.0);
    text += format("| `%s` | %s | %.0f | %.2f |\n", row->value("command", "").c_str(), ms((*row)["wall_median_ms"]).c_str(),
                   peak / (1 << 20), peak / output);
  }
  text += unfinished(by_section["process"]);

  text += "\n## Many views\n\n";
  for (const Json* row : by_section["views"]) {
    if (row->value("status", "") != "ok") continue;
    const bool npy = row->value("row", "").ends_with("-npy");
    text += format("%u views of %s at %ux%u (depth and normal, rendered and written to %s in one run): %.1f views/s, "
                   "%s ms a view.\n",
                   row->value("views", 0u), row->value("scene", "").c_str(), row->value("width", 0u), row->value("height", 0u),
                   npy ? ".npy files" : "OpenEXR (zip:1)", row->value("views_per_s", 0.0), ms((*row)["gpu_median_ms"]).c_str());
  }
  text += unfinished(by_section["views"]);

  text += "\n## Given rays\n\nA whole `cast_rays` call (ordering, writing, dispatch, reading back) against Embree's "
          "rtcIntersect1M in chunks of 1024 on every host thread, same rays (for occlusion rays `occluded` against "
          "rtcOccluded1M); flips and distance error against the reference.\n\n| rays | count | walk | vkray ms | Embree ms | Embree / vkray | flips | t p99 | Embree flips |\n"
          "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const Json* row : by_section["rays"]) {
    if (row->value("status", "") != "ok") continue;
    const double vkray_ms = (*row)["vkray_median_ms"], embree_ms = (*row)["embree_median_ms"];
    const bool embree = embree_ms > 0.0;  // none for first hits, which Embree has no call for
    text += format("| %s | %zu | %s | %s | %s | %s | %zu | %.2e | %s |\n", row->value("row", "").c_str(),
                   row->value("rays", size_t{0}), row->value("walk", "").c_str(), ms(vkray_ms).c_str(),
                   embree ? ms(embree_ms).c_str() : "-", embree ? format("%.2f", embree_ms / vkray_ms).c_str() : "-",
                   row->value("hit_mismatches", size_t{0}), row->value("t_rel_p99", 0.0),
                   embree ? std::to_string(row->value("embree_hit_mismatches", size_t{0})).c_str() : "-");
  }
  text += unfinished(by_section["rays"]);
  text += unfinished(by_section["device"]);
  return text;
}

}  // namespace vkray
