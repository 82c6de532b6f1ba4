// libFuzzer target: the views file parser (--views: a JSON array of views or JSON Lines) on
// arbitrary bytes. Bad input must end in InputError; any other exception, a crash, a hang or a
// sanitizer report is a finding. An accepted view must keep the parser's promises: a camera at a
// finite position within the coordinate bound with a field of view in (0, 180) degrees, and a
// transform for each instance it places, finite and affine.
#include "engine/views/view_list.hpp"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    for (const vkray::View& view : vkray::parse_views(text, "fuzz.jsonl")) {
      const vkray::Camera& camera = view.camera;
      for (int k = 0; k < 3; ++k) {
        if (!(std::abs(camera.from[k]) <= vkray::max_coordinate)) std::abort();
      }
      if (camera.projection == vkray::Projection::perspective && !camera.intrinsics &&
          !(camera.fovy_degrees > 0.0 && camera.fovy_degrees < 180.0)) {
        std::abort();
      }
      if (view.poses.instances.size() != view.poses.transforms.size()) std::abort();
      for (const glm::dmat4& transform : view.poses.transforms) {
        for (int column = 0; column < 4; ++column) {
          for (int row = 0; row < 4; ++row) {
            if (!std::isfinite(transform[column][row])) std::abort();
          }
          if (transform[column][3] != (column == 3 ? 1.0 : 0.0)) std::abort();
        }
      }
    }
  } catch (const vkray::InputError&) {
  }
  return 0;
}
