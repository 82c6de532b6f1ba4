#include "engine/renderer.hpp"

#include "engine/camera.hpp"
#include "engine/gpu_scene.hpp"
#include "engine/vulkan/buffer.hpp"
#include "engine/vulkan/raycast_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <optional>

namespace vkray {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

template <typename T>
std::optional<GpuBuffer> upload_if_any(VulkanContext& context, const std::vector<T>& items) {
  if (items.empty()) return std::nullopt;
  return upload_storage_buffer(context, items.data(), items.size() * sizeof(T));
}

uint32_t checked_count(size_t count, const char* what) {
  if (count > UINT32_MAX) throw InputError(std::string("too many ") + what + " for one scene");
  return static_cast<uint32_t>(count);
}

// Bytes per pixel of each output buffer.
constexpr vk::DeviceSize depth_bytes = sizeof(float);
constexpr vk::DeviceSize normal_bytes = 3 * sizeof(float);
constexpr vk::DeviceSize uv_bytes = 2 * sizeof(float);

// One output of one tile: the buffer the shader writes and, where that buffer is not host-visible,
// the buffer it is copied into for reading.
struct OutputBuffer {
  GpuBuffer written;
  std::optional<GpuBuffer> readback;
  const void* host() const { return readback ? readback->mapped : written.mapped; }
};

// Output buffers for tiles of `width` x `rows`, kept between renders of the same shape.
struct TileOutputs {
  uint32_t width = 0;
  uint32_t rows = 0;
  uint32_t aov_bits = 0;
  std::optional<OutputBuffer> depth, normal, uv;
};

}  // namespace

struct Renderer::Impl {
  Impl(VulkanContext& vulkan_context, RendererOptions renderer_options)
      : context(vulkan_context), options(renderer_options) {}

  VulkanContext& context;
  RendererOptions options;
  glm::dvec3 anchor{0.0};
  GpuBuffer placeholder;  // bound wherever the scene lacks a primitive type or an output is off
  std::optional<GpuBuffer> spheres, planes, triangles, meshes;
  std::optional<RaycastPipeline> pipeline;
  vk::raii::QueryPool timestamps{nullptr};
  TileOutputs tile;
  RenderTimings timings;

  OutputBuffer make_output(vk::DeviceSize bytes) {
    OutputBuffer output{create_storage_buffer(context, bytes, vk::BufferUsageFlagBits::eTransferSrc), std::nullopt};
    if (!output.written.mapped) output.readback = create_readback_buffer(context, bytes);
    return output;
  }

  void prepare_tile(uint32_t width, uint32_t rows, AovSet aovs) {
    if (tile.width == width && tile.rows == rows && tile.aov_bits == aovs.bits()) return;
    tile = TileOutputs{width, rows, aovs.bits(), {}, {}, {}};
    const vk::DeviceSize pixels = vk::DeviceSize{width} * rows;
    if (aovs.has(Aov::depth)) tile.depth = make_output(pixels * depth_bytes);
    if (aovs.has(Aov::normal)) tile.normal = make_output(pixels * normal_bytes);
    if (aovs.has(Aov::uv)) tile.uv = make_output(pixels * uv_bytes);
    auto handle = [&](const auto& buffer) { return buffer ? *buffer->buffer : *placeholder.buffer; };
    auto output_handle = [&](const std::optional<OutputBuffer>& output) {
      return output ? *output->written.buffer : *placeholder.buffer;
    };
    std::array<vk::Buffer, VKRAY_BINDING_COUNT> bindings;
    bindings[VKRAY_BINDING_SPHERES] = handle(spheres);
    bindings[VKRAY_BINDING_PLANES] = handle(planes);
    bindings[VKRAY_BINDING_TRIANGLES] = handle(triangles);
    bindings[VKRAY_BINDING_MESHES] = handle(meshes);
    bindings[VKRAY_BINDING_DEPTH] = output_handle(tile.depth);
    bindings[VKRAY_BINDING_NORMAL] = output_handle(tile.normal);
    bindings[VKRAY_BINDING_UV] = output_handle(tile.uv);
    pipeline->bind_buffers(bindings);
  }

