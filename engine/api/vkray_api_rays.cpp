// The C API's given rays: nearest and first hits, occlusion and crossings, the caller's arrays read and
// written in place where the device can, bad rays refused or taken as misses.
#include "engine/api/vkray_api_common.hpp"

#include "engine/parallel.hpp"
#include "engine/render/ray_order.hpp"
#include "engine/surface_outputs.hpp"
#include "engine/unit_vector.hpp"

#include <algorithm>
#include <chrono>
#include <span>
#include <vector>

using namespace vkray;
using namespace vkray::api;

namespace {

// The rays a call traces, with their ranges in the engine's convention (along the unit direction).
// A bad ray (a zero or non-finite direction, an origin beyond max_coordinate, a range the engine
// refuses) fails the call where the flags ask for that; else, once the engine has refused one, the
// bad rays are found in one pass (refused_rays), left out of what is traced, and come back as misses.
// The rays are the caller's memory, read in place.
struct CallRays {
  std::span<const GivenRay> rays;
  std::vector<double> t_min, t_max;  // none where the caller gave none
  std::vector<double> length;        // each direction's length, where t is along the direction as given
  bool bad_rays_fail = false;
  bool filtered = false;             // some rays were bad: the good ones below are traced
  std::vector<uint8_t> refused;
  std::vector<size_t> good;          // their indices among the given rays
  std::vector<GivenRay> good_rays;
  std::vector<double> good_t_min, good_t_max;

  CallRays(const double* given, uint64_t count, const double* t_min_given, const double* t_max_given, uint32_t flags)
      : bad_rays_fail((flags & VKRAY_BAD_RAYS_FAIL) != 0) {
    if (const uint32_t unknown = flags & ~uint32_t{VKRAY_T_ALONG_DIRECTION | VKRAY_BAD_RAYS_FAIL}) {
      throw InputError("flags: unknown bits " + std::to_string(unknown) + " (vkray_ray_flags: VKRAY_T_ALONG_DIRECTION = 1, "
                       "VKRAY_BAD_RAYS_FAIL = 2)");
    }
    if (count > 0) require(given, "rays");
    static_assert(sizeof(GivenRay) == 6 * sizeof(double));
    rays = {reinterpret_cast<const GivenRay*>(given), static_cast<size_t>(count)};
    if (flags & VKRAY_T_ALONG_DIRECTION) {
      length.resize(rays.size());
      parallel_for_chunks(rays.size(), [&](size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) length[k] = glm::length(vec3_at(given, k, 6, 3));
      });
    }
    // t along the direction as given is t along the unit direction over the direction's length.
    const auto range = [&](const double* values, std::vector<double>& into) {
      if (!values) return;
      into.assign(values, values + rays.size());
      for (size_t k = 0; k < length.size(); ++k) into[k] *= length[k];
    };
    range(t_min_given, t_min);
    range(t_max_given, t_max);
  }

  void filter() {
    refused = refused_rays(rays, {t_min, t_max});
    filtered = true;
    for (size_t k = 0; k < rays.size(); ++k) {
      if (refused[k]) continue;
      good.push_back(k);
      good_rays.push_back(rays[k]);
      if (!t_min.empty()) good_t_min.push_back(t_min[k]);
      if (!t_max.empty()) good_t_max.push_back(t_max[k]);
    }
  }
  std::span<const GivenRay> traced() const { return filtered ? std::span<const GivenRay>(good_rays) : rays; }
  RayRanges traced_ranges() const { return filtered ? RayRanges{good_t_min, good_t_max} : RayRanges{t_min, t_max}; }
  size_t given_index(size_t traced_index) const { return filtered ? good[traced_index] : traced_index; }
};

// The runs of consecutive rays from one origin, where the rays hold a few large ones and start at
// their origins: a batch of sensor poses, each run of which the engine walks in packets as it walks a
// single pose (one call of them all would walk one by one, the rays not sharing one origin). None
// where they do not.
std::vector<std::pair<size_t, size_t>> pose_runs(std::span<const GivenRay> rays, const RayRanges& ranges) {
  constexpr size_t least_run = 4096, most_runs = 256;  // fewer rays walk as fast one by one
  if (!std::all_of(ranges.t_min.begin(), ranges.t_min.end(), [](double t) { return t == 0.0; })) return {};
  if (shared_origin(rays)) return {};  // one pose: found on every core, where the runs are found on one
  std::vector<std::pair<size_t, size_t>> runs;  // first, end
  for (size_t k = 0; k < rays.size(); ++k) {
    const bool same = k > 0 && std::equal(rays[k].begin(), rays[k].begin() + 3, rays[k - 1].begin());
    if (!same) {
      if (!runs.empty() && runs.back().second - runs.back().first < least_run) return {};
      if (runs.size() == most_runs) return {};
      runs.emplace_back(k, k);
    }
    runs.back().second = k + 1;
  }
  if (runs.size() < 2 || runs.back().second - runs.back().first < least_run) return {};
  return runs;
}

