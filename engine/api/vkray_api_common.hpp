// What the C API's files share (engine/api/vkray_api_*.cpp): vkray.h's objects as the engine holds
// them, and the checks and conversions every call makes. Every exception a call raises becomes a
// status and the thread's message (guarded); nothing here is exported.
#pragma once

#include "engine/api/vkray.h"
#include "engine/device/gpu_device.hpp"
#include "engine/frame.hpp"
#include "engine/reference/reference.hpp"
#include "engine/render/renderer.hpp"
#include "engine/scene/scene.hpp"

#include <glm/mat4x4.hpp>
#include <nlohmann/json.hpp>

#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>

// vkray.h's objects, as the engine holds them (outside any namespace: vkray.h declares them so).
struct vkray_scene {
  vkray::Scene scene;
  bool camera_given = false;
  bool finished = false;
};

struct vkray_renderer {
  vkray::Scene scene;  // the surface outputs of given rays read its meshes
  std::unique_ptr<vkray::GpuDevice> device;
  std::unique_ptr<vkray::Renderer> renderer;
  std::unique_ptr<vkray::ReferenceScene> reference;  // the reference's, where renderer is none: for rays of ray_mask
  vkray::Mask ray_mask = vkray::every_mask_bit;
  bool doubles = false;
  std::string device_name;
  vkray::RenderTimings setup;  // the constructor's
  vkray::RenderTimings last_call;  // the last call's: the engine's, summed over the engine calls it made
  double reference_ms = 0.0;  // the reference's last call
  bool called = false;        // a render, cast or occlusion call was made: timings has a last call
  // The engine's Renderer serves one call at a time; callers' threads wait their turn here.
  std::mutex busy;
};

namespace vkray::api {

// The calling thread's last failure (vkray_last_error).
extern thread_local std::string last_error;

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

// InputError "WHAT: NULL" where `pointer` is null.
void require(const void* pointer, const char* what);
// A scene is read-only once finished or loaded (vkray.h): what `call` would add or change is refused,
// so that what a renderer takes has passed check_scene.
void require_unfinished(const vkray_scene& scene, const char* call);
// An image side: none for 0 (the scene's), else within max_image_side.
std::optional<uint32_t> size_or_default(uint32_t given, const char* what);

inline glm::dvec3 vec3_at(const double* values, size_t row, size_t columns, size_t first = 0) {
  const double* at = values + row * columns + first;
  return {at[0], at[1], at[2]};
}

// An output asked for by name, known (render's aovs, or given rays' outputs: "t" for the depth).
const OutputInfo& output_named(const char* name, bool rays);

// Writes `planes` (components planes of `count` values, the engine's layout) into `result`,
// count x components, converted to T.
template <typename T, typename Planes>
void interleave(const Planes& planes, size_t count, uint32_t components, void* result) {
  T* out = static_cast<T*>(result);
  for (size_t k = 0; k < count; ++k) {
    for (uint32_t c = 0; c < components; ++c) out[k * components + c] = static_cast<T>(planes[c * count + k]);
  }
}

// The scene's camera with `camera_json`'s keys over it (none: the scene's).
Camera camera_over(const char* camera_json, const Camera& base);
// A renderer's timings as vkray_renderer_timings gives them: a call's, or (constructor) its setup.
nlohmann::json timings_json(const RenderTimings& t, bool constructor);
// A 4 x 4 affine matrix given row-major (last row 0 0 0 1) of finite numbers, as glm holds it.
glm::dmat4 affine_matrix(const double* rows, const std::string& path);
// An object's mask from the C API's 32-bit argument: 8 bits (see Mask).
Mask object_mask_argument(uint32_t mask);
// Makes `mask` the renderer's rays' for the call under way (the caller holds `busy`): the engine's,
// or the reference's tree made again for it.
void use_ray_mask(vkray_renderer& renderer, uint32_t mask);

}  // namespace vkray::api
