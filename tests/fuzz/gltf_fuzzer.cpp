// libFuzzer target: a glTF's JSON (the .gltf text), through vkray's checks of its shape and tinygltf
// into vkray's reading of the model: nesting, node graphs (cycles, DAGs that multiply a mesh),
// transforms, cameras, accessors and buffers. Buffers come from data: uris; a uri naming a file is
// looked for in a folder that does not exist, so no input reads the machine's files. Bad input must
// end in InputError; any other exception, a crash, a hang or a sanitizer report is a finding. An
// accepted model keeps the loader's promises (mesh_promises.hpp), and holds no more triangles than
// the instancing limit allows of what the file holds.
#include "engine/scene/gltf_loader.hpp"
#include "tests/fuzz/mesh_promises.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const vkray::Model model = vkray::read_gltf(bytes, false, "/nonexistent-vkray-fuzz-folder", "fuzz.gltf");
    size_t triangles = 0;
    for (const vkray::Mesh& mesh : model.meshes) {
      vkray::test::check_mesh_promises(mesh);
      triangles += mesh.triangles.size();
    }
    // Every triangle came from the file's bytes, at most max_gltf_instancing times over: a strip's
    // n indices give n - 2 triangles, each index at least a byte.
    if (triangles > vkray::max_gltf_instancing * size) std::abort();
  } catch (const vkray::InputError&) {
  }
  return 0;
}
