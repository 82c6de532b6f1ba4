// vkray points: point queries for datasets (docs/points.md): the points of a dense grid over the
// model's box, of a .npy file, or drawn as SDF datasets draw them (uniform in the box, near the
// surface), queried on the device or by the reference, each output written as a .npy file.
#include "cli/commands.hpp"
#include "cli/device_options.hpp"
#include "cli/scene_argument.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/io/array_files.hpp"
#include "engine/io/image_io.hpp"
#include "engine/point_outputs.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/render/search.hpp"
#include "engine/scene/point_samples.hpp"
#include "engine/stopwatch.hpp"
#include "engine/typed_names.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vkray::cli {
namespace {

struct PointsOptions {
  std::string scene;
  uint32_t grid = 0;
  std::string points_file;
  size_t uniform = 0, near_surface = 0;
  std::optional<double> sigma;
  double box_scale = 1.1;
  uint64_t seed = 0;
  std::string outputs = "signed-distance";
  std::string prefix = "points";
  std::optional<double> max_distance;
  DeviceOptions device_options;
  std::string precision = "float";
  std::string traversal = "auto";
  uint32_t mask = every_mask_bit;
  bool reference = false;
};

// The file of `name` beside the prefix: PREFIX.NAME.npy.
std::filesystem::path file_for(const std::string& prefix, const std::string& name) { return prefix + "." + name + ".npy"; }

int run_points(const PointsOptions& options) {
  const bool sampled = options.uniform > 0 || options.near_surface > 0;
  if (int(options.grid > 0) + int(!options.points_file.empty()) + int(sampled) != 1) {
    throw InputError("give the points one way: --grid N, --points FILE.npy, or --uniform N and/or --near-surface N");
  }
  std::vector<const PointOutputInfo*> asked;
  for (const std::string& name : split_list(options.outputs)) {
    const PointOutputInfo* info = find_point_output(name);
    if (!info) throw InputError("--output: unknown point output '" + name + "' (" + point_output_names() + ")");
    asked.push_back(info);
  }
  if (asked.empty()) throw InputError("--output: name at least one point output (" + std::string(point_output_names()) + ")");
  const Scene scene = load_scene_argument(options.scene, std::nullopt, std::nullopt);

  // The points, and the shape of the arrays they make: n x n x n for a grid, the file's leading shape
  // (flattened to N) for a file, N for samples (the uniform ones first).
  std::vector<glm::dvec3> points;
  std::vector<size_t> shape;
  if (options.grid > 0) {
    points = grid_points(sample_box(scene, options.box_scale), options.grid);
    shape = {options.grid, options.grid, options.grid};
  } else if (!options.points_file.empty()) {
    points = read_npy_points(options.points_file);
  } else {
    const Bounds model = finite_bounds(scene);
    const double sigma = options.sigma.value_or(glm::length(model.upper - model.lower) / 200.0);
    if (!(sigma >= 0.0) || std::isinf(sigma)) throw InputError("--sigma: a distance >= 0 (world units)");
    points = uniform_points(sample_box(scene, options.box_scale), options.uniform, options.seed);
    const std::vector<glm::dvec3> near = near_surface_points(scene, options.near_surface, sigma, options.seed + 1);
    points.insert(points.end(), near.begin(), near.end());
    std::fprintf(stderr, "vkray: %zu points uniform in the box %.3gx the model's, %zu near the surface (sigma %.6g)\n",
                 options.uniform, options.box_scale, options.near_surface, sigma);
  }
  if (shape.empty()) shape = {points.size()};
  const std::vector<double> max_distances = options.max_distance ? std::vector<double>{*options.max_distance} : std::vector<double>{};
  check_query_points(points, max_distances);

  // Every file is checked before any work: a run must not end, its work lost, on an unwritable name.
  std::vector<std::filesystem::path> files{file_for(options.prefix, "points")};
  for (const PointOutputInfo* info : asked) files.push_back(file_for(options.prefix, info->name));
  for (const auto& file : files) check_output_path(file);

  bool nearest = false, winding = false;
  for (const PointOutputInfo* info : asked) nearest |= info->nearest, winding |= info->winding;
  std::optional<PointHits> nearest_hits, winding_hits;
  const bool doubles = options.reference || options.precision == "double";
  const auto start = Clock::now();
  std::string answered_by = "the CPU reference (double precision)";
  if (options.reference) {
    const ReferenceScene reference(scene, static_cast<Mask>(options.mask));
    if (nearest) nearest_hits = reference_point_hits(reference, points, max_distances, HitQuery::nearest);
    if (winding) winding_hits = reference_point_hits(reference, points, max_distances, HitQuery::winding);
  } else {
    GpuDevice device(options.device_options.device, options.device_options.transfer_mode());
    print_cpu_device_note(device.info());
    RendererOptions renderer_options;
    if (options.precision == "double") renderer_options.shader.precision = Precision::float64;
    renderer_options.scene.search = *traversal_from_name(options.traversal);
    Renderer renderer(device, scene, renderer_options);
    renderer.set_ray_mask(static_cast<Mask>(options.mask));
    if (nearest) nearest_hits = renderer.closest_points(points, max_distances);
    if (winding) winding_hits = renderer.winding_numbers(points);
    answered_by = device.info().name;
  }
  const double query_ms = elapsed_ms(start);

  // The points first (float64, as given), then each output.
  std::vector<size_t> point_shape = shape;
  point_shape.push_back(3);
  std::string bytes = npy_header("<f8", point_shape);
  bytes.append(reinterpret_cast<const char*>(points.data()), points.size() * sizeof(glm::dvec3));
  write_text_file(files[0], bytes);
  const PointAnswers answers{points, nearest_hits ? &*nearest_hits : nullptr, winding_hits ? &*winding_hits : nullptr};
  for (size_t k = 0; k < asked.size(); ++k) {
    const PointOutputInfo& info = *asked[k];
    std::vector<size_t> output_shape = shape;
    if (info.components > 1) output_shape.push_back(info.components);
    const size_t item = info.integer ? 4 : doubles ? 8 : 4;
    std::string data(points.size() * info.components * item, '\0');
    write_point_output(info, scene, answers, doubles, data.data());
    write_text_file(files[k + 1], npy_header(info.integer ? "<u4" : doubles ? "<f8" : "<f4", output_shape) + data);
  }
  std::printf("vkray: %zu points queried in %.1f ms on %s; wrote %s", points.size(), query_ms, answered_by.c_str(),
              files[0].string().c_str());
  for (size_t k = 1; k < files.size(); ++k) std::printf(", %s", files[k].string().c_str());
  std::printf("\n");
  return 0;
}

}  // namespace