// One engine call's timings into a C API call's: the first replaces, the later ones add.
void add_timings(RenderTimings& call, const RenderTimings& engine, bool first) {
  if (first) {
    call = engine;
    return;
  }
  call.add(engine);
  call.given_walk = engine.given_walk;
}

// Traces the call's rays: all of them at once where whole(rays, ranges) takes them (returns true),
// else trace(first, rays, ranges) for each pose run of them (pose_runs), or once for all, each
// engine call's timings added to the call's; where the engine refuses a bad ray and the call takes
// bad rays as misses, again without the bad ones. `bad(given)` is called for each.
template <typename Whole, typename Trace, typename Bad>
void trace_call(vkray_renderer& r, CallRays& call, Whole&& whole, Trace&& trace, Bad&& bad) {
  const auto all_runs = [&] {
    const std::span<const GivenRay> rays = call.traced();
    const RayRanges ranges = call.traced_ranges();
    if (whole(rays, ranges)) {
      if (r.renderer) add_timings(r.last_call, r.renderer->timings(), true);
      return;
    }
    std::vector<std::pair<size_t, size_t>> runs = r.renderer ? pose_runs(rays, ranges) : std::vector<std::pair<size_t, size_t>>{};
    if (runs.empty()) runs.emplace_back(0, rays.size());
    for (const auto& [first, end] : runs) {
      const size_t n = end - first;
      const auto part = [&](std::span<const double> values) { return values.empty() ? values : values.subspan(first, n); };
      trace(first, rays.subspan(first, n), RayRanges{part(ranges.t_min), part(ranges.t_max)});
      if (r.renderer) add_timings(r.last_call, r.renderer->timings(), first == 0);
    }
  };
  try {
    all_runs();
  } catch (const InputError&) {
    if (call.bad_rays_fail || call.filtered) throw;
    call.filter();
    all_runs();
    for (size_t k = 0; k < call.rays.size(); ++k) {
      if (call.refused[k]) bad(k);
    }
  }
}

// The caller's arrays of a cast_rays call, written ray by ray from a hit in the engine's terms (t
// along the unit direction, the unit normal facing the ray, the object and primitive).
class RayOutputs {
 public:
  // `hits`: each ray's first hits (1: the nearest), hit k of ray n at entry n * hits + k.
  RayOutputs(const std::vector<const OutputInfo*>& asked, void* const* results, bool doubles, const CallRays& call,
             const Scene& scene, uint32_t hits)
      : asked_(asked), results_(results), doubles_(doubles), call_(call), scene_(scene), hits_(hits) {
    for (const OutputInfo* output : asked) {
      surface_ = surface_ || output->source == OutputSource::surface;
      needs_direction_ = needs_direction_ || output->source == OutputSource::surface || output->aov == Aov::position;
    }
  }

  void miss(size_t k) const {
    for (uint32_t layer = 0; layer < hits_; ++layer) hit(k, layer, INFINITY, glm::dvec3(0.0), {no_object, no_object}, no_object);
  }

  // The caller's arrays from ray `first` on, for Renderer::cast_rays_in_place: where the outputs
  // asked for are float32 t along the unit direction, normals and ids alone, and the traced rays are
  // the given ones (none was left out as bad).
  std::optional<HitArrays> arrays_from(size_t first) const {
    if (doubles_ || !call_.length.empty() || call_.filtered || hits_ > 1) return std::nullopt;
    HitArrays arrays;
    for (size_t n = 0; n < asked_.size(); ++n) {
      if (std::count(asked_.begin(), asked_.begin() + static_cast<std::ptrdiff_t>(n), asked_[n]) > 0) return std::nullopt;  // asked twice
      switch (asked_[n]->aov) {
        case Aov::depth: arrays.t = static_cast<float*>(results_[n]) + first; break;
        case Aov::normal: arrays.normal = static_cast<float*>(results_[n]) + 3 * first; break;
        case Aov::mesh_id: arrays.object = static_cast<uint32_t*>(results_[n]) + first; break;
        case Aov::primitive_id: arrays.primitive = static_cast<uint32_t*>(results_[n]) + first; break;
        default: return std::nullopt;
      }
    }
    return arrays;
  }

