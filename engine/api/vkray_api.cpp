// vkray.h over the engine: arguments checked and converted, the engine called, results written into
// the caller's arrays, every exception turned into a status and a message. A front end as thin as the
// CLI: scenes are checked, rendered and traced by the engine.
#include "engine/api/vkray.h"

#include "engine/device/gpu_device.hpp"
#include "engine/parallel.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/ray_order.hpp"
#include "engine/render/renderer.hpp"
#include "engine/render/search.hpp"
#include "engine/scene/camera_description.hpp"
#include "engine/scene/framing.hpp"
#include "engine/scene/scene_loader.hpp"
#include "engine/scene/scene_or_model.hpp"
#include "engine/surface_outputs.hpp"
#include "engine/typed_names.hpp"
#include "engine/unit_vector.hpp"

#include <glm/gtc/type_ptr.hpp>
#include <glm/matrix.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <vector>

#ifndef VKRAY_VERSION
#error "VKRAY_VERSION comes from CMake"
#endif

using namespace vkray;

struct vkray_scene {
  Scene scene;
  bool camera_given = false;
  bool finished = false;
};

struct vkray_renderer {
  Scene scene;  // the surface outputs of given rays read its meshes
  std::unique_ptr<GpuDevice> device;
  std::unique_ptr<Renderer> renderer;
  std::unique_ptr<ReferenceScene> reference;  // the reference's, where renderer is none: for rays of ray_mask
  Mask ray_mask = every_mask_bit;
  bool doubles = false;
  std::string device_name;
  RenderTimings setup;  // the constructor's
  RenderTimings last_call;  // the last call's: the engine's, summed over the engine calls it made
  double reference_ms = 0.0;  // the reference's last call
  bool called = false;        // a render, cast or occlusion call was made: timings has a last call
  // The engine's Renderer serves one call at a time; callers' threads wait their turn here.
  std::mutex busy;
};

