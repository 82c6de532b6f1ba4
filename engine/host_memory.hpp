// The process's peak resident memory, for --timings and the bench.
#pragma once

#include <sys/resource.h>

#include <cstddef>

namespace vkray {

// Peak resident set size of this process so far, in bytes (Linux reports ru_maxrss in KiB).
inline size_t peak_host_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<size_t>(usage.ru_maxrss) * 1024;
}

}  // namespace vkray
