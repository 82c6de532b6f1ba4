// The scenes of `vkray bench --suite NAME`. Generated scenes are deterministic (fixed seeds), so two
// runs, on two machines, time the same geometry: their scene hashes match (bench_report.hpp).
#pragma once

#include "engine/scene/scene.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace vkray {

struct BenchScene {
  std::string name;
  Scene scene;
};

// For help texts and error messages.
inline constexpr const char* bench_suite_names = "basic, scaling, stiff, accuracy, models, rays, host, moving, instances";
// The suite whose rows are given rays (engine/bench/given_rays_bench.hpp), not a camera's variants.
inline constexpr const char* given_rays_suite = "rays";
// The suite whose rows are the host's stages on a frame made on the host (engine/bench/host_bench.hpp):
// no device, no scene.
inline constexpr const char* host_suite = "host";
// The suite whose rows are a deforming mesh's refit against a rebuild (engine/bench/moving_bench.hpp).
inline constexpr const char* moving_suite = "moving";
// The suite whose rows are instances against the scene flattened (engine/bench/instances_bench.hpp).
inline constexpr const char* instances_suite = "instances";
// The real mesh the accuracy suite adds from the models folder, when it is there.
inline constexpr const char* accuracy_model = "stanford-bunny.obj";

// The scenes of one suite at width x height:
// - basic: the built-in scene, one sphere, spheres on a ground plane, a closed mesh;
// - scaling: closed meshes of 1k to 4M triangles, sphere fields of 1 to 10k spheres;
// - stiff: the numerically hard cases of engine/bench/stiff_cases.hpp (cases about image sizes keep
//   theirs);
// - accuracy: the stiff cases, then the basic suite and the Stanford bunny (accuracy_model, when
//   `models_dir` has it, or a line in `skipped` saying it is not): what docs/accuracy.md tabulates;
// - models: every .obj file in `models_dir`, framed to fill the image (none when the folder is
//   absent; the caller says so). A file that does not load is left out, its error added to
//   `skipped` when given;
// - rays: three models of `models_dir` for given rays, framed: the Utah teapot (6k triangles, open
//   seams), the Stanford bunny (70k) and dragon (100k); each one missing or broken is a line in
//   `skipped`;
// - moving: the Stanford bunny and dragon of `models_dir`, framed, for a deforming mesh;
// - instances: the Stanford bunny, dragon and armadillo and two small models (Spot, the Utah
//   teapot) of `models_dir`, to be placed many times.
// Throws InputError for an unknown suite name.
std::vector<BenchScene> bench_suite(const std::string& suite, uint32_t width, uint32_t height,
                                    const std::filesystem::path& models_dir,
                                    std::vector<std::string>* skipped = nullptr);

}  // namespace vkray
