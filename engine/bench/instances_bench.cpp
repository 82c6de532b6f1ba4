#include "engine/bench/instances_bench.hpp"

#include "engine/render/gpu_scene.hpp"
#include "engine/bench/render_times.hpp"
#include "engine/render/renderer.hpp"
#include "engine/host_memory.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <random>

namespace vkray {
namespace {

// A model's first mesh moved to the origin and scaled to a box whose longest side is 1, instanced.
Mesh unit_mesh(const Scene& model) {
  Mesh mesh = model.meshes.at(0);
  Bounds box;
  for (const glm::dvec3& p : mesh.positions) box.add(p);
  const glm::dvec3 centre = 0.5 * (box.lower + box.upper), size = box.upper - box.lower;
  const double scale = 1.0 / std::max({size.x, size.y, size.z});
  for (glm::dvec3& p : mesh.positions) p = (p - centre) * scale;
  mesh.normals.clear(), mesh.normal_corners.clear();  // unused here
  mesh.instanced = true;
  return mesh;
}

// A random turn about y and a scale of 0.6 to 1, at cell (i, j) of the grid, lifted so that the unit
// box rests on the ground.
glm::dmat4 random_placement(std::mt19937_64& random, size_t cell, size_t side) {
  std::uniform_real_distribution<double> turn(0.0, 6.283185307179586), scale(0.6, 1.0), jitter(-0.1, 0.1);
  const double angle = turn(random), s = scale(random);
  const double c = std::cos(angle), n = std::sin(angle);
  glm::dmat4 m(glm::dvec4(c * s, 0.0, -n * s, 0.0), glm::dvec4(0.0, s, 0.0, 0.0), glm::dvec4(n * s, 0.0, c * s, 0.0),
               glm::dvec4(0.0, 0.0, 0.0, 1.0));
  const double half = 0.5 * double(side - 1);
  m[3] = glm::dvec4(1.2 * (double(cell % side) - half) + jitter(random), 0.5 * s, 1.2 * (double(cell / side) - half) + jitter(random), 1.0);
  return m;
}


// The host's peak bytes a flattened triangle costs the suite (its scene, its GpuScene and tree, the
// reference's copy), measured: `vkray bench --suite instances --models` (the bunny) with
// --instances 100 and 200 peaked at 1.53 and 2.95 GB, 1.42 GB for 6.9M triangles: 205 bytes each.
constexpr double flattened_bytes_per_triangle = 205.0;

}  // namespace

void check_instances_fit(const std::vector<Scene>& models, uint32_t count) {
  if (models.empty() || count == 0) return;
  size_t per_round = 0;  // one instance of each model, in turn
  for (const Scene& model : models) per_round += model.meshes.at(0).triangles.size();
  const double average = double(per_round) / double(models.size());
  const double triangles = average * count;
  const size_t available = available_host_memory_bytes();
  if (available == 0 || triangles * flattened_bytes_per_triangle <= double(available)) return;
  const auto fitting = static_cast<uint64_t>(double(available) / flattened_bytes_per_triangle / average);
  char text[400];
  std::snprintf(text, sizeof text, "--instances %u: the flattened scene the suite measures against holds %.3g triangles, about "
                "%.1f GB at %.0f bytes each, beyond the %.1f GB this machine has free: at most %llu instances of these models",
                count, triangles, triangles * flattened_bytes_per_triangle / 1e9, flattened_bytes_per_triangle,
                double(available) / 1e9, static_cast<unsigned long long>(fitting));
  throw InputError(text);
}

InstancesRow bench_instances(GpuDevice& device, const std::vector<Scene>& models, uint32_t count, uint32_t width,
                             uint32_t height, uint32_t frames, uint32_t row_step) {
  std::mt19937_64 random(20261129);
  Scene scene;
  scene.width = width, scene.height = height;
  Scene meshes_once;  // each model's mesh once, where it stands: what the meshes take without instances
  for (const Scene& model : models) {
    scene.meshes.push_back(unit_mesh(model));
    Mesh alone = scene.meshes.back();
    alone.instanced = false;
    meshes_once.meshes.push_back(std::move(alone));
  }
  const auto side = static_cast<size_t>(std::ceil(std::sqrt(double(count))));
  for (uint32_t k = 0; k < count; ++k) {
    Instance instance;
    instance.mesh = k % static_cast<uint32_t>(scene.meshes.size());
    place_by(instance, random_placement(random, k, side));
    scene.instances.push_back(instance);
  }
  const double extent = 1.2 * double(side);
  scene.camera = {glm::dvec3(0.0, 0.75 * extent, 0.85 * extent), glm::dvec3(0.0, 0.0, 0.05 * extent), glm::dvec3(0.0, 1.0, 0.0), 55.0};
  check_scene(scene);
  Scene flat = scene;  // every placement written out as a mesh of its own, placed in double
  flat.meshes.clear();
  flat.instances.clear();
  for (const Instance& instance : scene.instances) {
    Mesh copy = scene.meshes[instance.mesh];
    copy.instanced = false;
    for (glm::dvec3& p : copy.positions) p = placed(instance, p);
    flat.meshes.push_back(std::move(copy));
  }

  InstancesRow row;
  row.instances = count;
  for (const Mesh& mesh : scene.meshes) row.triangles_stored += mesh.triangles.size();
  row.triangles_placed = flat.triangle_count();
  row.meshes_bytes = make_gpu_scene(meshes_once).geometry_bytes();
  Frame instanced_frame, flattened_frame, moved_frame;
  {
    Renderer flattened(device, flat);
    row.flattened_bytes = flattened.scene_stats().geometry_bytes;
    row.flattened = render_times(flattened, flat, frames, flattened_frame);
  }
  flat = Scene{};  // its memory back before the instanced scene's
  Renderer renderer(device, scene);
  row.instanced_bytes = renderer.scene_stats().geometry_bytes;
  row.instanced = render_times(renderer, scene, frames, instanced_frame);
  row.instanced_error = check_against_reference(scene, instanced_frame, row_step);
  row.flattened_error = check_against_reference(scene, flattened_frame, row_step);

  std::vector<uint32_t> every(count);
  for (uint32_t k = 0; k < count; ++k) every[k] = k;
  std::vector<double> update_ms;
  std::vector<glm::dmat4> transforms(count);
  for (uint32_t call = 0; call <= frames; ++call) {
    for (uint32_t k = 0; k < count; ++k) transforms[k] = random_placement(random, k, side);
    renderer.set_transforms(every, transforms);
    if (call > 0) update_ms.push_back(renderer.timings().scene_update_ms);
  }
  row.set_transforms = time_stats(update_ms);
  const Scene& moved = renderer.scene();
  row.moved = render_times(renderer, moved, frames, moved_frame);
  row.moved_error = check_against_reference(moved, moved_frame, row_step);
  Renderer built(device, moved);
  Frame built_frame;
  row.moved_built = render_times(built, moved, frames, built_frame);
  return row;
}

std::string instances_report(const InstancesRow& row) {
  char text[4096];
  const auto error = [](const EnvelopeReport& report) {
    char line[120];
    std::snprintf(line, sizeof line, "depth p99 %.2e, %zu of %zu pixels outside the envelope", report.stats.depth_p99,
                  report.failures, report.pixels);
    std::string described = line;
    for (const std::string& failure : report.first_failures) described += "\n    " + failure;
    return described;
  };
  const size_t budget = row.meshes_bytes + 256 * row.instances;
  std::snprintf(text, sizeof text,
                "%zu instances of %zu triangles (%zu placed)\n"
                "render, instances     %9.2f ms  %s\n"
                "render, flattened     %9.2f ms  %s\n"
                "ratio                 %9.2f\n"
                "bytes, instances      %9.2f MiB  (the meshes alone %.2f MiB, + 256 B an instance: %.2f MiB)\n"
                "bytes, flattened      %9.2f MiB\n"
                "set_transforms, all   %9.3f ms\n"
                "render after          %9.2f ms  %s\n"
                "render, made for it   %9.2f ms  (after set_transforms: %.2f of it)\n",
                row.instances, row.triangles_stored, row.triangles_placed, row.instanced.median_ms,
                error(row.instanced_error).c_str(), row.flattened.median_ms, error(row.flattened_error).c_str(),
                row.instanced.median_ms / row.flattened.median_ms, double(row.instanced_bytes) / 1048576.0,
                double(row.meshes_bytes) / 1048576.0, double(budget) / 1048576.0,
                double(row.flattened_bytes) / 1048576.0, row.set_transforms.median_ms, row.moved.median_ms,
                error(row.moved_error).c_str(), row.moved_built.median_ms, row.moved.median_ms / row.moved_built.median_ms);
  return text;
}

}  // namespace vkray
