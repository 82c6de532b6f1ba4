// `vkray report`: what one device does, in one run that writes a JSON and a Markdown report
// (docs/gpu-report.md). Its groups of rows: the device as Vulkan describes it; checks of
// correctness against the reference (the stiff cases and models, every traversal and geometry
// layout the device runs, both transfers, float64); the bench at two sizes and an 8K frame with
// Embree beside it; many views; given rays; whole `vkray render` processes. Each group runs in a process of its own (the CLI starts
// them, cli/report_command.cpp), so that a hang or a lost device ends a row, not the report: a
// group writes each row as one line of JSON the moment it is done, and the rows a process did not
// finish get their reason from how it ended.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace vkray {

inline constexpr const char* report_schema = "vkray-gpu-report-1";

struct ReportSettings {
  // The sizes CI runs on lavapipe within a few minutes (320x180 and 640x360, 64k rays, 8 views)
  // instead of a GPU's (1920x1080 and 3840x2160, an 8K frame, 1M rays, 100 views).
  bool reduced = false;
  // Where stanford-bunny.obj and stanford-dragon-100k.obj are; without them a generated mesh of
  // 80k triangles stands in, and the report says so.
  std::filesystem::path models_dir;
  // Further scenes for the bench (a scene file; docs/bench-scenes/room.json is docs/gpu-report.md's room).
  std::vector<std::filesystem::path> scene_files;
  // Rows whose variant (the traversal or layout a row runs: report_row_variant) ended its process in
  // an earlier group are skipped, saying so: a walk that hangs the device costs the report once.
  std::vector<std::string> failed_variants;
};



// A piece of the report run in one process: its rows in order, by name.
struct ReportGroup {
  std::string id;       // "checks-staging", "bench-stanford-bunny.obj-1920x1080", ...
  std::string section;  // device, checks, bench, transfer, views, rays
  std::vector<std::string> rows;
  double timeout_s = 0.0;  // for the whole group, however many processes it takes
};

// The variant a row runs ("default" for a stiff case, "float64" for the float64 check), or the row
// itself where it runs none (device, transfer, rays).
std::string report_row_variant(const ReportGroup& group, const std::string& row);

// Every group of a report with these settings, in the order they run (the device first).
std::vector<ReportGroup> report_plan(const ReportSettings& settings);

// Runs rows [first, end) of `group` on the device named by `device_choice` (as choose_gpu_device
// takes it), writing each to `out` as one line of JSON as soon as it is done, flushed: a row that
// cannot run says why in its line. Throws (and so ends the process) only where nothing more can
// run: a lost device.
void run_report_group(const ReportSettings& settings, const ReportGroup& group, size_t first,
                      const std::string& device_choice, std::ostream& out);

// The whole-process rows (section "process"): `vkray render` of a model at a size, as a user runs
// it (EXR and PNG preview, the pipeline cache warm), each a process the CLI starts and times (the
// engine starts none). What the row runs, less the executable and the output it names; none where
// the report has no model file (the generated stand-in), the row then skipped.
std::optional<std::vector<std::string>> report_process_arguments(const ReportSettings& settings, const ReportGroup& group);
// Each timed run's wall time and the largest peak resident memory among them.
struct ProcessTimes {
  std::vector<double> wall_ms;
  uint64_t peak_bytes = 0;
};
std::string report_process_row(const ReportGroup& group, size_t row, const std::string& command, const ProcessTimes& times);

// The line of a row its process did not finish: `status` "failed" (the process died or the device
// was lost: `reason` says how) or "not run" (the group's or the report's time ran out first).
std::string report_unfinished_row(const ReportGroup& group, size_t row, const std::string& status,
                                  const std::string& reason);

// The report from every row's line, in the plan's order: JSON (report_schema) and Markdown.
// `command` and `seconds` say how it was made.
std::string report_json(const std::vector<std::string>& row_lines, const std::string& command, double seconds);
std::string report_markdown(const std::string& json_text);

// Whether every row of the report ran and every check passed: the command's exit code is 0 then.
bool report_passed(const std::string& json_text);

}  // namespace vkray