namespace {

thread_local std::string last_error;

// Runs `work`, turning what it throws into a status and the thread's message.
template <typename Work>
vkray_status guarded(Work&& work) {
  try {
    work();
    return VKRAY_OK;
  } catch (const InputError& error) {
    last_error = error.what();
    return VKRAY_INPUT_ERROR;
  } catch (const GpuError& error) {
    last_error = error.what();
    return VKRAY_DEVICE_ERROR;
  } catch (const std::bad_alloc&) {
    last_error = "out of memory";
    return VKRAY_OUT_OF_MEMORY;
  } catch (const std::exception& error) {
    last_error = error.what();
    return VKRAY_INTERNAL_ERROR;
  }
}

void require(const void* pointer, const char* what) {
  if (!pointer) throw InputError(std::string(what) + ": NULL");
}

// A scene is read-only once finished or loaded (vkray.h): what `call` would add or change is refused,
// so that what a renderer takes has passed check_scene.
void require_unfinished(const vkray_scene& scene, const char* call) {
  if (scene.finished) {
    throw InputError(std::string(call) + ": the scene is finished (vkray_scene_finish, or loaded): it is read-only; "
                     "build another with vkray_scene_new");
  }
}

// The strings a call returns (vkray_renderer_timings, vkray_scene_describe): each thread's own, valid
// until that thread's next call of the same function, so that threads sharing a renderer never read
// one another's (vkray.h).
thread_local std::string returned_timings, returned_description;

std::optional<uint32_t> size_or_default(uint32_t given, const char* what) {
  if (given == 0) return std::nullopt;
  if (given > max_image_side) {
    throw InputError(std::string(what) + ": must be in 1 .. " + std::to_string(max_image_side) + ", got " + std::to_string(given));
  }
  return given;
}

glm::dvec3 vec3_at(const double* values, size_t row, size_t columns, size_t first = 0) {
  const double* at = values + row * columns + first;
  return {at[0], at[1], at[2]};
}

// An output asked for by name, known (render's aovs, or given rays' outputs: "t" for the depth).
const OutputInfo& output_named(const char* name, bool rays) {
  const char* what = rays ? "outputs" : "aovs";
  require(name, what);
  const std::string_view given(name);
  const auto aov = aov_from_name(rays && given == "t" ? "depth" : given);
  if (!aov) throw InputError(std::string(what) + ": " + unknown_output_message(std::string(given)));
  const OutputInfo& output = output_info(*aov);
  if (rays && (output.source == OutputSource::camera && output.aov != Aov::position)) {
    throw InputError(std::string("outputs: '") + name + "' belongs to a camera's image; given rays have t, normal, primitive-id, mesh-id, "
                     "instance-id, position, barycentric, front-facing, shading-normal and texcoord");
  }
  if (rays && (output.aov == Aov::uv || output.aov == Aov::depth) && given != "t") {
    throw InputError(std::string("outputs: '") + name + "' belongs to a camera's image; a given ray's distance is 't'");
  }
  return output;
}

// Writes `planes` (components planes of `count` values, the engine's layout) into `result`,
// count x components, converted to T.
template <typename T, typename Planes>
void interleave(const Planes& planes, size_t count, uint32_t components, void* result) {
  T* out = static_cast<T*>(result);
  for (size_t k = 0; k < count; ++k) {
    for (uint32_t c = 0; c < components; ++c) out[k * components + c] = static_cast<T>(planes[c * count + k]);
  }
}

Camera camera_over(const char* camera_json, const Camera& base) {
  return camera_json ? parse_camera_override(camera_json, "camera", base) : base;
}

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

nlohmann::json timings_json(const RenderTimings& t, bool constructor) {
  nlohmann::json json;
  if (constructor) {
    json["upload_ms"] = t.upload_ms;
    json["bvh_build_ms"] = t.bvh_build_ms;
    json["pipeline_ms"] = t.pipeline_ms;  // after the upload (one made beside it is in upload_ms)
    return json;
  }
  json["pipeline_ms"] = t.pipeline_ms;
  if (t.has_gpu_times) json["dispatch_gpu_ms"] = t.dispatch_gpu_ms;
  json["readback_ms"] = t.readback_ms;
  json["rays_ms"] = t.rays_ms;
  if (t.given_walk != GivenRayWalk::none) {
    json["rays_walk"] = given_ray_walk_name(t.given_walk);
    json["rays_in_place"] = t.rays_in_place;
    if (t.order_gpu_ms > 0.0) json["order_gpu_ms"] = t.order_gpu_ms;
  }
  json["dispatches"] = t.tiles;
  json["cpu_finished_rays"] = t.unfinished_rays;
  if (t.scene_update_ms > 0.0) {  // set_vertices
    json["scene_update_ms"] = t.scene_update_ms;
    json["tree_refitted"] = t.tree_refitted;
    json["refit_mesh_alone"] = t.refit_mesh_alone;
    json["bvh_build_ms"] = t.bvh_build_ms;
  }
  return json;
}

// An object's mask from the C API's 32-bit argument: 8 bits (see Mask).
// A 4 x 4 affine matrix given row-major (last row 0 0 0 1) of finite numbers, as glm holds it.
glm::dmat4 affine_matrix(const double* rows, const std::string& path) {
  const std::string affine = path + ": expected a 4 x 4 affine matrix of finite numbers (last row 0, 0, 0, 1)";
  if (!std::all_of(rows, rows + 16, [](double v) { return std::isfinite(v); })) throw InputError(affine);
  if (rows[12] != 0.0 || rows[13] != 0.0 || rows[14] != 0.0 || rows[15] != 1.0) throw InputError(affine);
  return glm::transpose(glm::make_mat4(rows));
}

Mask object_mask_argument(uint32_t mask) {
  if (mask > every_mask_bit) throw InputError("mask: " + std::to_string(mask) + " is no mask of 8 bits (0..255)");
  return static_cast<Mask>(mask);
}

// Makes `mask` the renderer's rays' for the call under way (the caller holds `busy`): the engine's,
// or the reference's tree made again for it.
void use_ray_mask(vkray_renderer& renderer, uint32_t mask) {
  if (mask == 0 || mask > every_mask_bit) {
    throw InputError("mask: " + std::to_string(mask) + " is no ray mask (1..255; 0 would hit nothing)");
  }
  const auto ray_mask = static_cast<Mask>(mask);
  if (renderer.renderer) {
    renderer.renderer->set_ray_mask(ray_mask);
  } else if (ray_mask != renderer.ray_mask) {
    renderer.reference = std::make_unique<ReferenceScene>(renderer.scene, ray_mask);
  }
  renderer.ray_mask = ray_mask;
}

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

uint32_t vkray_api_version(void) { return VKRAY_API_VERSION; }

const char* vkray_version(void) { return VKRAY_VERSION; }

const char* vkray_last_error(void) { return last_error.c_str(); }

int vkray_output(uint32_t index, vkray_output_info* info) {
  const auto all = outputs();
  if (index >= all.size() || !info) return 0;
  const OutputInfo& output = all[index];
  info->name = output.name;
  info->description = output.description;
  info->components = output.components;
  info->is_integer = output.integer ? 1 : 0;
  for (size_t c = 0; c < 3; ++c) info->channels[c] = c < output.components ? output.channels[c] : nullptr;
  return 1;
}

const char* vkray_traversal(uint32_t index) {
  const auto all = searches();
  return index < all.size() ? all[index].name : nullptr;
}

vkray_status vkray_scene_load(const char* path, uint32_t width, uint32_t height, const char* view, const double* view_direction,
                              vkray_scene** scene) {
  return guarded([&] {
    require(path, "path");
    require(scene, "scene");
    *scene = nullptr;
    std::optional<FramingView> side;
    if (view) {
      side = framing_view_from_name(view);
      if (!side) throw InputError("view: unknown side '" + std::string(view) + "' (" + framing_view_names + ")");
    } else if (view_direction) {
      const glm::dvec3 direction(view_direction[0], view_direction[1], view_direction[2]);
      if (direction == glm::dvec3(0.0) || !std::isfinite(glm::length(direction))) {
        throw InputError("view: the direction from the centre to the eye must be finite and not 0");
      }
      side = FramingView{direction, {0.0, 1.0, 0.0}};
    }
    auto made = std::make_unique<vkray_scene>();
    made->scene = load_scene_or_model(path, size_or_default(width, "width"), size_or_default(height, "height"));
    if (side) made->scene.camera = frame_scene(made->scene, made->scene.width, made->scene.height, *side);
    made->camera_given = made->finished = true;
    *scene = made.release();
  });
}

vkray_status vkray_scene_new(uint32_t width, uint32_t height, vkray_scene** scene) {
  return guarded([&] {
    require(scene, "scene");
    *scene = nullptr;
    auto made = std::make_unique<vkray_scene>();
    made->scene.width = width;
    made->scene.height = height;
    *scene = made.release();
  });
}

vkray_status vkray_scene_add_mesh(vkray_scene* scene, const double* vertices, uint64_t vertex_count, const void* triangles,
                                  int triangles_unsigned, uint64_t triangle_count, const double* transform) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_mesh");
    const std::string path = "meshes[" + std::to_string(scene->scene.meshes.size()) + "]";
    if (vertex_count > 0) require(vertices, (path + ".vertices").c_str());
    if (triangle_count > 0) require(triangles, (path + ".triangles").c_str());
    Mesh mesh;
    mesh.source = path;
    mesh.positions.reserve(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) {
      mesh.positions.push_back(vec3_at(vertices, v, 3));
      check_coordinates(mesh.positions.back(), path + ".vertices[" + std::to_string(v) + "]");
    }
    mesh.triangles.reserve(triangle_count);
    for (size_t t = 0; t < triangle_count; ++t) {
      std::array<uint32_t, 3> triangle{};
      for (size_t c = 0; c < 3; ++c) {
        // Signed and unsigned indices each in their own width: an unsigned index past 2^63 must not wrap.
        const bool in_range = triangles_unsigned ? static_cast<const uint64_t*>(triangles)[3 * t + c] < vertex_count
                                                 : static_cast<const int64_t*>(triangles)[3 * t + c] >= 0 &&
                                                       static_cast<uint64_t>(static_cast<const int64_t*>(triangles)[3 * t + c]) < vertex_count;
        if (!in_range) {
          const std::string index = triangles_unsigned ? std::to_string(static_cast<const uint64_t*>(triangles)[3 * t + c])
                                                       : std::to_string(static_cast<const int64_t*>(triangles)[3 * t + c]);
          throw InputError(path + ".triangles[" + std::to_string(t) + "][" + std::to_string(c) + "]: vertex index " + index +
                           " is out of range (the mesh has " + std::to_string(vertex_count) + " vertices)");
        }
        triangle[c] = static_cast<uint32_t>(triangles_unsigned ? static_cast<const uint64_t*>(triangles)[3 * t + c]
                                                               : static_cast<uint64_t>(static_cast<const int64_t*>(triangles)[3 * t + c]));
      }
      mesh.triangles.push_back(triangle);
    }
    if (transform) {
      const glm::dmat4 affine = affine_matrix(transform, path + ".transform");
      for (glm::dvec3& p : mesh.positions) p = glm::dvec3(affine * glm::dvec4(p, 1.0));
    }
    scene->scene.meshes.push_back(std::move(mesh));
  });
}

