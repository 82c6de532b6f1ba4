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

// The real mesh the accuracy scenes add from the models folder, when it is there.
inline constexpr const char* accuracy_model = "stanford-bunny.obj";

// The scenes a suite of `vkray bench` measures (cli/bench_suites.cpp lists the suites, each with
// its scenes and runner), each at width x height from `models_dir` where it takes models: a model
// missing or broken is a line in `skipped` (when given), not an error. Each has the same signature:
using BenchSceneSet = std::vector<BenchScene> (*)(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                                  std::vector<std::string>* skipped);
// The built-in scene, one sphere, spheres on a ground plane, a closed mesh.
std::vector<BenchScene> basic_scenes(uint32_t width, uint32_t height, const std::filesystem::path& = {},
                                     std::vector<std::string>* = nullptr);
// Closed meshes of 1k to 4M triangles, sphere fields of 1 to 10k spheres.
std::vector<BenchScene> scaling_scenes(uint32_t width, uint32_t height, const std::filesystem::path& = {},
                                       std::vector<std::string>* = nullptr);
// The numerically hard cases of engine/bench/stiff_cases.hpp (cases about image sizes keep theirs).
std::vector<BenchScene> stiff_scenes(uint32_t width, uint32_t height, const std::filesystem::path& = {},
                                     std::vector<std::string>* = nullptr);
// The stiff cases, then the basic scenes and the Stanford bunny (accuracy_model): what
// docs/accuracy.md tabulates.
std::vector<BenchScene> accuracy_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                        std::vector<std::string>* skipped);
// Every .obj file in `models_dir`, framed to fill the image (none when the folder is absent; the
// caller says so).
std::vector<BenchScene> model_folder_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                            std::vector<std::string>* skipped);
// For given rays: the Utah teapot (6k triangles, open seams), the Stanford bunny (70k) and dragon (100k).
std::vector<BenchScene> given_rays_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                          std::vector<std::string>* skipped);
// For a deforming mesh: the Stanford bunny and dragon.
std::vector<BenchScene> moving_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                      std::vector<std::string>* skipped);
// To be placed many times: the Stanford bunny, dragon and armadillo and two small models (Spot, the
// Utah teapot).
std::vector<BenchScene> instances_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                         std::vector<std::string>* skipped);

// For point queries: the Stanford bunny (70k triangles, open at its base), dragon (100k) and
// armadillo (50k).
std::vector<BenchScene> points_scenes(uint32_t width, uint32_t height, const std::filesystem::path& models_dir,
                                      std::vector<std::string>* skipped);

}  // namespace vkray
