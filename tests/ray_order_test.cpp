// How cast_rays lays out rays from one origin for the packet walk (engine/render/ray_order.hpp):
// which lists keep their places as an image's rows, and how compact the order by direction makes
// each run of 64 rays (a packet).
#include "engine/render/ray_order.hpp"
#include "engine/unit_vector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace vkray {
namespace {

// A 60-degree pinhole camera's pixel rays, width x height, row by row (from the same origin).
std::vector<GivenRay> camera_rays(uint32_t width, uint32_t height) {
  std::vector<GivenRay> rays;
  const double shorter = std::min(width, height);
  for (uint32_t j = 0; j < height; ++j) {
    for (uint32_t i = 0; i < width; ++i) {
      rays.push_back({1, 2, 3, (2.0 * i + 1 - width) / shorter, (height - 2.0 * j - 1) / shorter, -std::sqrt(3.0)});
    }
  }
  return rays;
}

std::vector<GivenRay> shuffled(std::vector<GivenRay> rays) {
  std::shuffle(rays.begin(), rays.end(), std::mt19937_64(7));
  return rays;
}

glm::dvec3 unit_direction(const GivenRay& ray) { return unit_vector(glm::dvec3(ray[3], ray[4], ray[5])); }

TEST(RayOrder, SharedOriginIsBitForBit) {
  std::vector<GivenRay> rays = camera_rays(4, 4);
  EXPECT_EQ(shared_origin(rays), glm::dvec3(1, 2, 3));
  rays[9][2] = std::nextafter(3.0, 4.0);
  EXPECT_FALSE(shared_origin(rays));
  EXPECT_FALSE(shared_origin({}));
}

TEST(RayOrder, ImageRowsAreFound) {
  for (const auto& [width, height] : {std::pair{64u, 48u}, {200u, 100u}, {1000u, 9u}, {9u, 700u}}) {
    SCOPED_TRACE(testing::Message() << width << "x" << height);
    EXPECT_EQ(scan_width(camera_rays(width, height)), width);
  }
  // A last row short of the others is an image's rows still.
  std::vector<GivenRay> rays = camera_rays(100, 50);
  rays.resize(rays.size() - 30);
  EXPECT_EQ(scan_width(rays), 100u);
}

TEST(RayOrder, OtherListsAreNoImage) {
  EXPECT_FALSE(scan_width(shuffled(camera_rays(200, 100))));
  EXPECT_FALSE(scan_width(camera_rays(100, 7)));  // fewer rows than a packet has
  EXPECT_FALSE(scan_width(camera_rays(7, 100)));  // rows narrower than a packet
  EXPECT_FALSE(scan_width(camera_rays(20, 15)));  // blocks a third of the image across: ordered by direction instead
  // Rays ordered by direction (already packets' order) are no image's rows.
  const std::vector<GivenRay> rays = camera_rays(128, 128);
  std::vector<GivenRay> ordered;
  for (const uint32_t k : order_by_direction(rays)) ordered.push_back(rays[k]);
  EXPECT_FALSE(scan_width(ordered));
}

// A spinning sensor's rays, ring by ring (64 rings over 30 degrees of elevation, `azimuths` all
// the way round each), and a spiral's: listed in order, their runs of 64 are nearly as compact as
// packets ordered by direction. Shuffled, too few to fill two runs, or an image's rows (a run is a
// row's 64 pixels, where its 8x8 blocks are the packets: scan_width), they are not.
TEST(RayOrder, SensorRingsAndSpiralsKeepTheirOrder) {
  auto sensor = [](size_t azimuths) {
    std::vector<GivenRay> rays;
    for (size_t ring = 0; ring < 64; ++ring) {
      const double elevation = (static_cast<double>(ring) / 63.0 - 0.5) * 0.52;
      for (size_t a = 0; a < azimuths; ++a) {
        const double azimuth = 2.0 * M_PI * static_cast<double>(a) / static_cast<double>(azimuths);
        rays.push_back({0, 0, 0, std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)});
      }
    }
    return rays;
  };
  EXPECT_TRUE(runs_stay_compact(sensor(4096), 64));
  EXPECT_FALSE(runs_stay_compact(shuffled(sensor(4096)), 64));
  std::vector<GivenRay> spiral;  // 16 turns from pole to pole, 0.001 radians between neighbours
  for (size_t k = 0; k < 100000; ++k) {
    const double z = 1.0 - 2.0 * (static_cast<double>(k) + 0.5) / 100000.0, angle = 0.001 * static_cast<double>(k);
    spiral.push_back({0, 0, 0, std::sqrt(1 - z * z) * std::cos(angle), std::sqrt(1 - z * z) * std::sin(angle), z});
  }
  EXPECT_TRUE(runs_stay_compact(spiral, 64));
  EXPECT_FALSE(runs_stay_compact(camera_rays(640, 480), 64));
  EXPECT_FALSE(runs_stay_compact(camera_rays(10, 10), 64));
}

TEST(RayOrder, OrderIsAPermutation) {
  const std::vector<GivenRay> rays = shuffled(camera_rays(123, 45));
  std::vector<uint32_t> order = order_by_direction(rays);
  std::sort(order.begin(), order.end());
  std::vector<uint32_t> all(rays.size());
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(order, all);
}

// Each run of 64 consecutive rays of the order (a packet) spans, on average, at most twice the
// diagonal of an 8x8 block of the image's pixels, the packets a camera's rays take; a run of a
// shuffled list would span about half the image. Whichever way the camera looks: its rays then
// fall on different parts of the octahedral map, some across its folds.
TEST(RayOrder, RunsOfTheOrderAreCompact) {
  const uint32_t width = 256, height = 192;
  for (const glm::dvec3 axis : {glm::dvec3(0, 0, -1), glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0), glm::dvec3(0.6, -0.64, 0.48)}) {
    SCOPED_TRACE(testing::Message() << "looking along " << axis.x << "," << axis.y << "," << axis.z);
    // The camera's rays turned so that its forward -z becomes `axis` (any rotation that does).
    const glm::dvec3 forward = -axis;
    const glm::dvec3 helper = std::abs(forward.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
    const glm::dvec3 right = glm::normalize(glm::cross(helper, forward)), up = glm::cross(forward, right);
    std::vector<GivenRay> rays = camera_rays(width, height);
    for (GivenRay& ray : rays) {
      const glm::dvec3 d = ray[3] * right + ray[4] * up + ray[5] * forward;
      ray[3] = d.x, ray[4] = d.y, ray[5] = d.z;
    }
    // Pixel pitch at the image centre: the angle between two neighbouring rays there.
    const size_t centre = size_t{height / 2} * width + width / 2;
    const double pitch = glm::distance(unit_direction(rays[centre]), unit_direction(rays[centre + 1]));
    const std::vector<GivenRay> listed = shuffled(rays);
    const std::vector<uint32_t> order = order_by_direction(listed);
    double extent_sum = 0.0;
    size_t runs = 0;
    for (size_t first = 0; first + 64 <= order.size(); first += 64, ++runs) {
      glm::dvec3 low(INFINITY), high(-INFINITY);
      for (size_t n = first; n < first + 64; ++n) {
        low = glm::min(low, unit_direction(listed[order[n]]));
        high = glm::max(high, unit_direction(listed[order[n]]));
      }
      extent_sum += glm::distance(low, high);
    }
    EXPECT_LT(extent_sum / static_cast<double>(runs), 2.0 * 7.0 * std::sqrt(2.0) * pitch);
  }
}

}  // namespace
}  // namespace vkray
