// libFuzzer target: the views file parser (--views: a JSON array of cameras or JSON Lines) on
// arbitrary bytes. Bad input must end in InputError; any other exception, a crash, a hang or a
// sanitizer report is a finding. An accepted camera must keep the parser's promises: a finite
// position within the coordinate bound and a field of view in (0, 180) degrees.
#include "engine/views/view_list.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    for (const vkray::Camera& camera : vkray::parse_views(text, "fuzz.jsonl")) {
      for (int k = 0; k < 3; ++k) {
        if (!(std::abs(camera.from[k]) <= vkray::max_coordinate)) std::abort();
      }
      if (camera.projection == vkray::Projection::perspective && !camera.intrinsics &&
          !(camera.fovy_degrees > 0.0 && camera.fovy_degrees < 180.0)) {
        std::abort();
      }
    }
  } catch (const vkray::InputError&) {
  }
  return 0;
}