  // Rows per dispatch: every output buffer within the device's storage-buffer range (and the
  // caller's cap), and the workgroup count within the device's limit.
  uint32_t rows_per_tile(uint32_t width, uint32_t height, AovSet aovs) const {
    vk::DeviceSize largest = 0;
    if (aovs.has(Aov::depth)) largest = std::max(largest, depth_bytes);
    if (aovs.has(Aov::normal)) largest = std::max(largest, normal_bytes);
    if (aovs.has(Aov::uv)) largest = std::max(largest, uv_bytes);
    vk::DeviceSize limit = context.limits.maxStorageBufferRange;
    if (options.max_tile_bytes > 0) limit = std::min<vk::DeviceSize>(limit, options.max_tile_bytes);
    const vk::DeviceSize by_bytes = std::max<vk::DeviceSize>(1, limit / (vk::DeviceSize{width} * largest));
    const vk::DeviceSize by_groups = vk::DeviceSize{context.limits.maxComputeWorkGroupCount[1]} * VKRAY_WORKGROUP_Y;
    return static_cast<uint32_t>(std::min<vk::DeviceSize>({height, by_bytes, by_groups}));
  }
};

Renderer::Renderer(GpuDevice& device, const Scene& scene, RendererOptions options)
    : impl_(std::make_unique<Impl>(device.vulkan(), options)) {
  with_vulkan_errors("uploading the scene", [&] {
    const auto start = Clock::now();
    Impl& r = *impl_;
    const GpuScene gpu_scene = make_gpu_scene(scene);
    const PrimitiveCounts counts{checked_count(gpu_scene.spheres.size(), "spheres"),
                                 checked_count(gpu_scene.planes.size(), "planes"),
                                 checked_count(gpu_scene.meshes.size(), "meshes")};
    checked_count(gpu_scene.triangles.size(), "triangles");
    const vk::DeviceSize buffer_limit =
        std::min<vk::DeviceSize>(r.context.limits.maxStorageBufferRange, r.context.info.max_allocation_bytes);
    if (gpu_scene.triangles.size() * sizeof(gpu::GpuTriangle) > buffer_limit) {
      throw GpuError(std::to_string(gpu_scene.triangles.size()) + " triangles take " +
                     std::to_string(gpu_scene.triangles.size() * sizeof(gpu::GpuTriangle) >> 20) + " MiB, more than " +
                     r.context.info.name + " can bind as one storage buffer (" + std::to_string(buffer_limit >> 20) +
                     " MiB)");
    }
    // The count above models the loops of raycast.comp; the margin covers the few iterations the
    // compiler may keep where it fails to unroll a constant-trip loop.
    constexpr uint64_t loop_margin = 16;
    const uint64_t loop_limit = r.context.info.max_loop_iterations;
    if (loop_limit > 0 && loop_iterations_per_ray(gpu_scene) + loop_margin > loop_limit) {
      throw GpuError("this scene needs up to " + std::to_string(loop_iterations_per_ray(gpu_scene)) +
                     " shader loop iterations per pixel, but " + r.context.info.name + " stops a shader after " +
                     std::to_string(loop_limit) + " and would silently drop geometry; use another device (--device)");
    }
    r.anchor = gpu_scene.anchor;
    r.placeholder = create_storage_buffer(r.context, 16);
    r.spheres = upload_if_any(r.context, gpu_scene.spheres);
    r.planes = upload_if_any(r.context, gpu_scene.planes);
    r.triangles = upload_if_any(r.context, gpu_scene.triangles);
    r.meshes = upload_if_any(r.context, gpu_scene.meshes);
    r.pipeline.emplace(r.context, counts);
    if (r.context.info.timestamp_period_ns > 0.0) {
      r.timestamps = vk::raii::QueryPool(r.context.device, vk::QueryPoolCreateInfo({}, vk::QueryType::eTimestamp, 3));
    }
    r.timings.upload_ms = elapsed_ms(start);
  });
}

Renderer::~Renderer() = default;

const RenderTimings& Renderer::timings() const { return impl_->timings; }

