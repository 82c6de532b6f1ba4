// libFuzzer target: the scene parser on arbitrary bytes. Bad input must end in InputError (one clear
// line, exit 2); any other exception, a crash, a hang or a sanitizer report is a finding. OBJ
// files a scene names are served from one fixed in-memory cube, so the fuzzer reaches the transform
// code without touching the disk.
#include "engine/scene/obj_loader.hpp"
#include "engine/scene/scene_loader.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

namespace {

constexpr std::string_view cube_obj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const vkray::Scene scene = vkray::parse_scene(text, "fuzz.json", "/nonexistent",
                                                  [](const std::filesystem::path& path) {
                                                    return std::vector<vkray::Mesh>{vkray::load_obj_text(cube_obj, path.string())};
                                                  });
    // What the loader promises about a scene it accepts.
    vkray::check_image_size(scene.width, scene.height);
    for (const auto& sphere : scene.spheres) {
      if (!(sphere.radius > 0.0) || !(sphere.radius <= vkray::max_coordinate)) std::abort();
    }
    for (const auto& mesh : scene.meshes) {
      for (const auto& triangle : mesh.triangles) {
        for (uint32_t index : triangle) {
          if (index >= mesh.positions.size()) std::abort();
        }
      }
    }
  } catch (const vkray::InputError&) {
  }
  return 0;
}
