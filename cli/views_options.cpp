#include "cli/views_options.hpp"

#include "engine/views/view_list.hpp"

#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <cstdlib>

namespace vkray::cli {
namespace {

// A whole number in `text`, nothing else; nothing for anything else.
std::optional<uint32_t> whole_number(std::string_view text) {
  uint32_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty()) return std::nullopt;
  return value;
}

std::optional<uint32_t> environment_number(const char* name) {
  const char* value = std::getenv(name);
  if (!value) return std::nullopt;
  const auto number = whole_number(value);
  if (!number) throw InputError(std::string("--shard auto: ") + name + "='" + value + "' is not a whole number");
  return number;
}

Shard checked_shard(uint32_t index, uint32_t count, const std::string& from) {
  if (count == 0) throw InputError("--shard: " + from + " gives 0 shards");
  if (index >= count) {
    throw InputError("--shard: " + from + " gives shard " + std::to_string(index) + " of " + std::to_string(count) +
                     " (shards are numbered from 0)");
  }
  return {index, count};
}

}  // namespace

void add_views_options(CLI::App* command, ViewsOptions& options) {
  CLI::Option* views = command->add_option("--views", options.views_file,
                                           "Render many views: a JSON array of cameras in the scene file's form, each "
                                           "may place instances (\"instances\"), or JSON Lines, one a line; -o then "
                                           "holds {index} or {index:05}");
  CLI::Option* orbit = command->add_option("--orbit", options.orbit,
                                           "Render N views turned about the camera's up axis through its target")
                           ->check(CLI::Range(1u, 10'000'000u));
  CLI::Option* sphere = command->add_option("--sphere", options.sphere,
                                            "Render N views of the camera's target from directions spread evenly "
                                            "over the sphere")
                            ->check(CLI::Range(1u, 10'000'000u));
  views->excludes(orbit)->excludes(sphere);
  orbit->excludes(sphere);
  command->add_option("--manifest", options.manifest,
                      "Many views: the JSON Lines manifest, one record a view (default: manifest.jsonl beside the "
                      "first view, manifest-shard-I-of-N.jsonl for a shard)");
  command->add_option("--shard", options.shard,
                      "Many views: render only the views whose index is I modulo N, as I/N; 'auto' takes them "
                      "from a Slurm array or a Kubernetes Indexed Job (with --shard-count)");
  command->add_option("--shard-count", options.shard_count,
                      "With --shard auto under Kubernetes: the number of shards (the Job's completions)")
      ->check(CLI::Range(1u, 1'000'000u));
  command->add_flag("--overwrite", options.overwrite,
                    "Many views: render every view, also those whose files exist (and start the manifest afresh)");
}

std::vector<View> batch_views(const ViewsOptions& options, const Camera& start) {
  if (options.views_file) return load_views(*options.views_file);
  if (options.orbit) return orbit_views(start, *options.orbit);
  return sphere_views(start, *options.sphere);
}

Shard parse_shard(const ViewsOptions& options) {
  if (!options.shard) {
    if (options.shard_count) throw InputError("--shard-count goes with --shard auto");
    return {};
  }
  const std::string& text = *options.shard;
  if (text != "auto") {
    if (options.shard_count) throw InputError("--shard-count goes with --shard auto; --shard I/N gives the count");
    const size_t slash = text.find('/');
    const auto index = whole_number(std::string_view(text).substr(0, slash));
    const auto count = slash == std::string::npos ? std::nullopt : whole_number(std::string_view(text).substr(slash + 1));
    if (!index || !count) throw InputError("--shard: '" + text + "' is not I/N of whole numbers to 4294967295 (as 0/4), or auto");
    return checked_shard(*index, *count, "'" + text + "'");
  }
  if (const auto task = environment_number("SLURM_ARRAY_TASK_ID")) {
    if (options.shard_count) throw InputError("--shard-count: under Slurm the array gives the count (SLURM_ARRAY_TASK_COUNT)");
    const auto count = environment_number("SLURM_ARRAY_TASK_COUNT");
    if (!count) throw InputError("--shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not");
    const uint32_t first = environment_number("SLURM_ARRAY_TASK_MIN").value_or(0);
    // `sbatch --array=2` to redo task 2 makes an array of one task: shard 0 of 1, every view, beside
    // the shards still running. Such an array says nothing of the run's count.
    if (*count == 1 && first > 0) {
      throw InputError("--shard auto: the Slurm array holds task " + std::to_string(*task) +
                       " alone (SLURM_ARRAY_TASK_COUNT=1), as when one task of a larger array is run again: give --shard " +
                       std::to_string(*task) + "/N, N the run's task count");
    }
    const uint32_t step = environment_number("SLURM_ARRAY_TASK_STEP").value_or(1);
    if (step == 0) throw InputError("--shard auto: SLURM_ARRAY_TASK_STEP=0 is no array's step (1 or more)");
    if (*task < first || (*task - first) % step != 0) {
      throw InputError("--shard auto: SLURM_ARRAY_TASK_ID " + std::to_string(*task) + " is not in the array " +
                       std::to_string(first) + "+" + std::to_string(step) + "k");
    }
    return checked_shard((*task - first) / step, *count, "Slurm's array");
  }
  if (const auto index = environment_number("JOB_COMPLETION_INDEX")) {
    if (!options.shard_count) throw InputError("--shard auto under Kubernetes (JOB_COMPLETION_INDEX) needs --shard-count, the Job's completions");
    return checked_shard(*index, *options.shard_count, "Kubernetes' JOB_COMPLETION_INDEX");
  }
  throw InputError("--shard auto: neither Slurm's SLURM_ARRAY_TASK_ID nor Kubernetes' JOB_COMPLETION_INDEX is set; "
                   "give --shard I/N");
}

std::filesystem::path manifest_path(const ViewsOptions& options, const Shard& shard, const OutputPattern& exr) {
  if (options.manifest) return *options.manifest;
  const std::string name = shard.count == 1 ? "manifest.jsonl"
                                            : "manifest-shard-" + std::to_string(shard.index) + "-of-" +
                                                  std::to_string(shard.count) + ".jsonl";
  return exr.path(0).parent_path() / name;
}

void ViewsProgress::operator()(const ViewBatchProgress& progress) {
  if (!started_) {
    terminal_ = isatty(STDERR_FILENO) == 1;
    started_ = true;
  }
  const double rate = progress.seconds > 0.0 ? progress.done / progress.seconds : 0.0;
  const double left_s = rate > 0.0 ? (progress.to_do - progress.done) / rate : 0.0;
  const bool finished = progress.done == progress.to_do;
  if (terminal_) {
    constexpr int bar_width = 30;
    const int filled = static_cast<int>(bar_width * static_cast<double>(progress.done) / progress.to_do);
    std::fprintf(stderr, "\rvkray: [%-*s] %u/%u views, %.1f views/s, %.0f s left  ", bar_width,
                 std::string(static_cast<size_t>(filled), '#').c_str(), progress.done, progress.to_do, rate, left_s);
    if (finished) std::fputc('\n', stderr);
  } else if (progress.seconds - last_line_s_ >= 5.0 || finished) {
    last_line_s_ = progress.seconds;
    std::fprintf(stderr, "vkray: %u/%u views, %.1f views/s, about %.0f s left\n", progress.done, progress.to_do, rate, left_s);
  }
  std::fflush(stderr);
}

}  // namespace vkray::cli
