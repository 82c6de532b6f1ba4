#include "engine/render/renderer_impl.hpp"
#include "engine/stopwatch.hpp"
#include "engine/vulkan/image.hpp"

namespace vkray {

std::span<const uint32_t> Renderer::Impl::listed_rays() {
  const auto* overflow = static_cast<const uint32_t*>(tile.overflow->host());
  const uint32_t count = overflow[0];
  if (count > 0 && tile.overflow->readback) {  // staging: the dispatch copied the count alone; now the rays listed
    const vk::DeviceSize listed = vk::DeviceSize{count} * sizeof(uint32_t);
    context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      commands.copyBuffer(*tile.overflow->written.buffer, *tile.overflow->readback->buffer,
                          vk::BufferCopy(tile.overflow->header_bytes, tile.overflow->header_bytes, listed));
      const vk::MemoryBarrier to_host(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, to_host, {}, {});
    });
    timings.readback_bytes += listed;
  }
  return {overflow + 1, count};
}

void Renderer::Impl::finish_unfinished(const std::function<void(uint32_t index)>& finish) {
  const auto start = Clock::now();
  const std::span<const uint32_t> listed = listed_rays();
  if (listed.empty()) return;
  if (!reference) reference.emplace(host_scene, ray_mask);
  for (const uint32_t index : listed) finish(index);
  timings.unfinished_rays += listed.size();
  timings.cpu_finish_ms += elapsed_ms(start);
}

void Renderer::Impl::finish_unfinished_rays(
    const CameraBasis& basis, uint32_t width, uint32_t height, uint32_t first_row,
    const std::function<void(uint32_t i, uint32_t j, const ReferenceHit& hit)>& finish) {
  finish_unfinished([&](uint32_t index) {
    const uint32_t i = index % width;
    const uint32_t j = first_row + index / width;
    finish(i, j, reference->trace(basis.origin, basis.direction(pixel_uv(i, j, width, height))));
  });
}

void Renderer::Impl::write_patches(const std::vector<PixelPatch>& patches, ImageTarget& target) {
  GpuBuffer staging = create_upload_buffer(context, patches.size() * sizeof(glm::vec4));
  std::vector<vk::BufferImageCopy> regions;
  regions.reserve(patches.size());
  auto* values = static_cast<glm::vec4*>(staging.mapped);
  for (size_t k = 0; k < patches.size(); ++k) {
    values[k] = patches[k].value;
    regions.emplace_back(k * sizeof(glm::vec4), 0, 0, color_layer,
                         vk::Offset3D(int32_t(patches[k].i), int32_t(patches[k].j), 0), vk::Extent3D(1, 1, 1));
  }
  const vk::Image image = *target.image().image;
  context.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
    transition_image(commands, image, vk::PipelineStageFlagBits::eComputeShader, vk::AccessFlagBits::eShaderWrite,
                     vk::ImageLayout::eGeneral, vk::PipelineStageFlagBits::eTransfer, vk::AccessFlagBits::eTransferWrite,
                     vk::ImageLayout::eTransferDstOptimal);
    commands.copyBufferToImage(*staging.buffer, image, vk::ImageLayout::eTransferDstOptimal, regions);
    transition_image(commands, image, vk::PipelineStageFlagBits::eTransfer, vk::AccessFlagBits::eTransferWrite,
                     vk::ImageLayout::eTransferDstOptimal, vk::PipelineStageFlagBits::eComputeShader,
                     vk::AccessFlagBits::eShaderRead | vk::AccessFlagBits::eShaderWrite, vk::ImageLayout::eGeneral);
  });
}

}  // namespace vkray
