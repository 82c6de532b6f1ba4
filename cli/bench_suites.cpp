#include "cli/bench_suites.hpp"

#include "engine/scene/scene.hpp"

namespace vkray::cli {
namespace {

constexpr uint32_t variant_rows = takes_variants | takes_files | takes_report;

const BenchSuiteRow suite_table[] = {
    {"basic", "the built-in scene, one sphere, spheres on a ground plane, a closed mesh: every variant", variant_rows,
     basic_scenes, run_variants},
    {"scaling", "closed meshes of 1k to 4M triangles and fields of 1 to 10k spheres: how time grows", variant_rows,
     scaling_scenes, run_variants},
    {"stiff", "the numerically hard cases (engine/bench/stiff_cases.hpp): every variant's error", variant_rows, stiff_scenes,
     run_variants},
    {"accuracy", "the stiff cases, the basic scenes and the Stanford bunny: docs/accuracy.md (--markdown)", variant_rows,
     accuracy_scenes, run_variants},
    {"models", "every .obj file of --models, framed: each variant against Embree", variant_rows, model_folder_scenes,
     run_variants},
    {"rays", "given rays of every kind (camera, lidar, incoherent, occlusion) on three models, against Embree",
     takes_files | takes_rays, given_rays_scenes, run_given_rays},
    {"host", "the host's stages (readback, EXR and PNG writing) on a frame made on the host: no device",
     takes_no_scenes, nullptr, run_host_stages},
    {"moving", "a deforming mesh: refit against rebuild, and the renders after", 0, moving_scenes, run_moving},
    {"instances", "models placed --instances times against the scene flattened, then every instance moved", takes_instances,
     instances_scenes, run_instances},
    {"points", "--points points uniform in the box and near the surface: distance and signed distance against Embree's "
               "rtcPointQuery", 0, points_scenes, run_points},
};

}  // namespace

std::span<const BenchSuiteRow> bench_suites() { return suite_table; }

const BenchSuiteRow& bench_suite_named(const std::string& name) {
  std::string names;
  for (const BenchSuiteRow& row : suite_table) {
    if (name == row.name) return row;
    names += (names.empty() ? "" : ", ") + std::string(row.name);
  }
  throw InputError("--suite: unknown suite '" + name + "' (choose from " + names + ")");
}

std::string bench_suites_help() {
  std::string help = "Built-in scenes and what they measure:";
  for (const BenchSuiteRow& row : suite_table) help += "\n  " + std::string(row.name) + ": " + row.measures;
  return help;
}

}  // namespace vkray::cli
