// The 8-bit preview's ramps (engine/io/preview.hpp): the thresholds reproduce the mapping they stand
// for, round(255 * clamp(f(v), 0, 1)), to within the float rounding of a threshold, and keep its
// fixed points: the nearest hit white, the farthest at the 10% floor, misses black, the disk drawn.
#include "engine/scene/camera.hpp"
#include "engine/io/preview.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace vkray {
namespace {

long direct_byte(double f) { return std::lround(255.0 * std::clamp(f, 0.0, 1.0)); }

// Away from a threshold by more than its rounding (a float ulp), the ramp gives the formula's byte;
// next to one, either neighbour.
template <typename Formula>
void expect_ramp_follows(const PreviewRamp& ramp, Formula formula, double low, double high, double (*input)(float)) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> uniform(low, high);
  int exact = 0;
  const int samples = 20000;
  for (int n = 0; n < samples; ++n) {
    const float v = static_cast<float>(uniform(random));
    const long expected = direct_byte(formula(input(v)));
    const long got = ramp.byte(v);
    EXPECT_LE(std::abs(got - expected), 1) << "at " << v;
    exact += got == expected;
  }
  EXPECT_GT(exact, samples * 999 / 1000);
}

double identity(float v) { return v; }
double negated(float v) { return -double(v); }

TEST(PreviewRamps, FollowTheirFormulas) {
  const DepthRange depths{0.75f, 40.0f};
  const double span = 1.0 / depths.near - 1.0 / depths.far;
  expect_ramp_follows(
      preview_ramps(Aov::depth, depths)[0], [&](double z) { return 0.1 + 0.9 * (1.0 / z - 1.0 / depths.far) / span; },
      -depths.far, -depths.near, negated);
  expect_ramp_follows(preview_ramps(Aov::normal, {})[0], [](double n) { return 0.5 * (n + 1.0); }, -1.0, 1.0, identity);
  const auto uv = preview_ramps(Aov::uv, {});
  expect_ramp_follows(uv[0], [](double u) { return 0.5 * (u + 1.0); }, -2.0, 2.0, identity);
  expect_ramp_follows(uv[1], [](double u) { return 0.3 * 0.5 * (u + 1.0); }, -4.0, 8.0, identity);
}

TEST(PreviewRamps, KeepTheFixedPoints) {
  const DepthRange depths{2.0f, 9.0f};
  const PreviewRamp depth = preview_ramps(Aov::depth, depths)[0];
  EXPECT_EQ(depth.byte(-depths.near), 255);
  EXPECT_EQ(depth.byte(-depths.far), 26);  // round(0.1 * 255)
  EXPECT_EQ(preview_ramps(Aov::depth, {3.0f, 3.0f})[0].byte(-3.0f), 255);  // one depth: full brightness
  const PreviewRamp normal = preview_ramps(Aov::normal, {})[0];
  EXPECT_EQ(normal.byte(-1.0f), 0);
  EXPECT_EQ(normal.byte(0.0f), 128);
  EXPECT_EQ(normal.byte(1.0f), 255);
  EXPECT_EQ(normal.byte(NAN), 0);
  const auto uv = preview_ramps(Aov::uv, {});
  EXPECT_EQ(uv[0].byte(0.0f), 128);  // blue inside the disk
  EXPECT_EQ(uv[1].byte(0.0f), 38);   // and outside: round(0.3 * 0.5 * 255)
}

TEST(PreviewRamps, TheDiskTouchesTheShorterBordersOnly) {
  for (auto [width, height] : {std::pair{9u, 5u}, std::pair{6u, 10u}, std::pair{7u, 7u}}) {
    for (uint32_t j = 0; j < height; ++j) {
      for (uint32_t i = 0; i < width; ++i) {
        const glm::dvec2 uv = pixel_uv(i, j, width, height);
        EXPECT_EQ(inside_unit_disk(i, j, width, height), uv.x * uv.x + uv.y * uv.y <= 1.0 + 1e-12)
            << i << "," << j << " of " << width << "x" << height;
      }
    }
  }
  // The middle of each shorter border is in (an odd count of pixels puts a centre on the axis)...
  EXPECT_TRUE(inside_unit_disk(4, 0, 9, 5));
  EXPECT_TRUE(inside_unit_disk(4, 4, 9, 5));
  // ...and the middle of a longer border is not.
  EXPECT_FALSE(inside_unit_disk(0, 2, 9, 5));
}

}  // namespace
}  // namespace vkray
