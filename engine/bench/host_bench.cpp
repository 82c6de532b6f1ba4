#include "engine/bench/host_bench.hpp"

#include "engine/bench/scratch_folder.hpp"
#include "engine/io/exr_file.hpp"
#include "engine/io/image_io.hpp"
#include "engine/statistics.hpp"
#include "engine/stopwatch.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace vkray {
namespace {

// A unit sphere seen from 3 away, filling most of the frame: depths and normals with the smooth
// runs and the edges a render has, which decide what deflate makes of them.
Frame sphere_frame(uint32_t width, uint32_t height) {
  Frame frame(width, height, AovSet{Aov::depth, Aov::normal});
  frame.allocate(false);
  const size_t pixels = frame.pixel_count();
  const double shorter = std::min(width, height);
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) {
      const size_t p = size_t{j} * width + i;
      // An orthographic view: the ray through (x, y) meets the sphere at z = sqrt(1 - x^2 - y^2).
      const double x = (2.0 * i + 1 - width) / shorter * 1.2, y = (height - 2.0 * j - 1) / shorter * 1.2;
      const double r2 = x * x + y * y;
      const bool hit = r2 < 1.0;
      const double z = hit ? std::sqrt(1.0 - r2) : 0.0;
      frame.depth[p] = hit ? static_cast<float>(3.0 - z) : INFINITY;
      const double normal[3] = {hit ? x : 0.0, hit ? y : 0.0, hit ? z : 0.0};
      for (size_t c = 0; c < 3; ++c) frame.normal[c * pixels + p] = static_cast<float>(normal[c]);
    }
  }
  return frame;
}

template <typename Stage>
HostStageRow timed(const std::string& name, unsigned threads, uint64_t bytes, uint32_t frames, Stage&& stage) {
  stage();  // untimed: first touches, caches
  std::vector<double> times;
  for (uint32_t k = 0; k < frames; ++k) {
    const auto start = Clock::now();
    stage();
    times.push_back(elapsed_ms(start));
  }
  const TimeStats stats = time_stats(times);
  return {name, threads, stats.median_ms, stats.min_ms, stats.max_ms, bytes};
}

// Writes `bytes` to a file and flushes it to the disk: the disk's write rate.
void write_and_sync(const std::filesystem::path& path, const std::vector<char>& block, size_t blocks) {
  const int file = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (file < 0) throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(errno));
  bool written = true;
  for (size_t k = 0; k < blocks && written; ++k) written = ::write(file, block.data(), block.size()) == static_cast<ssize_t>(block.size());
  written = written && ::fsync(file) == 0;
  ::close(file);
  if (!written) throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(errno));
}

}  // namespace

std::vector<HostStageRow> bench_host_stages(uint32_t width, uint32_t height, uint32_t frames) {
  const ScratchFolder scratch("vkray-host-bench-");
  const std::filesystem::path& folder = scratch.path();
  const Frame frame = sphere_frame(width, height);
  const uint64_t frame_bytes = Frame::bytes(width, height, frame.aovs, false);
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  std::vector<HostStageRow> rows;
  OutputSettings exr;
  for (const unsigned threads : {1u, cores}) {
    use_exr_threads(threads);
    rows.push_back(timed("EXR (" + exr.compression + "), depth and normal", threads, frame_bytes, frames,
                         [&] { write_outputs(folder / "frame.exr", nullptr, frame, exr); }));
  }
  use_exr_threads(cores);
  rows.push_back(timed("PNG preview, depth and normal panels", cores, frame_bytes, frames,
                       [&] { write_preview(folder / "frame.png", frame); }));
  OutputSettings npy;
  npy.format = FileFormat::npy;
  rows.push_back(timed("npy files, depth and normal", 1, frame_bytes, frames, [&] { write_outputs(folder / "frame.exr", nullptr, frame, npy); }));
  // The host's part of a readback: the frame's planes copied once, as from mapped memory.
  std::vector<float> copy(frame.depth.size() + frame.normal.size());
  rows.push_back(timed("host copy of the frame's planes", 1, frame_bytes, frames, [&] {
    std::memcpy(copy.data(), frame.depth.data(), frame.depth.size() * sizeof(float));
    std::memcpy(copy.data() + frame.depth.size(), frame.normal.data(), frame.normal.size() * sizeof(float));
  }));
  // The disk: 256 MiB written and flushed (fsync), as each view's files are.
  const std::vector<char> block(size_t{4} << 20, 'v');
  rows.push_back(timed("disk: 256 MiB written and flushed", 1, uint64_t{256} << 20, frames,
                       [&] { write_and_sync(folder / "disk.bin", block, 64); }));
  return rows;
}

std::string host_stages_table(const std::vector<HostStageRow>& rows, uint32_t width, uint32_t height) {
  std::string table;
  char line[200];
  std::snprintf(line, sizeof line, "host stages on a %ux%u frame of depth and normal (%.1f MB), medians\n", width, height,
                static_cast<double>(width) * height * 16 / 1e6);
  table += line;
  std::snprintf(line, sizeof line, "%-40s %7s %10s %10s %10s %10s\n", "stage", "threads", "median ms", "min ms", "max ms", "MB/s");
  table += line;
  for (const HostStageRow& row : rows) {
    std::snprintf(line, sizeof line, "%-40s %7u %10.1f %10.1f %10.1f %10.0f\n", row.stage.c_str(), row.threads, row.median_ms,
                  row.min_ms, row.max_ms, static_cast<double>(row.bytes) / 1e3 / row.median_ms);
    table += line;
  }
  if (rows.size() >= 2 && rows[1].threads > rows[0].threads) {
    std::snprintf(line, sizeof line, "EXR with %u threads: %.2f of one thread's time\n", rows[1].threads, rows[1].median_ms / rows[0].median_ms);
    table += line;
  }
  return table;
}

}  // namespace vkray
