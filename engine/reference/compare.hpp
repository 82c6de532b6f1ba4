// Error of a rendered frame against the double-precision reference: the figures vkray reports next
// to its timings (render --check) and the tests' summary statistics.
#pragma once

#include "engine/frame.hpp"
#include "engine/reference/reference.hpp"

#include <map>
#include <string>
#include <vector>

namespace vkray {

struct FrameError {
  size_t pixels = 0;
  size_t hit_mismatches = 0;  // pixels where one says hit and the other miss
  size_t nan_pixels = 0;      // pixels with a NaN in depth or normal (counted among the misses too)
  size_t both_hit = 0;
  // Which outputs the frame had: the figures of an output it did not compute are not errors of 0.
  bool depth_compared = false, normal_compared = false;
  // Relative depth error |z - z_ref| / z_ref and normal angle error in degrees, over pixels where
  // both hit; percentiles by nearest rank.
  double depth_p50 = 0, depth_p99 = 0, depth_max = 0;
  double normal_deg_p50 = 0, normal_deg_p99 = 0, normal_deg_max = 0;
  // The depth error in float32 ulps of the reference depth (ulp(z) = 2^(floor(log2 z) - 23)): a
  // correctly rounded float32 is within 0.5.
  double depth_ulp_p50 = 0, depth_ulp_p99 = 0, depth_ulp_max = 0;

  double mismatch_fraction() const { return pixels ? static_cast<double>(hit_mismatches) / static_cast<double>(pixels) : 0.0; }
  std::string summary() const;  // one line
};

// The outputs the host derives (camera, id and surface outputs: engine/frame.hpp) against the
// reference's own (reference_frame), over the pixels where both hit, the surface outputs where both
// name the same primitive: a figure for each OutputInfo::error_field, as its OutputError says (the
// outputs that share a field share it: a pixel counts once among mismatches, its samples pool in
// a percentile). A field whose outputs the frame lacks stays 0.
struct OutputErrorField {
  std::string name;   // OutputInfo::error_field
  std::string label;  // OutputInfo::error_label
  bool count;         // a number of pixels; else a measure
  bool degrees;       // an angle
};
// Every field, counts first, then in the order of outputs().
const std::vector<OutputErrorField>& output_error_fields();

struct OutputErrors {
  bool compared = false;  // the frame has an output the host derives
  std::map<std::string, uint64_t> counts;
  std::map<std::string, double> measures;
};
OutputErrors measure_output_errors(const Frame& frame, const Frame& reference);

// Angle between unit vectors in radians, via atan2(|a x b|, a.b): accurate for tiny angles, where
// acos(a.b) is not.
double angle_between(const glm::dvec3& a, const glm::dvec3& b);

// Compares the depth and normal outputs that `frame` has with the reference hits of the same size
// (the double ones where the frame has them: the float64 shader's).
FrameError measure_error(const Frame& frame, const std::vector<ReferenceHit>& reference);

}  // namespace vkray
