// Many views of one scene (`vkray render --views/--orbit/--sphere`): where their cameras come from.
#pragma once

#include "engine/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// One view of many: a camera, and the instances placed anew for it alone (a dataset's object poses
// per frame); every instance it does not place stands where the scene places it.
struct View {
  Camera camera;
  InstancePoses poses;
  std::string source;  // where a views file placed instances ("views.jsonl:57"), for messages; else empty
};

// Views in the scene file's camera form ("from" and "to" required, "up" and "fovy" optional), each
// with, optionally, "instances": [{"instance": k, "transform": {...}}] (parse_camera_object), as a
// JSON array, or as JSON Lines: one view object a line, blank lines skipped. Every error names the
// file and the line of the view at fault ("views.jsonl:57: fovy: must be in (0, 180), got 190").
// At least one view. Throws InputError.
std::vector<View> parse_views(std::string_view text, const std::string& name);
std::vector<View> load_views(const std::filesystem::path& path);

// Throws InputError naming the view's source where a view places an instance `scene` does not have,
// places one twice, or places one beyond what check_transform allows: checked for every view before
// any renders.
void check_view_poses(const std::vector<View>& views, const Scene& scene);

// `count` views of `start` turned about the axis through start.to along start.up, 360/count degrees
// apart (counterclockwise seen from above); view 0 is `start`. The distance to `to`, up and fovy
// stay.
std::vector<View> orbit_views(const Camera& start, uint32_t count);

// `count` views of start.to from start's distance, from directions spread evenly over the sphere
// about it: a Fibonacci lattice (Gonzalez, "Measurement of areas on a sphere using Fibonacci and
// latitude-longitude lattices", Math. Geosci. 42, 2010) whose poles lie along start.up, the same
// directions on every machine. Up and fovy stay (a view straight along up takes the camera's
// fallback up, docs/scene-format.md).
std::vector<View> sphere_views(const Camera& start, uint32_t count);

}  // namespace vkray
