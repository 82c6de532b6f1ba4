#include "engine/render/dispatch_sizer.hpp"
#include "engine/render/renderer_impl.hpp"
#include "engine/stopwatch.hpp"

#include <bit>
#include <cmath>

namespace vkray {

double Renderer::Impl::dispatch_tile(const vk::raii::Pipeline& chosen, const gpu::RayGenParams& params) {
  if (pipeline->first_dispatch(chosen)) {
    // A pipeline's first dispatch runs over one row of workgroups, untimed: lavapipe compiles a
    // pipeline's code there (a first render or occlusion query took 3 to 5 times its tenth's time;
    // the viewer's first frame 657 ms of GPU time against 24 ms). Timed, it would pass for a dispatch
    // over the budget and shrink every dispatch after it (13 where 2 do, in the report that found it).
    // That time is the pipeline's; the same rows run again below, writing the same values.
    const auto warm_up_start = Clock::now();
    const RenderTimings before = timings;
    gpu::RayGenParams first_rows = params;
    first_rows.image.w = std::min(params.image.w, workgroup_footprint(tile.mode).height);
    submit_tile(chosen, first_rows);
    timings = before;
    timings.pipeline_ms += elapsed_ms(warm_up_start);
  }
  return submit_tile(chosen, params);
}

double Renderer::Impl::submit_tile(const vk::raii::Pipeline& chosen, const gpu::RayGenParams& params) {
  const auto submitted = Clock::now();
  const bool to_image = tile.image_id != 0;
  context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    if (*timestamps) {
      commands.resetQueryPool(*timestamps, 0, 3);
      commands.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *timestamps, 0);
    }
    if (tile.overflow || to_image) {
      if (tile.overflow) commands.fillBuffer(*tile.overflow->written.buffer, 0, sizeof(uint32_t), 0u);
      if (to_image) {  // (+infinity, 0): see DepthRangeBits
        commands.fillBuffer(*depth_range->written.buffer, 0, sizeof(uint32_t), std::bit_cast<uint32_t>(INFINITY));
        commands.fillBuffer(*depth_range->written.buffer, sizeof(uint32_t), VK_WHOLE_SIZE, 0u);
      }
      const vk::MemoryBarrier cleared(vk::AccessFlagBits::eTransferWrite,
                                      vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eComputeShader, {},
                               cleared, {}, {});
    }
    pipeline->bind(commands, chosen, params);
    const vk::Extent2D group = workgroup_footprint(tile.mode);
    commands.dispatch((tile.width + group.width - 1) / group.width, (params.image.w + group.height - 1) / group.height, 1);
    if (*timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eComputeShader, *timestamps, 1);
    // Make the shader's writes visible to the copy into host-visible memory, and to the host.
    const vk::MemoryBarrier barrier(vk::AccessFlagBits::eShaderWrite,
                                    vk::AccessFlagBits::eTransferRead | vk::AccessFlagBits::eHostRead);
    commands.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader,
                             vk::PipelineStageFlagBits::eTransfer | vk::PipelineStageFlagBits::eHost, {}, barrier, {},
                             {});
    bool copied = false;
    for (const auto* output :
         {&tile.depth, &tile.normal, &tile.uv, &tile.overflow, &tile.hits, &tile.instance_hits, to_image ? &depth_range : nullptr}) {
      if (!output || !*output || !(*output)->readback) continue;
      const OutputBuffer& written = **output;
      // First hits fill a run of the tile's planes each (TileOutputs::layers).
      const vk::DeviceSize pixels = vk::DeviceSize{tile.width} * params.image.w *
                                    (output == &tile.depth || output == &tile.normal || output == &tile.hits || output == &tile.instance_hits
                                         ? tile.layers
                                         : 1);
      // Of the list of rays the CPU finishes, its count alone: it is almost always 0, and the rays it
      // lists are fetched when it is not (finish_unfinished). At 8K the whole list is 127 MiB a frame.
      const vk::DeviceSize bytes = output == &tile.overflow ? written.header_bytes : written.bytes_written(pixels);
      if (const auto& frame = written.frame_planes) {
        // Each plane of the tile (packed to its pixels) to the tile's rows of that plane in the frame.
        const vk::DeviceSize tile_plane_bytes = pixels * frame->element_bytes;
        const vk::DeviceSize first_pixel = vk::DeviceSize{tile.width} * params.image.z;
        std::vector<vk::BufferCopy> regions;
        for (vk::DeviceSize plane = 0; plane < written.pixel_bytes / frame->element_bytes; ++plane) {
          regions.emplace_back(plane * tile_plane_bytes,
                              frame->memory.offset + (plane * frame->frame_pixels + first_pixel) * frame->element_bytes,
                              tile_plane_bytes);
        }
        commands.copyBuffer(*written.written.buffer, *frame->memory.buffer.buffer, regions);
        timings.readback_in_place_bytes += bytes;
      } else {
        commands.copyBuffer(*written.written.buffer, *written.readback->buffer, vk::BufferCopy(0, 0, bytes));
      }
      timings.readback_bytes += bytes;
      copied = true;
    }
    if (copied) {  // a fence wait alone does not make device writes visible to the host
      const vk::MemoryBarrier to_host(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, to_host,
                               {}, {});
    }
    if (*timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *timestamps, 2);
  });

  double dispatch_ms = elapsed_ms(submitted);
  if (*timestamps) {
    const auto [result, ticks] = timestamps.getResults<uint64_t>(
        0, 3, 3 * sizeof(uint64_t), sizeof(uint64_t), vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
    const double period_ms = context.info.timestamp_period_ns * 1e-6;
    dispatch_ms = static_cast<double>(ticks[1] - ticks[0]) * period_ms;
    timings.dispatch_gpu_ms += dispatch_ms;
    timings.readback_ms += static_cast<double>(ticks[2] - ticks[1]) * period_ms;
  }
  ++timings.tiles;
  timings.longest_dispatch_ms = std::max(timings.longest_dispatch_ms, dispatch_ms);
  return dispatch_ms;
}

