#include "engine/reference/compare.hpp"

#include "engine/statistics.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace vkray {

double angle_between(const glm::dvec3& a, const glm::dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

OutputErrors measure_output_errors(const Frame& frame, const Frame& reference) {
  OutputErrors errors;
  const AovSet derived{Aov::planar_depth, Aov::position, Aov::camera_position, Aov::mesh_id, Aov::primitive_id,
                       Aov::barycentric, Aov::shading_normal, Aov::texcoord};
  errors.compared = (frame.aovs.bits() & derived.bits()) != 0;
  if (!errors.compared) return errors;
  const size_t pixels = frame.pixel_count();
  auto at = [&](const std::vector<float>& planes, size_t components, size_t p) {
    glm::dvec3 value(0.0);
    for (size_t c = 0; c < components; ++c) value[static_cast<int>(c)] = planes[c * pixels + p];
    return value;
  };
  std::vector<double> planar, position, shading;
  for (size_t p = 0; p < pixels; ++p) {
    if (!frame.hit(p) || !reference.hit(p)) continue;
    const double depth = reference.depth[p];
    if (!frame.planar_depth.empty()) {
      planar.push_back(std::abs(frame.planar_depth[p] - reference.planar_depth[p]) / std::abs(double{reference.planar_depth[p]}));
    }
    for (const auto* planes : {&frame.position, &frame.camera_position}) {
      if (planes->empty()) continue;
      const auto& theirs = planes == &frame.position ? reference.position : reference.camera_position;
      position.push_back(glm::distance(at(*planes, 3, p), at(theirs, 3, p)) / depth);
    }
    if (frame.mesh_id.empty()) continue;
    if (frame.mesh_id[p] != reference.mesh_id[p] || frame.primitive_id[p] != reference.primitive_id[p]) {
      ++errors.id_mismatches;
      continue;
    }
    if (!frame.barycentric.empty()) {
      const glm::dvec3 d = glm::abs(at(frame.barycentric, 2, p) - at(reference.barycentric, 2, p));
      errors.barycentric_max = std::max({errors.barycentric_max, d.x, d.y});
    }
    if (!frame.texcoord.empty()) {
      const glm::dvec3 d = glm::abs(at(frame.texcoord, 2, p) - at(reference.texcoord, 2, p));
      errors.texcoord_max = std::max({errors.texcoord_max, d.x, d.y});
    }
    if (!frame.shading_normal.empty()) {
      shading.push_back(angle_between(at(frame.shading_normal, 3, p), at(reference.shading_normal, 3, p)) * 180.0 / std::numbers::pi);
    }
  }
  errors.planar_depth_p99 = percentile(planar, 0.99);
  errors.position_p99 = percentile(position, 0.99);
  errors.shading_normal_deg_p99 = percentile(shading, 0.99);
  return errors;
}

FrameError measure_error(const Frame& frame, const std::vector<ReferenceHit>& reference) {
  FrameError error;
  error.pixels = frame.pixel_count();
  // The depth also where only the camera outputs were asked for: they come from it alone.
  error.depth_compared = !frame.depth.empty();
  error.normal_compared = !frame.normal.empty();
  // Sized once: at 7680x4320, growing them by doubling would hold up to twice their 265 MB each.
  std::vector<double> depth_errors, depth_ulps, normal_errors;
  if (error.depth_compared) depth_errors.reserve(error.pixels), depth_ulps.reserve(error.pixels);
  if (error.normal_compared) normal_errors.reserve(error.pixels);
  const bool doubles = !frame.depth64.empty() || !frame.normal64.empty();
  for (size_t p = 0; p < error.pixels; ++p) {
    const bool nan_depth = error.depth_compared && std::isnan(frame.depth[p]);
    const bool nan_normal = error.normal_compared && glm::any(glm::isnan(frame.normal_at(p)));
    error.nan_pixels += nan_depth || nan_normal;
    const bool reference_hit = reference[p].kind != PrimitiveKind::none;
    if (frame.hit(p) != reference_hit) {
      ++error.hit_mismatches;
      continue;
    }
    if (!reference_hit) continue;
    ++error.both_hit;
    if (error.depth_compared) {
      const double difference = std::abs((doubles ? frame.depth64[p] : frame.depth[p]) - reference[p].t);
      depth_errors.push_back(difference / reference[p].t);
      depth_ulps.push_back(difference / std::ldexp(1.0, std::ilogb(reference[p].t) - 23));
    }
    if (error.normal_compared) {
      const size_t n = frame.pixel_count();
      const glm::dvec3 normal = doubles ? glm::dvec3(frame.normal64[p], frame.normal64[n + p], frame.normal64[2 * n + p])
                                        : glm::dvec3(frame.normal_at(p));
      normal_errors.push_back(angle_between(normal, reference[p].normal) * 180.0 / std::numbers::pi);
    }
  }
  error.depth_max = depth_errors.empty() ? 0.0 : *std::max_element(depth_errors.begin(), depth_errors.end());
  error.normal_deg_max = normal_errors.empty() ? 0.0 : *std::max_element(normal_errors.begin(), normal_errors.end());
  error.depth_p50 = percentile(depth_errors, 0.5);
  error.depth_p99 = percentile(depth_errors, 0.99);
  error.depth_ulp_max = depth_ulps.empty() ? 0.0 : *std::max_element(depth_ulps.begin(), depth_ulps.end());
  error.depth_ulp_p50 = percentile(depth_ulps, 0.5);
  error.depth_ulp_p99 = percentile(depth_ulps, 0.99);
  error.normal_deg_p50 = percentile(normal_errors, 0.5);
  error.normal_deg_p99 = percentile(normal_errors, 0.99);
  return error;
}

std::string FrameError::summary() const {
  char line[400];
  std::string text;
  std::snprintf(line, sizeof line, "hit/miss mismatches %zu of %zu (%.4f%%); ", hit_mismatches, pixels,
                100.0 * mismatch_fraction());
  text += line;
  if (depth_compared) {
    std::snprintf(line, sizeof line, "depth rel. error p50 %.2e p99 %.2e max %.2e; ", depth_p50, depth_p99, depth_max);
    text += line;
  } else {
    text += "depth error not computed (no depth output); ";
  }
  if (normal_compared) {
    std::snprintf(line, sizeof line, "normal error p50 %.2e p99 %.2e max %.2e deg", normal_deg_p50, normal_deg_p99,
                  normal_deg_max);
    text += line;
  } else {
    text += "normal error not computed (no normal output)";
  }
  return text;
}

}  // namespace vkray
