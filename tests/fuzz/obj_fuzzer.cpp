// libFuzzer target: the OBJ loader on arbitrary bytes. Bad input must end in InputError; any other
// exception, a crash, a hang or a sanitizer report is a finding. An accepted mesh must keep the
// loader's promises: finite positions within the coordinate bound, indices in range.
#include "engine/scene/obj_loader.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const vkray::Mesh mesh = vkray::load_obj_text(text, "fuzz.obj");
    for (const auto& position : mesh.positions) {
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(position[k])) std::abort();
      }
    }
    for (const auto& triangle : mesh.triangles) {
      for (uint32_t index : triangle) {
        if (index >= mesh.positions.size()) std::abort();
      }
    }
  } catch (const vkray::InputError&) {
  }
  return 0;
}
