// The scenes of `vkray bench --suite NAME`. Generated scenes are deterministic (fixed seeds), so two
// runs, on two machines, time the same geometry: their scene hashes match (bench_report.hpp).
#pragma once

#include "engine/scene.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace vkray {

struct BenchScene {
  std::string name;
  Scene scene;
};

// "basic, scaling, stiff, models": for help texts and error messages.
inline constexpr const char* bench_suite_names = "basic, scaling, stiff, models";

// The scenes of one suite at width x height:
// - basic: the built-in scene, one sphere, spheres on a ground plane, a closed mesh;
// - scaling: closed meshes of 1k to 4M triangles, sphere fields of 1 to 10k spheres;
// - stiff: the numerically hard cases (a small sphere far away, a huge sphere as the ground, a
//   grazing plane, a scene far from the origin, a camera looking straight up, a closed mesh 1e5
//   from the origin);
// - models: every .obj file in `models_dir`, framed to fill the image (none when the folder is
//   absent; the caller says so). A file that does not load is left out, its error added to
//   `skipped` when given.
// Throws InputError for an unknown suite name.
std::vector<BenchScene> bench_suite(const std::string& suite, uint32_t width, uint32_t height,
                                    const std::filesystem::path& models_dir,
                                    std::vector<std::string>* skipped = nullptr);

}  // namespace vkray
