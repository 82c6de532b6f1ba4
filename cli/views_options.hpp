// `vkray render`'s options for many views in one run: where the cameras come from, which of them
// this process renders (shards for Slurm and Kubernetes), and how their progress shows.
#pragma once

#include "engine/views/view_batch.hpp"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vkray::cli {

struct ViewsOptions {
  std::optional<std::string> views_file;
  std::optional<uint32_t> orbit, sphere;
  std::optional<std::string> manifest;
  std::optional<std::string> shard;
  std::optional<uint32_t> shard_count;
  bool overwrite = false;
  bool any() const { return views_file || orbit || sphere; }
};

// Registers --views, --orbit, --sphere, --manifest, --shard, --shard-count and --overwrite.
void add_views_options(CLI::App* command, ViewsOptions& options);

// The views the options ask for; `start` is the scene's (or the framed) camera. Throws InputError.
std::vector<View> batch_views(const ViewsOptions& options, const Camera& start);

// --shard I/N, or auto: I and N from Slurm's array variables (SLURM_ARRAY_TASK_ID less
// SLURM_ARRAY_TASK_MIN, over SLURM_ARRAY_TASK_STEP; SLURM_ARRAY_TASK_COUNT tasks) or from
// Kubernetes' JOB_COMPLETION_INDEX with --shard-count. Throws InputError.
Shard parse_shard(const ViewsOptions& options);

// --manifest, or manifest.jsonl beside the first view's file (manifest-shard-I-of-N.jsonl for a
// shard, so that shards writing into one folder keep their own parts).
std::filesystem::path manifest_path(const ViewsOptions& options, const Shard& shard, const OutputPattern& exr);

// Progress on stderr: a bar with the rate and the time left on a terminal, a line every 5 s
// otherwise (logs of batch jobs).
class ViewsProgress {
 public:
  void operator()(const ViewBatchProgress& progress);

 private:
  bool terminal_ = false;
  bool started_ = false;
  double last_line_s_ = 0.0;
};

}  // namespace vkray::cli
