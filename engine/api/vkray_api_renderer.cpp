// The C API's renderers: the device's and the fp64 reference's, their scene's changes and timings, and
// their renders.
#include "engine/api/vkray_api_common.hpp"

#include "engine/render/search.hpp"

#include <chrono>

using namespace vkray;
using namespace vkray::api;

namespace {

// vkray_renderer_timings' text: each thread's own, valid until its next call, so that threads sharing
// a renderer never read one another's (vkray.h).
thread_local std::string returned_timings;

}  // namespace

extern "C" {

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
    made->setup = made->renderer->timings();
    *renderer = made.release();
  });
}

vkray_status vkray_renderer_prepare(vkray_renderer* renderer) {
  return guarded([&] {
    require(renderer, "renderer");
    if (!renderer->renderer) return;  // the reference has no pipelines
    renderer->renderer->prepare_pipelines(renderer->scene.camera, renderer->scene.width, renderer->scene.height);
    renderer->setup.pipeline_ms += renderer->renderer->timings().pipeline_ms;
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

}  // extern "C"
