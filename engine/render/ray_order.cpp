#include "engine/render/ray_order.hpp"

#include "engine/parallel.hpp"
#include "shaders/gpu_layout.h"
#include "engine/unit_vector.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <utility>

namespace vkray {

std::optional<glm::dvec3> shared_origin(std::span<const GivenRay> rays) {
  if (rays.empty()) return std::nullopt;
  const GivenRay& first = rays.front();
  std::atomic<bool> shared = true;
  parallel_for_chunks(rays.size(), [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end && shared.load(std::memory_order_relaxed); ++k) {
      if (rays[k][0] != first[0] || rays[k][1] != first[1] || rays[k][2] != first[2]) shared = false;
    }
  });
  return shared ? std::optional(glm::dvec3(first[0], first[1], first[2])) : std::nullopt;
}

namespace {

// Bits per axis of a direction's cell (gpu::direction_key): 4096 x 4096 cells over the octahedral
// map's square. A 40-degree camera's rays cover about 3% of the square, 500,000 cells: a million of
// its pixels' rays fall about two to a cell, and 64 consecutive ones along the curve form a compact
// patch (on the bunny, packets of them took 33 ms where the same pixels' 8x8 blocks took 29, and
// packets along a Z-order curve over the same cells 40: a Hilbert curve never jumps).
constexpr uint32_t cell_bits = 12;
constexpr int radix_bits = 8;  // three passes over the 24-bit key, 256 counters each
constexpr int key_bits = 2 * cell_bits;
static_assert(key_bits % radix_bits == 0);

uint32_t direction_key(const glm::vec3& unit) { return gpu::direction_key(unit.x, unit.y, unit.z, cell_bits); }

// Whether groups of `group` rays out of `count`, spanning `mean_span` on average (unit directions),
// are compact enough to walk as packets: within `allowance` times what a compact patch of `group`
// rays spans, sqrt(group / count) of the whole list's extent `extent`, and within a sixth of that
// extent (a small list's compact patch is a large part of it, and ordering by direction does as
// well there).
bool groups_are_compact(double mean_span, size_t group, size_t count, double extent, double allowance) {
  const double compact = std::sqrt(static_cast<double>(group) / static_cast<double>(count)) * extent;
  return mean_span <= std::min(allowance * compact, extent / 6.0);
}

}  // namespace

std::optional<uint32_t> scan_width(std::span<const GivenRay> rays) {
  auto unit = [&](size_t k) { return unit_vector(glm::dvec3(rays[k][3], rays[k][4], rays[k][5])); };
  // The first row ends where a step between consecutive rays is over eight times the step before
  // (a camera's rows step evenly; the next row starts a whole row's width away).
  constexpr size_t block = 8, longest_row = 65536;
  size_t width = 0;
  double step_before = glm::distance(unit(0), unit(std::min<size_t>(1, rays.size() - 1)));
  for (size_t k = 1; k + 1 < std::min(rays.size(), longest_row + 1); ++k) {
    const double step = glm::distance(unit(k), unit(k + 1));
    if (step > 8.0 * step_before && step_before > 0.0) {
      width = k + 1;
      break;
    }
    step_before = step;
  }
  const size_t rows = width > 0 ? rays.size() / width : 0;
  if (width < block || rows < block) return std::nullopt;
  // Checked: 8x8 blocks of the image span no more than twice what a compact patch of 64 rays would,
  // sqrt(64 / N) of the whole list's extent (its sampled corners' bounding box), and at most a sixth
  // of that extent. A list in no such order spans about half the extent in every block; a small
  // image's blocks are large parts of it, and ordering by direction does as well there.
  constexpr size_t samples = 16;
  glm::dvec3 low(INFINITY), high(-INFINITY);
  double block_extent = 0.0;
  for (size_t row_sample = 0; row_sample < samples; ++row_sample) {
    for (size_t column_sample = 0; column_sample < samples; ++column_sample) {
      const size_t row = (rows - block) * row_sample / (samples - 1), column = (width - block) * column_sample / (samples - 1);
      const glm::dvec3 corners[] = {unit(row * width + column), unit(row * width + column + block - 1),
                                    unit((row + block - 1) * width + column), unit((row + block - 1) * width + column + block - 1)};
      for (const glm::dvec3& corner : corners) low = glm::min(low, corner), high = glm::max(high, corner);
      block_extent += std::max(glm::distance(corners[0], corners[3]), glm::distance(corners[1], corners[2]));
    }
  }
  block_extent /= samples * samples;
  if (!groups_are_compact(block_extent, block * block, rays.size(), glm::distance(low, high), 2.0)) return std::nullopt;
  return static_cast<uint32_t>(width);
}

bool runs_stay_compact(std::span<const GivenRay> rays, size_t run) {
  auto unit = [&](size_t k) { return unit_vector(glm::dvec3(rays[k][3], rays[k][4], rays[k][5])); };
  // As scan_width's blocks are tested (groups_are_compact): a run's span, over 256 runs sampled
  // evenly, the extent the box of the sampled runs. A run is a strip, thin across: up to four
  // times a patch's span it walked the bunny within 8% of packets ordered by direction (a sensor
  // inside it, every ray a hit, 4096 and 16384 azimuths a ring), and sorting costs more than that;
  // at five times (1024 azimuths) the walk took 35% longer, as long as sorting and walking.
  constexpr size_t samples = 256;
  if (rays.size() < 2 * run) return false;
  glm::dvec3 low(INFINITY), high(-INFINITY);
  double run_extent = 0.0;
  for (size_t sample = 0; sample < samples; ++sample) {
    const size_t first = (rays.size() - run) / (samples - 1) * sample;
    glm::dvec3 run_low(INFINITY), run_high(-INFINITY);
    for (size_t k = first; k < first + run; ++k) {
      const glm::dvec3 d = unit(k);
      run_low = glm::min(run_low, d), run_high = glm::max(run_high, d);
    }
    low = glm::min(low, run_low), high = glm::max(high, run_high);
    run_extent += glm::distance(run_low, run_high);
  }
  run_extent /= samples;
  return groups_are_compact(run_extent, run, rays.size(), glm::distance(low, high), 4.0);
}

std::vector<uint32_t> order_by_direction(std::span<const GivenRay> rays) {
  // (key << 32) | index, sorted by the key: least significant digit first, stable each pass.
  std::vector<uint64_t> items(rays.size()), scratch(rays.size());
  parallel_for_chunks(rays.size(), [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const GivenRay& ray = rays[k];
      items[k] = (uint64_t{direction_key(glm::vec3(unit_vector(glm::dvec3(ray[3], ray[4], ray[5]))))} << 32) | k;
    }
  });
  for (int shift = 32; shift < 32 + key_bits; shift += radix_bits) {
    std::array<size_t, size_t{1} << radix_bits> starts{};
    for (const uint64_t item : items) ++starts[(item >> shift) & (starts.size() - 1)];
    if (std::find(starts.begin(), starts.end(), items.size()) != starts.end()) continue;  // one digit: in order
    size_t next = 0;
    for (size_t& start : starts) next += std::exchange(start, next);
    for (const uint64_t item : items) scratch[starts[(item >> shift) & (starts.size() - 1)]++] = item;
    items.swap(scratch);
  }
  std::vector<uint32_t> order(rays.size());
  for (size_t k = 0; k < items.size(); ++k) order[k] = static_cast<uint32_t>(items[k]);
  return order;
}

}  // namespace vkray