  // Hit `layer` of ray k; `instance`: the instance placing the mesh hit, or no_object.
  void hit(size_t k, uint32_t layer, double t, const glm::dvec3& normal, ObjectPrimitive source, uint32_t instance) const {
    const bool missed = source.object == no_object;
    const glm::dvec3 origin = vec3_at(call_.rays[k].data(), 0, 6);
    const glm::dvec3 direction =
        missed || !needs_direction_ ? glm::dvec3(0.0) : unit_vector(vec3_at(call_.rays[k].data(), 0, 6, 3));
    SurfaceAt surface;
    if (surface_ && !missed) surface = surface_at(scene_, source, origin, direction, t, instance);
    const size_t at = k * hits_ + layer;
    for (size_t n = 0; n < asked_.size(); ++n) {
      void* result = results_[n];
      switch (asked_[n]->aov) {
        case Aov::depth: put(result, at, 1, &t, doubles_, call_.length.empty() ? 1.0 : call_.length[k]); break;
        case Aov::normal: put(result, at, 3, &normal[0], doubles_); break;
        case Aov::mesh_id: static_cast<uint32_t*>(result)[at] = source.object; break;
        case Aov::primitive_id: static_cast<uint32_t*>(result)[at] = source.primitive; break;
        case Aov::instance_id: static_cast<uint32_t*>(result)[at] = instance; break;
        case Aov::position: {
          const glm::dvec3 p = missed ? glm::dvec3(0.0) : origin + t * direction;
          put(result, at, 3, &p[0], false);
          break;
        }
        case Aov::barycentric: put(result, at, 2, &surface.barycentric[0], false); break;
        case Aov::shading_normal: put(result, at, 3, &surface.shading_normal[0], false); break;
        case Aov::texcoord: put(result, at, 2, &surface.texcoord[0], false); break;
        case Aov::front_facing: static_cast<uint32_t*>(result)[at] = surface.front ? 1u : 0u; break;
        default: break;  // output_named let no other through
      }
    }
  }

 private:
  // components values of entry k, over `scale`, as float32 or float64.
  static void put(void* result, size_t k, uint32_t components, const double* values, bool doubles, double scale = 1.0) {
    for (uint32_t c = 0; c < components; ++c) {
      if (doubles) static_cast<double*>(result)[k * components + c] = values[c] / scale;
      else static_cast<float*>(result)[k * components + c] = static_cast<float>(values[c] / scale);
    }
  }

  const std::vector<const OutputInfo*>& asked_;
  void* const* results_;
  bool doubles_;
  const CallRays& call_;
  const Scene& scene_;
  bool surface_ = false;
  bool needs_direction_ = false;  // the hit point or the surface outputs are asked for
  uint32_t hits_;
};

// A call that answers each ray with one value (occluded, count_intersections), as trace_call runs
// it: `on_device` answers a run of rays on the renderer's device, `on_reference` one ray of a
// reference renderer; a bad ray gets 0.
template <typename T, typename OnDevice, typename OnReference>
vkray_status answer_each_ray(vkray_renderer* renderer, const double* rays, uint64_t count, const double* t_min,
                             const double* t_max, uint32_t flags, uint32_t mask, T* answers, const char* name,
                             OnDevice&& on_device, OnReference&& on_reference) {
  return guarded([&] {
    require(renderer, "renderer");
    if (count > 0) require(answers, name);
    CallRays call(rays, count, t_min, t_max, flags);
    const std::lock_guard one_call_at_a_time(renderer->busy);
    use_ray_mask(*renderer, mask);
    renderer->called = true;
    const auto never_whole = [](std::span<const GivenRay>, const RayRanges&) { return false; };
    trace_call(*renderer, call, never_whole, [&](size_t first, std::span<const GivenRay> run, const RayRanges& run_ranges) {
      std::vector<T> answered;
      if (renderer->renderer) {
        answered = on_device(*renderer->renderer, run, run_ranges);
      } else {
        check_given_rays(run);  // InputError names a bad ray, as the device's call does
        check_ray_ranges(run, run_ranges);
        answered.resize(run.size());
        parallel_for_chunks(run.size(), [&](size_t begin, size_t end) {
          for (size_t k = begin; k < end; ++k) {
            answered[k] = on_reference(*renderer->reference, run[k], run_ranges.start(k), run_ranges.end(k));
          }
        });
      }
      for (size_t k = 0; k < answered.size(); ++k) answers[call.given_index(first + k)] = answered[k];
    }, [&](size_t given) { answers[given] = T{0}; });
  });
}

}  // namespace

