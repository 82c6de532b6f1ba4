// The process's peak resident memory, for --timings and the bench, and what the system has free.
#pragma once

#include <sys/resource.h>

#include <cstddef>
#include <cstdio>
#include <cstring>

namespace vkray {

// Peak resident set size of this process so far, in bytes (Linux reports ru_maxrss in KiB).
inline size_t peak_host_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<size_t>(usage.ru_maxrss) * 1024;
}

// The memory the system says it can give without swapping (/proc/meminfo's MemAvailable), in bytes;
// 0 where it does not say.
inline size_t available_host_memory_bytes() {
  std::FILE* info = std::fopen("/proc/meminfo", "r");
  if (!info) return 0;
  char line[256];
  size_t kib = 0;
  while (std::fgets(line, sizeof line, info)) {
    if (std::sscanf(line, "MemAvailable: %zu kB", &kib) == 1) break;
  }
  std::fclose(info);
  return kib * 1024;
}

}  // namespace vkray
