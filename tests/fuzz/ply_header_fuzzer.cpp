// libFuzzer target: PLY headers. The input is the lines between "ply" and "end_header", followed by
// a fixed body (ply_header_input.hpp): the mutations go to the elements, properties, lists, types,
// counts and formats, where the second hostile campaign found its faults (two vertex elements, counts of empty records, a second format line, MeshLab's lists).
// Bad input must end in InputError; any other exception, a crash, a hang or a sanitizer report is a
// finding. An accepted mesh keeps the loader's promises (mesh_promises.hpp).
#include "engine/scene/model_loader.hpp"
#include "tests/fuzz/mesh_promises.hpp"
#include "tests/fuzz/ply_header_input.hpp"

#include <cstdint>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string file = vkray::test::ply_from_header(std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    const vkray::Model model = vkray::read_model_bytes(file, ".ply", "fuzz.ply");
    for (const vkray::Mesh& mesh : model.meshes) vkray::test::check_mesh_promises(mesh);
  } catch (const vkray::InputError&) {
  }
  return 0;
}