extern "C" {

vkray_status vkray_cast_rays(vkray_renderer* renderer, const double* rays, uint64_t count, const double* t_min, const double* t_max,
                             uint32_t flags, uint32_t mask, uint32_t hits, uint32_t output_count, const char* const* outputs,
                             void* const* results) {
  return guarded([&] {
    require(renderer, "renderer");
    if (hits < 1 || hits > VKRAY_HITS_MAX) {
      throw InputError("hits: " + std::to_string(hits) + " is not between 1 and " + std::to_string(VKRAY_HITS_MAX));
    }
    if (output_count > 0) {
      require(outputs, "outputs");
      require(results, "results");
    }
    std::vector<const OutputInfo*> asked;
    for (uint32_t k = 0; k < output_count; ++k) {
      asked.push_back(&output_named(outputs[k], true));
      if (count > 0) require(results[k], outputs[k]);
    }
    CallRays call(rays, count, t_min, t_max, flags);
    const RayOutputs written(asked, results, renderer->doubles, call, renderer->scene, hits);
    const std::lock_guard one_call_at_a_time(renderer->busy);
    use_ray_mask(*renderer, mask);
    renderer->called = true;
    // Where it can, the device reads the rays and writes the hits in the caller's own arrays;
    // elsewhere each traced hit goes into them from the host.
    const auto in_place = [&](std::span<const GivenRay> traced, const RayRanges& ranges) {
      const std::optional<HitArrays> arrays = written.arrays_from(0);
      return renderer->renderer && arrays && ranges.t_min.empty() && ranges.t_max.empty() &&
             renderer->renderer->cast_rays_in_place(traced, *arrays);
    };
    trace_call(*renderer, call, in_place, [&](size_t first, std::span<const GivenRay> run, const RayRanges& run_ranges) {
      if (renderer->renderer) {
        const RayHits traced = renderer->renderer->cast_rays(run, run_ranges, hits);
        const bool doubles = !traced.t64.empty();
        parallel_for_chunks(traced.count, [&](size_t begin, size_t end) {
          for (size_t k = begin; k < end; ++k) {  // hit k % hits of ray k / hits
            const auto normal = [&](size_t c) {
              return doubles ? traced.normal64[c * traced.count + k] : double{traced.normal[c * traced.count + k]};
            };
            written.hit(call.given_index(first + k / hits), static_cast<uint32_t>(k % hits), doubles ? traced.t64[k] : traced.t[k],
                        {normal(0), normal(1), normal(2)}, {traced.object[k], traced.primitive[k]},
                        traced.instance.empty() ? no_object : traced.instance[k]);
          }
        });
        return;
      }
      const auto start = std::chrono::steady_clock::now();
      const ReferenceScene& reference = *renderer->reference;
      check_given_rays(run);
      check_ray_ranges(run, run_ranges);
      parallel_for_chunks(run.size(), [&](size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) {
          // The nearest hit by its own rules (coincident surfaces, ties) where it is the one asked for.
          const std::vector<ReferenceHit> listed =
              hits == 1 ? std::vector<ReferenceHit>{trace_reference_ray(reference, run[k], run_ranges.start(k), run_ranges.end(k))}
                        : first_reference_hits(reference, run[k], run_ranges.start(k), run_ranges.end(k), hits);
          for (uint32_t layer = 0; layer < hits; ++layer) {
            written.hit(call.given_index(first + k), layer, listed[layer].t, listed[layer].normal, reference.source(listed[layer]),
                        listed[layer].instance);
          }
        }
      });
      renderer->reference_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }, [&](size_t given) { written.miss(given); });
  });
}

vkray_status vkray_occluded(vkray_renderer* renderer, const double* rays, uint64_t count, const double* t_min, const double* t_max,
                            uint32_t flags, uint32_t mask, uint8_t* occluded) {
  return answer_each_ray(
      renderer, rays, count, t_min, t_max, flags, mask, occluded, "occluded",
      [](Renderer& device, std::span<const GivenRay> run, const RayRanges& ranges) { return device.occluded(run, ranges); },
      [](const ReferenceScene& reference, const GivenRay& ray, double start, double end) {
        // The nearest hit decides: exactly whether any hit lies in the range.
        return uint8_t{trace_reference_ray(reference, ray, start, end).kind != PrimitiveKind::none};
      });
}

vkray_status vkray_count_intersections(vkray_renderer* renderer, const double* rays, uint64_t count, const double* t_min,
                                       const double* t_max, uint32_t flags, uint32_t mask, uint32_t* crossings) {
  return answer_each_ray(
      renderer, rays, count, t_min, t_max, flags, mask, crossings, "crossings",
      [](Renderer& device, std::span<const GivenRay> run, const RayRanges& ranges) { return device.count_intersections(run, ranges); },
      count_reference_crossings);
}

}  // extern "C"