Action add_points_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "points", "Query points (distance, signed distance, occupancy, closest points...) on a grid, from a .npy file or drawn near the "
                "surface as SDF datasets draw them; each output written as a .npy file");
  auto options = std::make_shared<PointsOptions>();
  command->add_option("scene", options->scene, "Scene file (.json) or model (.obj, .ply, .gltf, .glb)")->required();
  command->add_option("--grid", options->grid, "A grid of N x N x N points over the model's box (--box-scale), arrays [x][y][z]")
      ->check(CLI::Range(1u, 1024u));
  command->add_option("--points", options->points_file, "Points of a .npy file, shape (..., 3), float64 or float32");
  command->add_option("--uniform", options->uniform, "Points uniform in the model's box (--box-scale)")
      ->check(CLI::Range(size_t{0}, size_t{1} << 28));
  command->add_option("--near-surface", options->near_surface,
                      "Points on the surface (area-weighted) moved by a Gaussian of --sigma: DeepSDF's samples")
      ->check(CLI::Range(size_t{0}, size_t{1} << 28));
  command->add_option("--sigma", options->sigma, "The Gaussian's standard deviation, world units (default: 1/200 of the box's diagonal)");
  command->add_option("--box-scale", options->box_scale, "The grid's and the uniform points' box, times the model's about its centre")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e3));
  command->add_option("--seed", options->seed, "The samples' seed (the same points for the same seed, on every machine)")
      ->capture_default_str();
  command->add_option("--output", options->outputs, std::string("Comma-separated: ") + point_output_names())->capture_default_str();
  command->add_option("-o,--prefix", options->prefix, "Files PREFIX.points.npy and PREFIX.OUTPUT.npy")->capture_default_str();
  command->add_option("--max-distance", options->max_distance, "Beyond it no point is found (distance inf)")
      ->check(CLI::Range(0.0, 1e300));
  CLI::Option* device = add_device_options(command, options->device_options);
  CLI::Option* precision = command->add_option("--precision", options->precision, "Shader arithmetic: float or double")
                               ->check(CLI::IsMember({"float", "double"}))
                               ->capture_default_str();
  add_traversal_option(command, options->traversal);
  add_mask_option(command, options->mask);
  command->add_flag("--reference", options->reference, "Answer with the double-precision CPU reference instead")
      ->excludes(device)
      ->excludes(precision);
  return [options] { return run_points(*options); };
}

}  // namespace vkray::cli
