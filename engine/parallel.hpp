// Splitting a loop over the host's cores.
#pragma once

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace vkray {

// Calls chunk(begin, end) for contiguous ranges covering [0, count), one a hardware thread, and
// returns when all are done. Ranges of at least `min_chunk` items: below that a thread costs more
// than it saves.
template <typename Chunk>
void parallel_for_chunks(size_t count, Chunk&& chunk, size_t min_chunk = 4096) {
  const size_t workers = std::clamp<size_t>(count / std::max<size_t>(min_chunk, 1), 1, std::max(1u, std::thread::hardware_concurrency()));
  if (workers == 1) {
    chunk(size_t{0}, count);
    return;
  }
  std::vector<std::jthread> threads;
  for (size_t worker = 0; worker < workers; ++worker) {
    threads.emplace_back([&, worker] { chunk(count * worker / workers, count * (worker + 1) / workers); });
  }
}

// Calls item(k, worker) for every k in [0, count), worker w of W taking k = w, w + W, w + 2W, ...
// (one worker a hardware thread, at most `count`), and returns when all are done: neighbouring
// items, which cost alike (an image's rows, a sky above a mesh), spread over every worker.
template <typename Item>
void parallel_for_strided(size_t count, Item&& item) {
  const size_t workers = std::clamp<size_t>(std::thread::hardware_concurrency(), 1, std::max<size_t>(count, 1));
  std::vector<std::jthread> threads;
  for (size_t worker = 0; worker < workers; ++worker) {
    threads.emplace_back([&, worker] {
      for (size_t k = worker; k < count; k += workers) item(k, worker);
    });
  }
}

}  // namespace vkray
