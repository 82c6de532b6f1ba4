// FNV-1a, 64 bits (Fowler, Noll and Vo; offset basis and prime from the authors' reference):
// a fast checksum where no adversary is involved, the bench's scene identity and the pipeline
// cache file's integrity.
#pragma once

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>

namespace vkray {

struct Fnv1a {
  uint64_t hash = 0xcbf29ce484222325ull;
  void add_bytes(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  }
  void add(double value) { add_bytes(&value, sizeof value); }
  void add(const glm::dvec3& v) { add(v.x), add(v.y), add(v.z); }
  void add(uint64_t value) { add_bytes(&value, sizeof value); }
};

}  // namespace vkray