void Renderer::Impl::dispatch_camera_rows(const vk::raii::Pipeline& camera_pipeline, const CameraBasis& basis,
                                          uint32_t width, uint32_t height, uint32_t tile_rows, RaycastMode mode,
                                          const std::function<void(uint32_t first_row, uint32_t rows)>& tile_done) {
  DispatchSizer sizer(width, tile_rows, options.dispatch_budget_ms, camera_ms_per_pixel, workgroup_footprint(mode).height);
  for (uint32_t first_row = 0, rows = 0; first_row < height; first_row += rows) {
    rows = std::min(sizer.next_rows(), height - first_row);
    sizer.measured(rows, dispatch_tile(camera_pipeline, make_ray_gen_params(basis, anchor, precision(), width, height,
                                                                            first_row, rows, counts)));
    camera_ms_per_pixel = sizer.slowest_ms_per_pixel();
    tile_done(first_row, rows);
  }
}

double Renderer::Impl::sustained_dispatch_ms(const Camera& camera, uint32_t width, uint32_t height, AovSet aovs,
                                             uint32_t repeats) {
  uint32_t tile_rows = 0;
  const vk::raii::Pipeline& chosen = begin_render(camera, width, height, aovs, nullptr, tile_rows);
  const CameraBasis basis = make_camera_basis(camera, width, height);
  std::vector<gpu::RayGenParams> tiles;
  for (uint32_t first_row = 0; first_row < height; first_row += tile_rows) {
    tiles.push_back(make_ray_gen_params(basis, anchor, precision(), width, height, first_row,
                                        std::min(tile_rows, height - first_row), counts));
  }
  const vk::Extent2D group = workgroup_footprint(RaycastMode::image_buffers);
  const auto submitted = Clock::now();
  context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    if (*timestamps) {
      commands.resetQueryPool(*timestamps, 0, 2);
      commands.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *timestamps, 0);
    }
    // Each pass writes the outputs the last one wrote, and starts the list of unfinished rays
    // anew (its count would otherwise run past the list's end).
    const vk::MemoryBarrier written(vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eTransferWrite,
                                    vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eShaderRead |
                                        vk::AccessFlagBits::eTransferWrite);
    const auto stages = vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer;
    for (uint32_t pass = 0; pass < repeats; ++pass) {
      for (const gpu::RayGenParams& params : tiles) {
        if (tile.overflow) {
          commands.fillBuffer(*tile.overflow->written.buffer, 0, sizeof(uint32_t), 0u);
          commands.pipelineBarrier(stages, stages, {}, written, {}, {});
        }
        pipeline->bind(commands, chosen, params);
        commands.dispatch((width + group.width - 1) / group.width, (params.image.w + group.height - 1) / group.height, 1);
        commands.pipelineBarrier(stages, stages, {}, written, {}, {});
      }
    }
    if (*timestamps) commands.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *timestamps, 1);
  });
  double total_ms = elapsed_ms(submitted);
  if (*timestamps) {
    const auto [result, ticks] = timestamps.getResults<uint64_t>(
        0, 2, 2 * sizeof(uint64_t), sizeof(uint64_t), vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
    total_ms = static_cast<double>(ticks[1] - ticks[0]) * context.info.timestamp_period_ns * 1e-6;
  }
  return total_ms / repeats;
}

}  // namespace vkray
