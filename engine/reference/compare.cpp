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

const std::vector<OutputErrorField>& output_error_fields() {
  static const std::vector<OutputErrorField> fields = [] {
    std::vector<OutputErrorField> list;
    for (const bool counts : {true, false}) {
      for (const OutputInfo& output : outputs()) {
        if (output.error == OutputError::none || (output.error == OutputError::mismatches) != counts) continue;
        if (std::none_of(list.begin(), list.end(), [&](const OutputErrorField& f) { return f.name == output.error_field; })) {
          list.push_back({output.error_field, output.error_label, counts, output.error == OutputError::degrees_p99});
        }
      }
    }
    return list;
  }();
  return fields;
}

OutputErrors measure_output_errors(const Frame& frame, const Frame& reference) {
  OutputErrors errors;
  for (const auto& field : output_error_fields()) {
    if (field.count) {
      errors.counts[field.name] = 0;
    } else {
      errors.measures[field.name] = 0.0;
    }
  }
  // The ids also where only the surface outputs asked for them: their mismatches say which pixels
  // the surface outputs are not compared on.
  std::vector<const OutputInfo*> measured;
  for (const OutputInfo& output : outputs()) {
    const bool computed = frame.aovs.has(output.aov) || (output.source == OutputSource::ids && frame.aovs.has_surface_outputs());
    if (output.error != OutputError::none && computed) measured.push_back(&output);
  }
  errors.compared = !measured.empty();
  if (!errors.compared) return errors;
  const size_t pixels = frame.pixel_count();
  // Component c of an output's value at pixel p, in double.
  auto component = [&](const Frame& of, const OutputInfo& output, size_t c, size_t p) {
    return output.integers ? double((of.*output.integers)[c * pixels + p]) : double((of.*output.floats)[c * pixels + p]);
  };
  auto vector = [&](const Frame& of, const OutputInfo& output, size_t p) {
    glm::dvec3 value(0.0);
    for (size_t c = 0; c < output.components; ++c) value[static_cast<int>(c)] = component(of, output, c, p);
    return value;
  };
  std::map<std::string, std::vector<double>> samples;
  for (size_t p = 0; p < pixels; ++p) {
    if (!frame.hit(p) || !reference.hit(p)) continue;
    const bool same_primitive =
        !frame.mesh_id.empty() && frame.mesh_id[p] == reference.mesh_id[p] && frame.primitive_id[p] == reference.primitive_id[p];
    std::map<std::string, bool> differs;  // a pixel counts once among its field's mismatches
    for (const OutputInfo* output : measured) {
      if (output->source == OutputSource::surface && !same_primitive) continue;
      const glm::dvec3 mine = vector(frame, *output, p), theirs = vector(reference, *output, p);
      switch (output->error) {
        case OutputError::relative_p99:
          samples[output->error_field].push_back(std::abs(mine.x - theirs.x) / std::abs(theirs.x));
          break;
        case OutputError::over_depth_p99:
          samples[output->error_field].push_back(glm::distance(mine, theirs) / reference.depth[p]);
          break;
        case OutputError::mismatches:
          differs[output->error_field] = differs[output->error_field] || mine != theirs;
          break;
        case OutputError::absolute_max: {
          const glm::dvec3 d = glm::abs(mine - theirs);
          double& largest = errors.measures[output->error_field];
          largest = std::max({largest, d.x, d.y, d.z});
          break;
        }
        case OutputError::degrees_p99:
          samples[output->error_field].push_back(angle_between(mine, theirs) * 180.0 / std::numbers::pi);
          break;
        case OutputError::none:
          break;
      }
    }
    for (const auto& [field, different] : differs) errors.counts[field] += different ? 1 : 0;
  }
  for (auto& [field, values] : samples) errors.measures[field] = percentile(values, 0.99);
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
