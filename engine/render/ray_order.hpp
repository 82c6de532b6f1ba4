// Given rays that start at one point, put in an order the packet walk wants: rays that point
// nearly the same way next to each other, whatever order the caller listed them in (an image's
// rows, a LiDAR's scan lines, random samples).
#pragma once

#include "engine/scene/scene.hpp"

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace vkray {

// The origin every ray starts at, bit for bit; none when two differ or there are no rays.
std::optional<glm::dvec3> shared_origin(std::span<const GivenRay> rays);

// Rays listed as an image's rows (a camera's pixels; a scan pattern's lines): the row width W for
// which ray k points nearly the same way as rays k + 1 and k + W throughout, found where the first
// row ends and checked on 8x8 blocks sampled over the whole list; none where the list is no such
// image (fewer than 8 rows, rows under 8 rays or a list in no spatial order). Directions non-zero.
std::optional<uint32_t> scan_width(std::span<const GivenRay> rays);

// Whether runs of `run` consecutive rays, sampled over the whole list, each point into as small a
// patch of directions as `run` rays ordered by direction would (a spinning sensor's rings, scan
// lines, spirals, an image's rows): then they make packets as they are listed, with no sorting.
// Directions non-zero.
bool runs_stay_compact(std::span<const GivenRay> rays, size_t run);

// The rays' indices ordered along a Hilbert curve over their directions' octahedral map: any run of
// consecutive ones points into a small patch of the sphere of directions. Directions non-zero;
// fewer than 2^32 rays.
std::vector<uint32_t> order_by_direction(std::span<const GivenRay> rays);

}  // namespace vkray
