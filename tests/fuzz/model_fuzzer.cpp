// libFuzzer target: PLY and glTF models (assimp, then vkray's own reading of what it returns) on
// arbitrary bytes. The kind follows the bytes as a user's file's extension would: "ply" at the start
// is a PLY, "glTF" a binary glTF, anything else a glTF's JSON. Bad input must end in InputError; any
// other exception, a crash, a hang or a sanitizer report is a finding. An accepted model must keep
// the loader's promises (mesh_promises.hpp).
#include "engine/scene/model_loader.hpp"
#include "tests/fuzz/mesh_promises.hpp"

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::string_view extension = bytes.starts_with("ply") ? ".ply" : bytes.starts_with("glTF") ? ".glb" : ".gltf";
  try {
    const vkray::Model model = vkray::read_model_bytes(bytes, extension, "fuzz");
    for (const vkray::Mesh& mesh : model.meshes) vkray::test::check_mesh_promises(mesh);
  } catch (const vkray::InputError&) {
  }
  return 0;
}
