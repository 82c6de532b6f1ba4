// The render core: built once per scene (geometry uploaded once, pipelines made on first use), then
// rendered any number of times with a new camera, image size or set of outputs.
#pragma once

#include "engine/frame.hpp"
#include "engine/gpu_device.hpp"
#include "engine/scene.hpp"

#include <memory>

namespace vkray {

struct RenderTimings {
  double upload_ms = 0.0;          // scene conversion and upload (once, in the constructor)
  double pipeline_ms = 0.0;        // pipeline creation (first render with a given set of outputs)
  bool has_gpu_times = false;      // the device has timestamps; else dispatch_gpu_ms is not measured
  double dispatch_gpu_ms = 0.0;    // GPU time of the ray-casting dispatches (timestamp queries)
  double readback_ms = 0.0;        // copying results back into the Frame
  uint32_t tiles = 0;              // dispatches the image was split into
};

struct RendererOptions {
  // Upper bound on the bytes of one output buffer; the image is split into tiles of rows to stay
  // under it and under the device's maxStorageBufferRange (a tile has at least one row, whatever
  // the bound). 0: the device limit alone.
  uint64_t max_tile_bytes = 0;
};

class Renderer {
 public:
  Renderer(GpuDevice& device, const Scene& scene, RendererOptions options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders `camera` at width x height; only the outputs in `aovs` are computed and read back.
  Frame render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs);

  // Timings of the last render (upload_ms is the constructor's).
  const RenderTimings& timings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vkray