vkray_status vkray_scene_add_instance(vkray_scene* scene, uint32_t mesh, const double* transform, uint32_t mask) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_instance");
    const std::string path = "instances[" + std::to_string(scene->scene.instances.size()) + "]";
    if (mesh >= scene->scene.meshes.size()) {
      throw InputError(path + ".mesh: " + std::to_string(mesh) + " is not a mesh_id of the " +
                       std::to_string(scene->scene.meshes.size()) + " meshes added so far");
    }
    Instance instance;
    instance.mesh = mesh;
    if (transform) place_by(instance, affine_matrix(transform, path + ".transform"));
    instance.mask = object_mask_argument(mask);
    scene->scene.meshes[mesh].instanced = true;  // drawn only where instances place it
    scene->scene.instances.push_back(instance);
  });
}

vkray_status vkray_scene_add_spheres(vkray_scene* scene, const double* spheres, uint64_t count) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_spheres");
    if (count > 0) require(spheres, "spheres");
    for (size_t k = 0; k < count; ++k) scene->scene.spheres.push_back({vec3_at(spheres, k, 4), spheres[4 * k + 3]});
  });
}

vkray_status vkray_scene_add_planes(vkray_scene* scene, const double* planes, uint64_t count) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_add_planes");
    if (count > 0) require(planes, "planes");
    for (size_t k = 0; k < count; ++k) scene->scene.planes.push_back({vec3_at(planes, k, 6), vec3_at(planes, k, 6, 3)});
  });
}