Frame Renderer::render(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs) {
  check_image_size(width, height);
  Impl& r = *impl_;
  Frame frame{width, height, aovs, {}, {}, {}};
  frame.allocate();
  r.timings = RenderTimings{r.timings.upload_ms, 0.0, *r.timestamps != vk::QueryPool(), 0.0, 0.0, 0};
  if (aovs.empty()) return frame;

  with_vulkan_errors("rendering", [&] {
    const vk::raii::Pipeline& pipeline = r.pipeline->pipeline(aovs, r.timings.pipeline_ms);
    const CameraBasis basis = make_camera_basis(camera, width, height);
    const uint32_t tile_rows = r.rows_per_tile(width, height, aovs);
    r.prepare_tile(width, tile_rows, aovs);

    for (uint32_t first_row = 0; first_row < height; first_row += tile_rows) {
      const uint32_t rows = std::min(tile_rows, height - first_row);
      const gpu::RayGenParams params = make_ray_gen_params(basis, r.anchor, width, height, first_row, rows);
      r.context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
        if (*r.timestamps) {
          commands.resetQueryPool(*r.timestamps, 0, 3);
          commands.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *r.timestamps, 0);
        }
        r.pipeline->bind(commands, pipeline, params);
        commands.dispatch((width + VKRAY_WORKGROUP_X - 1) / VKRAY_WORKGROUP_X,
                          (rows + VKRAY_WORKGROUP_Y - 1) / VKRAY_WORKGROUP_Y, 1);
        if (*r.timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eComputeShader, *r.timestamps, 1);
        // Make the shader's writes visible to the copy into host-visible memory, and to the host.
        const vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                                        vk::AccessFlagBits::eTransferRead | vk::AccessFlagBits::eHostRead);
        commands.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                                 vk::PipelineStageFlagBits::eTransfer | vk::PipelineStageFlagBits::eHost, {}, barrier,
                                 {}, {});
        bool copied = false;
        for (const auto* output : {&r.tile.depth, &r.tile.normal, &r.tile.uv}) {
          if (*output && (*output)->readback) {
            commands.copyBuffer(*(*output)->written.buffer, *(*output)->readback->buffer,
                                vk::BufferCopy(0, 0, (*output)->written.size));
            copied = true;
          }
        }
        if (copied) {  // a fence wait alone does not make device writes visible to the host
          const vk::MemoryBarrier to_host(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
          commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {},
                                   to_host, {}, {});
        }
        if (*r.timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *r.timestamps, 2);
      });

      if (*r.timestamps) {
        const auto [result, ticks] = r.timestamps.getResults<uint64_t>(
            0, 3, 3 * sizeof(uint64_t), sizeof(uint64_t), vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
        const double period_ms = r.context.info.timestamp_period_ns * 1e-6;
        r.timings.dispatch_gpu_ms += static_cast<double>(ticks[1] - ticks[0]) * period_ms;
        r.timings.readback_ms += static_cast<double>(ticks[2] - ticks[1]) * period_ms;
      }
      const auto copy_start = Clock::now();
      // The shader packs each plane of this tile to width * rows floats (see raycast.comp); each
      // lands in the same plane of the frame.
      const size_t first_pixel = size_t{first_row} * width;
      const size_t tile_pixels = size_t{rows} * width;
      auto copy_planes = [&](const std::optional<OutputBuffer>& output, std::vector<float>& target, size_t planes) {
        if (!output) return;
        const auto* source = static_cast<const float*>(output->host());
        for (size_t plane = 0; plane < planes; ++plane) {
          std::memcpy(target.data() + plane * frame.pixel_count() + first_pixel,
                      source + plane * tile_pixels, tile_pixels * sizeof(float));
        }
      };
      copy_planes(r.tile.depth, frame.depth, 1);
      copy_planes(r.tile.normal, frame.normal, 3);
      copy_planes(r.tile.uv, frame.uv, 2);
      r.timings.readback_ms += elapsed_ms(copy_start);
      ++r.timings.tiles;
    }
  });
  return frame;
}

}  // namespace vkray
