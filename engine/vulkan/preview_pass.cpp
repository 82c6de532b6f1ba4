#include "engine/vulkan/preview_pass.hpp"

#include "engine/io/preview.hpp"
#include "engine/vulkan/shader_modules.hpp"

#include <cstring>
#include <stdexcept>

namespace vkray {
namespace {

// preview.comp's local_size.
constexpr uint32_t group_side = 8;

uint32_t preview_mode(Aov aov) {
  switch (aov) {
    case Aov::depth: return VKRAY_PREVIEW_DEPTH;
    case Aov::normal: return VKRAY_PREVIEW_NORMAL;
    case Aov::uv: return VKRAY_PREVIEW_UV;
    default: break;  // the other outputs: the viewer refuses them (cli/view_command.cpp)
  }
  throw std::invalid_argument("the viewer shows depth, normal or uv, not " + AovSet{aov}.names());
}

}  // namespace

PreviewPass::PreviewPass(VulkanContext& context) : context_(context) {
  with_vulkan_errors("making the preview pipeline", [&] {
    shader_.emplace(context_.device, embedded_shader("preview.comp", {}));
    const vk::PushConstantRange push_range(vk::ShaderStageFlagBits::eCompute, 0, sizeof(gpu::PreviewParams));
    const vk::DescriptorSetLayout set_layout = *shader_->layout;
    layout_ = vk::raii::PipelineLayout(context_.device, vk::PipelineLayoutCreateInfo({}, set_layout, push_range));
    const vk::PipelineShaderStageCreateInfo stage({}, vk::ShaderStageFlagBits::eCompute, *shader_->module, "main");
    pipeline_ = vk::raii::Pipeline(context_.device, context_.pipeline_cache->handle(),
                                   vk::ComputePipelineCreateInfo({}, stage, *layout_));
    context_.pipeline_cache->save();
    ramps_ = create_upload_buffer(context_, sizeof(gpu::GpuPreviewRamps), vk::BufferUsageFlagBits::eUniformBuffer);
  });
}

void PreviewPass::run(const ImageTarget& values, Aov aov, DepthRange depths, bool bgra) {
  with_vulkan_errors("making the preview", [&] {
    const vk::Extent2D extent(values.width(), values.height());
    const bool resized = !picture_ || picture_->extent != extent;
    if (resized) {
      picture_.reset();
      picture_ = create_storage_image(context_, extent, vk::Format::eR8G8B8A8Uint, vk::ImageUsageFlagBits::eTransferSrc);
    }
    if (resized || bound_values_ != values.id()) {
      const vk::DescriptorImageInfo value_info({}, *values.image().view, vk::ImageLayout::eGeneral);
      const vk::DescriptorImageInfo picture_info({}, *picture_->view, vk::ImageLayout::eGeneral);
      const vk::DescriptorBufferInfo ramps_info(*ramps_.buffer, 0, VK_WHOLE_SIZE);
      const std::array writes{
          vk::WriteDescriptorSet(*shader_->set, VKRAY_PREVIEW_BINDING_VALUES, 0, shader_->types.at(VKRAY_PREVIEW_BINDING_VALUES), value_info),
          vk::WriteDescriptorSet(*shader_->set, VKRAY_PREVIEW_BINDING_PICTURE, 0, shader_->types.at(VKRAY_PREVIEW_BINDING_PICTURE), picture_info),
          vk::WriteDescriptorSet(*shader_->set, VKRAY_PREVIEW_BINDING_RAMPS, 0, shader_->types.at(VKRAY_PREVIEW_BINDING_RAMPS), nullptr, ramps_info)};
      context_.device.updateDescriptorSets(writes, {});
      bound_values_ = values.id();
    }

    // No submission is in flight: each run waits for its own.
    const auto ramps = preview_ramps(aov, depths);
    for (size_t r = 0; r < ramps.size(); ++r) {
      std::memcpy(static_cast<float*>(ramps_.mapped) + r * VKRAY_RAMP_LEVELS, ramps[r].thresholds.data(),
                  sizeof(ramps[r].thresholds));
    }
    const gpu::PreviewParams params{glm::uvec4(extent.width, extent.height, preview_mode(aov), bgra ? 1u : 0u)};

    context_.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      // After the render's shader and transfer writes into `values`.
      const vk::MemoryBarrier values_written(vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eTransferWrite,
                                             vk::AccessFlagBits::eShaderRead);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer,
                               vk::PipelineStageFlagBits::eComputeShader, {}, values_written, {}, {});
      // The picture is written whole: its old contents go (UNDEFINED), once the last copy out of it
      // is done.
      transition_image(commands, *picture_->image, vk::PipelineStageFlagBits::eTransfer, {}, vk::ImageLayout::eUndefined,
                       vk::PipelineStageFlagBits::eComputeShader, vk::AccessFlagBits::eShaderWrite,
                       vk::ImageLayout::eGeneral);
      commands.bindPipeline(vk::PipelineBindPoint::eCompute, *pipeline_);
      commands.bindDescriptorSets(vk::PipelineBindPoint::eCompute, *layout_, 0, {*shader_->set}, {});
      commands.pushConstants<gpu::PreviewParams>(*layout_, vk::ShaderStageFlagBits::eCompute, 0, params);
      commands.dispatch((extent.width + group_side - 1) / group_side, (extent.height + group_side - 1) / group_side, 1);
      // For the copies out of the picture that follow (onto the swapchain, or read_rgb).
      transition_image(commands, *picture_->image, vk::PipelineStageFlagBits::eComputeShader,
                       vk::AccessFlagBits::eShaderWrite, vk::ImageLayout::eGeneral, vk::PipelineStageFlagBits::eTransfer,
                       vk::AccessFlagBits::eTransferRead, vk::ImageLayout::eTransferSrcOptimal);
    });
  });
}

std::vector<uint8_t> PreviewPass::read_rgb() {
  return with_vulkan_errors("reading the preview back", [&] {
    const vk::Extent2D extent = picture_->extent;
    const size_t pixels = size_t{extent.width} * extent.height;
    GpuBuffer readback = create_readback_buffer(context_, pixels * 4);
    context_.submit_and_wait([&](const vk::raii::CommandBuffer& commands) {
      const vk::BufferImageCopy region(0, 0, 0, color_layer, {0, 0, 0}, vk::Extent3D(extent, 1));
      commands.copyImageToBuffer(*picture_->image, vk::ImageLayout::eTransferSrcOptimal, *readback.buffer, region);
      const vk::MemoryBarrier to_host(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
      commands.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {}, to_host, {}, {});
    });
    const auto* rgba = static_cast<const uint8_t*>(readback.mapped);
    std::vector<uint8_t> rgb(pixels * 3);
    for (size_t p = 0; p < pixels; ++p) std::memcpy(&rgb[3 * p], &rgba[4 * p], 3);
    return rgb;
  });
}

}  // namespace vkray