vkray_status vkray_scene_set_mask(vkray_scene* scene, uint32_t object, uint32_t mask) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_set_mask");
    set_object_mask(scene->scene, object, object_mask_argument(mask));
  });
}

vkray_status vkray_scene_set_camera(vkray_scene* scene, const char* camera_json) {
  return guarded([&] {
    require(scene, "scene");
    require_unfinished(*scene, "vkray_scene_set_camera");
    require(camera_json, "camera");
    scene->scene.camera = parse_camera_override(camera_json, "camera", Camera{});
    scene->camera_given = true;
  });
}

vkray_status vkray_scene_finish(vkray_scene* scene) {
  return guarded([&] {
    require(scene, "scene");
    if (scene->finished) return;
    check_scene(scene->scene);
    if (!scene->camera_given) scene->scene.camera = frame_scene(scene->scene, scene->scene.width, scene->scene.height);
    scene->finished = true;
  });
}

const char* vkray_scene_describe(vkray_scene* scene) {
  if (!scene) return "";
  const Scene& s = scene->scene;
  nlohmann::ordered_json json;
  json["width"] = s.width;
  json["height"] = s.height;
  json["meshes"] = s.meshes.size();
  json["triangles"] = s.triangle_count();
  json["spheres"] = s.spheres.size();
  json["planes"] = s.planes.size();
  json["camera"] = camera_description(s.camera, s.width, s.height)["camera"];
  json["object_names"] = object_names(s);
  std::vector<uint32_t> masks;
  for (uint32_t object = 0; object < s.object_count(); ++object) masks.push_back(object_mask(s, object));
  json["masks"] = masks;
  returned_description = json.dump();
  return returned_description.c_str();
}

