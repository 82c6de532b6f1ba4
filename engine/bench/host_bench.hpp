// `vkray bench --suite host`: the host's stages of a render and of many views alone, on a frame made
// on the host, so that any machine measures them, with or without a GPU: what a device's frame then
// costs to write (EXR with one thread and with all, the PNG preview, npy files), the host's copy rate
// (a readback's host part) and the disk's write rate. A GPU's render takes well under a millisecond;
// these are what the user waits for.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vkray {

struct HostStageRow {
  std::string stage;
  unsigned threads = 1;
  double median_ms = 0.0, min_ms = 0.0, max_ms = 0.0;
  uint64_t bytes = 0;  // what the stage reads or writes: its rate is bytes over the median
};

// Each stage timed `frames` times on a width x height frame of depth and normal (a sphere filling
// most of it, misses around it, as a render's are), after one untimed run; files go to a temporary
// folder, removed at the end. Throws std::runtime_error where that folder cannot be written.
std::vector<HostStageRow> bench_host_stages(uint32_t width, uint32_t height, uint32_t frames);

// The rows as the bench prints them: a header, then one line each, then what the rows say of the
// EXR's encoding on more threads.
std::string host_stages_table(const std::vector<HostStageRow>& rows, uint32_t width, uint32_t height);

}  // namespace vkray
