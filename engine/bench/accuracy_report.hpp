// docs/accuracy.md: the error and time of every shader variant on every stiff case and on ordinary
// scenes, written from a bench report (`vkray bench --suite accuracy --markdown FILE`), never typed.
#pragma once

#include "engine/bench/bench_report.hpp"

#include <string>

namespace vkray {

// The goals the summary checks on every stiff case, with the default shader.
inline constexpr double accuracy_goal_depth_ulps = 4.0;     // depth p99, float32 ulps
inline constexpr double accuracy_goal_normal_deg = 0.01;    // normal p99, degrees
inline constexpr double accuracy_goal_float64_depth = 1e-12;  // relative depth max of the float64 shader

// The Markdown document for `report`; `command` is the command line that made it.
std::string accuracy_markdown(const BenchReport& report, const std::string& command);

}  // namespace vkray
