// The plot of a bench report (engine/bench/bench_plot.py, run with the system's python3 and matplotlib).
#pragma once

#include <filesystem>

namespace vkray {

// Runs the embedded plot script on a bench JSON file; throws std::runtime_error with the script's
// complaint, or with what to install when python3 or matplotlib is missing.
void plot_bench(const std::filesystem::path& json, const std::filesystem::path& png);

}  // namespace vkray
