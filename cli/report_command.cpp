// `vkray report FOLDER`: the GPU report (engine/bench/gpu_report.hpp). This process plans the
// report and runs each group of rows in a process of its own (this same executable, with the hidden
// --group option), each within its time: a hung or crashed group ends its rows with the reason, and
// the report goes on. report.json and report.md are rewritten after every group, so a report cut
// short keeps what it measured.
#include "cli/commands.hpp"
#include "engine/bench/gpu_report.hpp"
#include "engine/io/image_io.hpp"
#include "engine/stopwatch.hpp"
#include "engine/scene/scene.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace vkray::cli {
namespace {

namespace fs = std::filesystem;

struct ReportOptions {
  std::string folder;
  std::vector<std::string> scenes;
  std::string models = "../shared/models";
  bool reduced = false;
  double minutes = 0.0;  // 0: 8, or 3 reduced
  bool require_gpu = false;
  std::vector<std::string> only;  // sections; empty: all
  std::string device;
  // The hidden options of a group's process.
  std::string group;
  size_t first_row = 0;
  std::string rows_file;
  std::vector<std::string> failed_variants;
};

ReportSettings settings_of(const ReportOptions& options) {
  ReportSettings settings;
  settings.reduced = options.reduced;
  settings.models_dir = options.models;
  for (const auto& scene : options.scenes) settings.scene_files.push_back(fs::absolute(scene));
  settings.failed_variants = options.failed_variants;
  return settings;
}

// The options that decide what is measured, as a command: the report names it.
std::string command_line(const ReportOptions& options) {
  std::string line = "vkray report " + options.folder;
  for (const auto& scene : options.scenes) line += " " + scene;
  line += " --models " + options.models;
  if (options.reduced) line += " --reduced";
  if (!options.device.empty()) line += " --device '" + options.device + "'";
  if (options.require_gpu) line += " --require-gpu";
  if (!options.only.empty()) {
    line += " --only ";
    for (size_t k = 0; k < options.only.size(); ++k) line += (k ? "," : "") + options.only[k];
  }
  return line;
}

// The last non-empty line of a file: a group's process says there why it stopped.
std::string last_line(const fs::path& path) {
  std::ifstream file(path);
  std::string line, last;
  while (std::getline(file, line)) {
    if (!line.empty()) last = line;
  }
  return last;
}

std::vector<std::string> lines_of(const fs::path& path) {
  std::ifstream file(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(file, line);) {
    if (!line.empty() && line.front() == '{' && line.back() == '}') lines.push_back(line);  // a cut-off last line is no row
  }
  return lines;
}

// How a group's process ended.
struct Ended {
  bool timed_out = false;
  int status = 0;  // waitpid's
  uint64_t peak_bytes = 0;  // the process's peak resident memory (getrusage's ru_maxrss)
};

// Starts this executable with `arguments` in a process group of its own, its standard error
// appended to `log`, and waits at most `seconds` (then kills the whole group).
Ended run_process(const std::vector<std::string>& arguments, const std::vector<std::string>& environment,
                  const fs::path& log, double seconds) {
  std::vector<char*> argv;
  for (const auto& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  std::vector<char*> envp;
  for (const auto& variable : environment) envp.push_back(const_cast<char*>(variable.c_str()));
  envp.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, "/proc/self/exe", &files, &attributes, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) throw std::runtime_error(std::string("cannot start a report process: ") + std::strerror(spawned));
  const auto deadline = after_ms(Clock::now(), 1e3 * std::max(seconds, 0.0));
  Ended ended;
  struct rusage usage {};
  while (wait4(pid, &ended.status, WNOHANG, &usage) == 0) {
    if (Clock::now() >= deadline) {
      kill(-pid, SIGKILL);
      wait4(pid, &ended.status, 0, &usage);
      ended.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ended.peak_bytes = static_cast<uint64_t>(usage.ru_maxrss) * 1024;  // in KiB on Linux
  return ended;
}

// The environment of a group's process: the checks run under the validation layer where it is
// installed (unless VKRAY_VALIDATION says otherwise); timed groups as the user runs vkray.
// A submission the report waits for at most (VKRAY_FENCE_TIMEOUT_MS, where the user has not set it):
// every dispatch is sized to a fifth of a second, so a walk that hangs the device costs its group
// this, not the default minute.
constexpr const char* report_fence_timeout = "VKRAY_FENCE_TIMEOUT_MS=20000";

std::vector<std::string> group_environment(const ReportGroup& group) {
  std::vector<std::string> environment;
  for (char** variable = environ; *variable; ++variable) environment.emplace_back(*variable);
  const bool checked = group.section == "checks" || group.section == "device";
  if (checked && !std::getenv("VKRAY_VALIDATION")) environment.emplace_back("VKRAY_VALIDATION=if-installed");
  if (!std::getenv("VKRAY_FENCE_TIMEOUT_MS")) environment.emplace_back(report_fence_timeout);
  return environment;
}

std::string describe_end(const Ended& ended, double seconds, const fs::path& log) {
  if (ended.timed_out) {
    return "stopped: the time left to its group (" + std::to_string(static_cast<int>(seconds)) + " s) ran out while it ran";
  }
  const std::string said = last_line(log);
  if (WIFSIGNALED(ended.status)) {
    return std::string("the process ended by signal ") + strsignal(WTERMSIG(ended.status)) + (said.empty() ? "" : " after: " + said);
  }
  return said.empty() ? "the process exited with code " + std::to_string(WEXITSTATUS(ended.status)) : said;
}

// Runs every row of `group`, in as many processes as it takes, within `seconds`; returns the rows'
// lines (those that did not run carry their reason). The variant of a row that ends its process
// joins `failed_variants`: later groups skip it.
std::vector<std::string> run_group(const ReportOptions& options, const ReportGroup& group, double seconds,
                                   std::vector<std::string>& failed_variants) {
  const fs::path parts = fs::path(options.folder) / "parts";
  const fs::path rows_file = parts / (group.id + ".jsonl"), log = parts / (group.id + ".log");
  fs::remove(rows_file);
  fs::remove(log);
  const auto deadline = after_ms(Clock::now(), 1e3 * seconds);
  std::vector<std::string> lines;
  // Processes in a row that ended before their last row: past three, something is wrong with every
  // row (a driver that crashes, a layer that aborts), and the group's time is better left to others.
  constexpr int most_ended_in_a_row = 3;
  int ended_in_a_row = 0;
  while (lines.size() < group.rows.size()) {
    const double left = -elapsed_ms(deadline) / 1e3;
    if (left <= 0.0 || ended_in_a_row == most_ended_in_a_row) {
      const std::string why = left <= 0.0 ? "the group's time ran out"
                                          : "three of its processes in a row ended early (the failed rows above say how)";
      for (size_t row = lines.size(); row < group.rows.size(); ++row) lines.push_back(report_unfinished_row(group, row, "not run", why));
      break;
    }
    std::vector<std::string> arguments = {"vkray", "report", options.folder, "--models", options.models, "--group", group.id,
                                          "--from", std::to_string(lines.size()), "--rows-file", rows_file.string()};
    for (const auto& scene : options.scenes) arguments.push_back(scene);
    if (options.reduced) arguments.push_back("--reduced");
    if (!options.device.empty()) arguments.insert(arguments.end(), {"--device", options.device});
    for (const auto& variant : failed_variants) arguments.insert(arguments.end(), {"--failed-variant", variant});
    const Ended ended = run_process(arguments, group_environment(group), log, left);
    const std::vector<std::string> written = lines_of(rows_file);
    ended_in_a_row = written.size() == lines.size() ? ended_in_a_row + 1 : 1;
    lines = written;
    if (!ended.timed_out && WIFEXITED(ended.status) && WEXITSTATUS(ended.status) == 0 && lines.size() >= group.rows.size()) break;
    if (lines.size() < group.rows.size()) {
      // The row being run when the process ended is the one that failed; the next process goes on after it.
      // A variant that crashed or lost the device is not tried again; one stopped by the clock
      // (a slow device) is.
      const std::string variant = report_row_variant(group, group.rows[lines.size()]);
      if (!ended.timed_out && group.section != "device" && variant != "default") failed_variants.push_back(variant);
      lines.push_back(report_unfinished_row(group, lines.size(), "failed", describe_end(ended, left, log)));
      std::ofstream(rows_file, std::ios::app) << lines.back() << '\n';
    }
  }
  return lines;
}

// A process group's rows (report_process_arguments): `vkray render` run once to warm the pipeline
// cache, then timed three times, each a process of its own, its output in the group's parts folder
// and removed afterwards.
void run_process_rows(const ReportOptions& options, const ReportSettings& settings, const ReportGroup& group,
                      std::ostream& rows) {
  const std::optional<std::vector<std::string>> arguments = report_process_arguments(settings, group);
  if (!arguments) {
    rows << report_unfinished_row(group, 0, "skipped", "no model file to render (the generated stand-in has none)") << std::endl;
    return;
  }
  const fs::path parts = fs::path(options.folder) / "parts";
  const fs::path output = parts / (group.id + ".exr"), log = parts / (group.id + ".render.log");
  std::vector<std::string> command = {"vkray"};
  command.insert(command.end(), arguments->begin(), arguments->end());
  command.insert(command.end(), {"-o", output.string()});
  if (!options.device.empty()) command.insert(command.end(), {"--device", options.device});
  std::vector<std::string> environment;
  for (char** variable = environ; *variable; ++variable) environment.emplace_back(*variable);
  constexpr int timed_runs = 3;
  ProcessTimes times;
  for (int run = 0; run <= timed_runs; ++run) {
    const auto start = Clock::now();
    const Ended ended = run_process(command, environment, log, group.timeout_s);
    const double wall_ms = elapsed_ms(start);
    if (ended.timed_out || !WIFEXITED(ended.status) || WEXITSTATUS(ended.status) != 0) {
      rows << report_unfinished_row(group, 0, "failed", describe_end(ended, group.timeout_s, log)) << std::endl;
      return;
    }
    if (run == 0) continue;  // the pipeline cache warmed
    times.wall_ms.push_back(wall_ms);
    times.peak_bytes = std::max(times.peak_bytes, ended.peak_bytes);
  }
  std::string shown = "vkray";
  for (const std::string& argument : *arguments) shown += " " + argument;
  rows << report_process_row(group, 0, shown, times) << std::endl;
  for (const fs::path& file : {output, fs::path(output).replace_extension(".png"), log}) fs::remove(file);
}

int run_report(const ReportOptions& options) {
  const ReportSettings settings = settings_of(options);
  if (!options.group.empty()) {  // one group's process
    for (const ReportGroup& group : report_plan(settings)) {
      if (group.id != options.group) continue;
      std::ofstream rows(options.rows_file, std::ios::app);
      if (!rows) throw std::runtime_error("cannot write " + options.rows_file);
      if (group.section == "process") {
        run_process_rows(options, settings, group, rows);
      } else {
        run_report_group(settings, group, options.first_row, options.device, rows);
      }
      return 0;
    }
    throw InputError("--group: no group '" + options.group + "' in this report");
  }

  for (const auto& scene : options.scenes) {
    if (!fs::is_regular_file(scene)) throw InputError("no such scene file: " + scene);
  }
  const fs::path folder = options.folder;
  fs::create_directories(folder / "parts");
  const double minutes = options.minutes > 0.0 ? options.minutes : options.reduced ? 3.0 : 8.0;
  const auto start = Clock::now();
  const auto deadline = after_ms(start, 60e3 * minutes);
  const std::string command = command_line(options);
  std::vector<std::string> lines, failed_variants;
  std::string json;
  auto save = [&] {
    json = report_json(lines, command, elapsed_ms(start) / 1e3);
    write_text_file(folder / "report.json", json);
    write_text_file(folder / "report.md", report_markdown(json));
  };
  for (const ReportGroup& group : report_plan(settings)) {
    if (!options.only.empty() && group.section != "device" &&
        std::find(options.only.begin(), options.only.end(), group.section) == options.only.end()) {
      continue;
    }
    const double left = -elapsed_ms(deadline) / 1e3;
    const auto group_start = Clock::now();
    std::vector<std::string> group_lines;
    if (left <= 0.0) {
      for (size_t row = 0; row < group.rows.size(); ++row) {
        group_lines.push_back(report_unfinished_row(group, row, "not run", "the report's time ran out"));
      }
    } else {
      group_lines = run_group(options, group, std::min(group.timeout_s, left), failed_variants);
    }
    lines.insert(lines.end(), group_lines.begin(), group_lines.end());
    save();
    size_t ok = 0, skipped = 0;
    for (const auto& line : group_lines) {
      ok += line.find("\"status\":\"ok\"") != std::string::npos;
      skipped += line.find("\"status\":\"skipped\"") != std::string::npos;
    }
    if (group.section == "device") {  // the first line names the device
      const std::string markdown = report_markdown(json);
      std::printf("%s\n", markdown.substr(2, markdown.find('\n') - 2).c_str());
      std::fflush(stdout);
      if (options.require_gpu && group_lines.front().find("\"type\":\"cpu\"") != std::string::npos) {
        std::fprintf(stderr, "vkray: --require-gpu, and the device is a CPU implementation of Vulkan: no GPU report "
                             "(see `vkray info`; %s)\n", (folder / "report.md").c_str());
        return 1;
      }
      if (group_lines.empty() || group_lines.front().find("\"status\":\"ok\"") == std::string::npos) {
        std::fprintf(stderr, "vkray: no device to report on: %s\n", group_lines.front().c_str());
        return 1;
      }
      continue;
    }
    std::printf("%-44s %3zu rows: %zu ok, %zu skipped, %zu failed or not run (%.0f s)\n", group.id.c_str(), group_lines.size(),
                ok, skipped, group_lines.size() - ok - skipped,
                elapsed_ms(group_start) / 1e3);
    std::fflush(stdout);
  }
  const bool passed = report_passed(json);
  std::printf("%s, %s: %s\n", (folder / "report.json").c_str(), (folder / "report.md").c_str(),
              passed ? "every row ran and every check passed" : "some rows failed or did not run, or a check failed");
  return passed ? 0 : 1;
}

}  // namespace

Action add_report_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "report", "Report what this device does: correctness checks, the bench, many views and given rays, as JSON and "
                "Markdown (docs/gpu-report.md).");
  auto options = std::make_shared<ReportOptions>();
  command->add_option("folder", options->folder, "Folder for report.json, report.md and each group's log (parts/)")->required();
  command->add_option("scenes", options->scenes, "Scene files to bench beside the models (docs/bench-scenes/room.json)");
  command->add_option("--models", options->models, "Folder holding stanford-bunny.obj and stanford-dragon-100k.obj")
      ->capture_default_str();
  command->add_flag("--reduced", options->reduced,
                    "Small sizes (320x180, 640x360 and 1280x720, 64k rays, 8 views): a few minutes on lavapipe, as CI runs it");
  command->add_option("--minutes", options->minutes, "Time for the whole report (default 8, or 3 with --reduced)")
      ->check(CLI::Range(0.1, 1e4));
  command->add_option("--only", options->only,
                      "Only these sections (and the device): checks, bench, rays, views, transfer, process")
      ->delimiter(',')
      ->check(CLI::IsMember({"checks", "bench", "rays", "views", "transfer", "process"}));
  command->add_flag("--require-gpu", options->require_gpu,
                    "Exit 1 after the first line when the device is a CPU implementation of Vulkan (lavapipe)");
  command->add_option("--device", options->device,
                      "The Vulkan device: its number or UUID as 'vkray info' prints them, or text its name contains");
  // A group's process (run_group); not for users.
  command->add_option("--group", options->group)->group("");
  command->add_option("--from", options->first_row)->group("");
  command->add_option("--rows-file", options->rows_file)->group("");
  command->add_option("--failed-variant", options->failed_variants)->group("");
  return [options] { return run_report(*options); };
}

}  // namespace vkray::cli
