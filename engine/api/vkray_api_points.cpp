// The C API's point queries: the nearest point, the winding number and what follows from them, each
// output of engine/point_outputs.hpp's table by name, answered by the device or the reference.
#include "engine/api/vkray_api_common.hpp"

#include "engine/point_outputs.hpp"

#include <chrono>
#include <optional>
#include <span>
#include <vector>

using namespace vkray;
using namespace vkray::api;

extern "C" {

int vkray_point_output(uint32_t index, vkray_output_info* info) {
  const auto all = point_outputs();
  if (index >= all.size() || !info) return 0;
  const PointOutputInfo& output = all[index];
  info->name = output.name;
  info->description = output.description;
  info->components = output.components;
  info->is_integer = output.integer ? 1 : 0;
  for (size_t c = 0; c < 3; ++c) info->channels[c] = nullptr;  // (an image's EXR channels: points have none)
  return 1;
}

vkray_status vkray_query_points(vkray_renderer* renderer, const double* points, uint64_t count, const double* max_distance,
                                uint32_t mask, uint32_t output_count, const char* const* outputs, void* const* results) {
  return guarded([&] {
    require(renderer, "renderer");
    if (count > 0) require(points, "points");
    if (output_count > 0) {
      require(outputs, "outputs");
      require(results, "results");
    }
    std::vector<const PointOutputInfo*> asked;
    bool nearest = false, winding = false;
    for (uint32_t k = 0; k < output_count; ++k) {
      require(outputs[k], ("outputs[" + std::to_string(k) + "]").c_str());
      const PointOutputInfo* info = find_point_output(outputs[k]);
      if (!info) throw InputError("unknown point output '" + std::string(outputs[k]) + "' (" + point_output_names() + ")");
      if (count > 0) require(results[k], outputs[k]);
      asked.push_back(info);
      nearest |= info->nearest;
      winding |= info->winding;
    }
    static_assert(sizeof(glm::dvec3) == 3 * sizeof(double));
    const std::span<const glm::dvec3> at(reinterpret_cast<const glm::dvec3*>(points), static_cast<size_t>(count));
    const std::span<const double> most = max_distance ? std::span<const double>(max_distance, static_cast<size_t>(count))
                                                      : std::span<const double>();
    const std::lock_guard one_call_at_a_time(renderer->busy);
    use_ray_mask(*renderer, mask);
    renderer->called = true;
    // Checked whichever query runs: a bad point fails the call before either.
    check_query_points(at, most);
    std::optional<PointHits> nearest_hits, winding_hits;
    const auto query = [&](HitQuery kind, bool first) {
      if (!renderer->renderer) return reference_point_hits(*renderer->reference, at, most, kind);
      PointHits hits = kind == HitQuery::nearest ? renderer->renderer->closest_points(at, most) : renderer->renderer->winding_numbers(at);
      first ? void(renderer->last_call = renderer->renderer->timings()) : renderer->last_call.add(renderer->renderer->timings());
      return hits;
    };
    const auto start = std::chrono::steady_clock::now();
    if (nearest) nearest_hits = query(HitQuery::nearest, true);
    if (winding) winding_hits = query(HitQuery::winding, !nearest);
    if (!renderer->renderer) renderer->reference_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const PointAnswers answers{at, nearest_hits ? &*nearest_hits : nullptr, winding_hits ? &*winding_hits : nullptr};
    for (size_t k = 0; k < asked.size(); ++k) write_point_output(*asked[k], renderer->scene, answers, renderer->doubles, results[k]);
  });
}

}  // extern "C"
