// A deforming mesh's cost (Renderer::set_vertices), timed and measured in one run: every vertex of a
// model moved by up to 1% of its size, the tree refitted (its shape kept, its boxes recomputed),
// against the same call where the primitives change (one triangle collapsed to a point at every
// other call), which builds the tree anew; then a render after the refit against one on a Renderer
// made from the moved model, each with its error against the double-precision reference.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/reference/envelope.hpp"
#include "engine/scene/scene.hpp"
#include "engine/statistics.hpp"

#include <string>

namespace vkray {

struct MovingRow {
  size_t vertices = 0;
  TimeStats refit, rebuild;  // set_vertices' whole time (RenderTimings::scene_update_ms)
  bool every_call_refitted = true;  // none of the refitting calls fell back to a build
  // GPU time of a render of the moved model at the scene's size (depth and normal), on the refitted
  // tree and on a tree built for it, and each frame against the reference.
  TimeStats render_refitted, render_built;
  EnvelopeReport refitted_error, built_error;
};

// `frames` timed calls of each after an untimed first (the refitting Renderer's first call converts
// the scene; the later ones refit in place), then `frames` renders of each after a first.
MovingRow bench_moving(GpuDevice& device, const Scene& scene, uint32_t frames);

// `vkray bench --suite moving`' table: its header, and a row of a model.
std::string moving_table_header();
std::string moving_table_row(const std::string& model, const MovingRow& row);

}  // namespace vkray