void vkray_scene_free(vkray_scene* scene) { delete scene; }

vkray_status vkray_renderer_new(const vkray_scene* scene, const char* device, const char* precision, const char* traversal,
                                vkray_renderer** renderer) {
  return guarded([&] {
    require(scene, "scene");
    require(renderer, "renderer");
    *renderer = nullptr;
    if (!scene->finished) throw InputError("scene: not finished (vkray_scene_finish)");
    RendererOptions options;
    const std::string chosen_precision = precision ? precision : "float";
    if (chosen_precision == "double") {
      options.shader.precision = Precision::float64;
    } else if (chosen_precision != "float") {
      throw InputError("precision: 'float' or 'double', got '" + chosen_precision + "'");
    }
    const std::string chosen_traversal = traversal ? traversal : "auto";
    const std::optional<PrimitiveSearch> search = traversal_from_name(chosen_traversal);
    if (!search) throw InputError("traversal: one of " + traversal_names() + ", got '" + chosen_traversal + "'");
    options.scene.search = *search;
    options.first_aovs = AovSet{Aov::depth, Aov::normal};
    auto made = std::make_unique<vkray_renderer>();
    made->scene = scene->scene;
    made->doubles = options.shader.precision == Precision::float64;
    made->device = std::make_unique<GpuDevice>(device ? device : "");
    made->device_name = made->device->info().name;
    made->renderer = std::make_unique<Renderer>(*made->device, made->scene, options);
    made->renderer->prepare_pipelines(made->scene.camera, made->scene.width, made->scene.height);
    made->setup = made->renderer->timings();
    *renderer = made.release();
  });
}

vkray_status vkray_reference_new(const vkray_scene* scene, vkray_renderer** renderer) {
  return guarded([&] {
    require(scene, "scene");
    require(renderer, "renderer");
    *renderer = nullptr;
    if (!scene->finished) throw InputError("scene: not finished (vkray_scene_finish)");
    auto made = std::make_unique<vkray_renderer>();
    made->scene = scene->scene;
    made->doubles = true;
    made->device_name = "CPU reference (double precision)";
    made->reference = std::make_unique<ReferenceScene>(made->scene);
    *renderer = made.release();
  });
}

int vkray_renderer_doubles(const vkray_renderer* renderer) { return renderer && renderer->doubles ? 1 : 0; }

const char* vkray_renderer_device_name(const vkray_renderer* renderer) { return renderer ? renderer->device_name.c_str() : ""; }

