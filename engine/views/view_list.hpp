// Many views of one scene (`vkray render --views/--orbit/--sphere`): where their cameras come from.
#pragma once

#include "engine/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// Cameras in the scene file's camera form ("from" and "to" required, "up" and "fovy" optional), as a
// JSON array, or as JSON Lines: one camera object a line, blank lines skipped. Every error names the
// file and the line of the camera at fault ("views.jsonl:57: fovy: must be in (0, 180), got 190").
// At least one camera. Throws InputError.
std::vector<Camera> parse_views(std::string_view text, const std::string& name);
std::vector<Camera> load_views(const std::filesystem::path& path);

// `count` views of `start` turned about the axis through start.to along start.up, 360/count degrees
// apart (counterclockwise seen from above); view 0 is `start`. The distance to `to`, up and fovy
// stay.
std::vector<Camera> orbit_views(const Camera& start, uint32_t count);

// `count` views of start.to from start's distance, from directions spread evenly over the sphere
// about it: a Fibonacci lattice (Gonzalez, "Measurement of areas on a sphere using Fibonacci and
// latitude-longitude lattices", Math. Geosci. 42, 2010) whose poles lie along start.up, the same
// directions on every machine. Up and fovy stay (a view straight along up takes the camera's
// fallback up, README "Scene format").
std::vector<Camera> sphere_views(const Camera& start, uint32_t count);

}  // namespace vkray
