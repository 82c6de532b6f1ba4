// The process's peak resident memory, for --timings and the bench, and what the system has free;
// vectors whose numbers are left for their writer to fill.
#pragma once

#include <sys/resource.h>

#include <cstddef>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

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

// An allocator whose vectors leave numbers uninitialized when they grow: cast_rays writes every
// ray's entries once, where filling them first cost a million rays 2-3 ms of 40.
template <typename T>
struct UninitializedAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  template <typename U>
  void construct(U* place) noexcept {
    ::new (static_cast<void*>(place)) U;
  }
};
template <typename T>
using UninitializedVector = std::vector<T, UninitializedAllocator<T>>;

}  // namespace vkray