vkray_status vkray_renderer_set_vertices(vkray_renderer* renderer, uint32_t mesh, const double* positions, uint64_t count) {
  return guarded([&] {
    require(renderer, "renderer");
    if (count > 0) require(positions, "positions");
    static_assert(sizeof(glm::dvec3) == 3 * sizeof(double));
    const std::span<const glm::dvec3> moved(reinterpret_cast<const glm::dvec3*>(positions), static_cast<size_t>(count));
    const std::lock_guard one_call_at_a_time(renderer->busy);
    move_vertices(renderer->scene, mesh, moved);  // the surface outputs of given rays read it
    if (renderer->renderer) {
      renderer->renderer->set_vertices(mesh, moved);
      renderer->last_call = renderer->renderer->timings();
    } else {
      const auto start = std::chrono::steady_clock::now();
      renderer->reference = std::make_unique<ReferenceScene>(renderer->scene, renderer->ray_mask);
      renderer->reference_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
    renderer->called = true;
  });
}

vkray_status vkray_renderer_set_transforms(vkray_renderer* renderer, const uint32_t* instances, const double* transforms,
                                           uint64_t count) {
  return guarded([&] {
    require(renderer, "renderer");
    if (count > 0) require(instances, "instances"), require(transforms, "transforms");
    std::vector<glm::dmat4> affine(count);
    for (size_t k = 0; k < count; ++k) affine[k] = affine_matrix(transforms + 16 * k, "transforms[" + std::to_string(k) + "]");
    const std::span<const uint32_t> moved(instances, static_cast<size_t>(count));
    const std::lock_guard one_call_at_a_time(renderer->busy);
    if (renderer->renderer) {
      renderer->renderer->set_transforms(moved, affine);
      renderer->scene.instances = renderer->renderer->scene().instances;  // the surface outputs of given rays read it
      renderer->last_call = renderer->renderer->timings();
    } else {
      const auto start = std::chrono::steady_clock::now();
      set_instance_transforms(renderer->scene, moved, affine);
      renderer->reference = std::make_unique<ReferenceScene>(renderer->scene, renderer->ray_mask);
      renderer->reference_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
    renderer->called = true;
  });
}

const char* vkray_renderer_timings(vkray_renderer* renderer) {
  if (!renderer) return "{}";
  const std::lock_guard one_call_at_a_time(renderer->busy);
  nlohmann::json json = nlohmann::json::object();
  if (renderer->renderer) {
    if (renderer->called) json = timings_json(renderer->last_call, false);
    json["setup"] = timings_json(renderer->setup, true);
  } else if (renderer->called) {
    json["reference_ms"] = renderer->reference_ms;
  }
  returned_timings = json.dump();
  return returned_timings.c_str();
}

void vkray_renderer_free(vkray_renderer* renderer) { delete renderer; }

vkray_status vkray_render(vkray_renderer* renderer, const char* camera_json, uint32_t width, uint32_t height, uint32_t mask,
                          uint32_t aov_count, const char* const* aov_names, void* const* results) {
  return guarded([&] {
    require(renderer, "renderer");
    if (aov_count == 0) throw InputError("aovs: name at least one output (" + output_names() + ")");
    require(aov_names, "aovs");
    require(results, "results");
    AovSet aovs;
    std::vector<const OutputInfo*> asked;
    for (uint32_t k = 0; k < aov_count; ++k) {
      asked.push_back(&output_named(aov_names[k], false));
      aovs.add(asked.back()->aov);
      require(results[k], aov_names[k]);
    }
    const Scene& scene = renderer->scene;
    const Camera camera = camera_over(camera_json, scene.camera);
    const uint32_t w = size_or_default(width, "width").value_or(scene.width);
    const uint32_t h = size_or_default(height, "height").value_or(scene.height);
    check_image_size(w, h);
    check_camera_reach(camera, w, h, "camera");
    Frame frame;
    {
      const std::lock_guard one_call_at_a_time(renderer->busy);
      use_ray_mask(*renderer, mask);
      renderer->called = true;
      if (renderer->renderer) {
        frame = renderer->renderer->render(camera, w, h, aovs);
        renderer->last_call = renderer->renderer->timings();
      } else {
        const auto start = std::chrono::steady_clock::now();
        const std::vector<ReferenceHit> hits = render_reference_hits(*renderer->reference, camera, w, h);
        // Depth and normal in double, the reference's own; the other outputs as `vkray render
        // --reference` writes them.
        frame = reference_frame(*renderer->reference, scene, hits, camera, w, h, aovs, true);
        renderer->reference_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      }
    }
    const size_t pixels = frame.pixel_count();
    for (uint32_t k = 0; k < aov_count; ++k) {
      const OutputInfo& output = *asked[k];
      if (output.aov == Aov::depth && !frame.depth64.empty()) {
        interleave<double>(frame.depth64, pixels, 1, results[k]);
      } else if (output.aov == Aov::normal && !frame.normal64.empty()) {
        interleave<double>(frame.normal64, pixels, 3, results[k]);
      } else if (output.integers) {
        interleave<uint32_t>(frame.*output.integers, pixels, output.components, results[k]);
      } else {
        interleave<float>(frame.*output.floats, pixels, output.components, results[k]);
      }
    }
  });
}

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
