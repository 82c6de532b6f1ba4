#include "engine/bench/moving_bench.hpp"

#include "engine/bench/render_times.hpp"
#include "engine/render/renderer.hpp"

#include <glm/geometric.hpp>

#include <cstdio>
#include <random>

namespace vkray {
namespace {

// The first mesh's vertices each moved by up to 1% of the mesh's size along each axis.
std::vector<glm::dvec3> moved_vertices(const Mesh& mesh, std::mt19937_64& random) {
  Bounds box;
  for (const glm::dvec3& p : mesh.positions) box.add(p);
  const double size = glm::length(box.upper - box.lower);
  std::uniform_real_distribution<double> step(-0.01 * size, 0.01 * size);
  std::vector<glm::dvec3> positions = mesh.positions;
  for (glm::dvec3& p : positions) p += glm::dvec3(step(random), step(random), step(random));
  return positions;
}


}  // namespace

MovingRow bench_moving(GpuDevice& device, const Scene& scene, uint32_t frames) {
  const Mesh& mesh = scene.meshes.at(0);
  MovingRow row;
  row.vertices = mesh.positions.size();
  std::mt19937_64 random(20261128);
  Renderer refitting(device, scene), rebuilding(device, scene);
  std::vector<double> refit, rebuild;
  std::vector<glm::dvec3> last;
  for (uint32_t call = 0; call <= frames; ++call) {
    last = moved_vertices(mesh, random);
    refitting.set_vertices(0, last);
    std::vector<glm::dvec3> collapsed_or_not = moved_vertices(mesh, random);
    if (call % 2 == 0) {  // the primitives differ from the last call's at every call
      const auto& corners = mesh.triangles.front();
      collapsed_or_not[corners[1]] = collapsed_or_not[corners[2]] = collapsed_or_not[corners[0]];
    }
    rebuilding.set_vertices(0, collapsed_or_not);
    if (call == 0) continue;
    refit.push_back(refitting.timings().scene_update_ms);
    row.every_call_refitted = row.every_call_refitted && refitting.timings().tree_refitted;
    rebuild.push_back(rebuilding.timings().scene_update_ms);
  }
  row.refit = time_stats(refit);
  row.rebuild = time_stats(rebuild);

  Scene moved = scene;
  moved.meshes[0].positions = last;
  Renderer built(device, moved);
  Frame refitted_frame, built_frame;
  row.render_refitted = render_times(refitting, moved, frames, refitted_frame);
  row.render_built = render_times(built, moved, frames, built_frame);
  row.refitted_error = check_against_reference(moved, refitted_frame);
  row.built_error = check_against_reference(moved, built_frame);
  return row;
}

std::string moving_table_header() {
  char line[320];
  std::snprintf(line, sizeof line, "%-28s %9s %9s %10s %6s  %12s %12s %6s  %-27s\n", "model", "vertices", "refit ms",
                "rebuild ms", "ratio", "render refit", "render built", "ratio", "depth p99 / outside, both");
  return line;
}

std::string moving_table_row(const std::string& model, const MovingRow& row) {
  char line[320];
  std::snprintf(line, sizeof line, "%-28s %9zu %9.2f %10.2f %6.2f  %12.2f %12.2f %6.2f  %.2e / %zu, %.2e / %zu%s\n",
                model.c_str(), row.vertices, row.refit.median_ms, row.rebuild.median_ms,
                row.refit.median_ms / row.rebuild.median_ms, row.render_refitted.median_ms, row.render_built.median_ms,
                row.render_refitted.median_ms / row.render_built.median_ms, row.refitted_error.stats.depth_p99,
                row.refitted_error.failures, row.built_error.stats.depth_p99, row.built_error.failures,
                row.every_call_refitted ? "" : "  (some refits fell back to a build)");
  return line;
}

}  // namespace vkray
