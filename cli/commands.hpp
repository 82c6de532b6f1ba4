// The vkray subcommands. Each registers its options on the CLI11 app and runs through the engine;
// none touches Vulkan directly.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace vkray::cli {

// A subcommand's action after parsing; returns the process exit code.
using Action = std::function<int()>;

Action add_render_command(CLI::App& app);
Action add_info_command(CLI::App& app);
Action add_bench_command(CLI::App& app);
Action add_view_command(CLI::App& app);
Action add_manifest_command(CLI::App& app);
Action add_report_command(CLI::App& app);
Action add_points_command(CLI::App& app);

}  // namespace vkray::cli
