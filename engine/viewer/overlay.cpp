#include "engine/viewer/overlay.hpp"

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

namespace vkray {
namespace {

void check_imgui_vulkan(VkResult result) {
  if (result < 0) throw GpuError("the overlay's Vulkan call failed: " + vk::to_string(static_cast<vk::Result>(result)));
}

// Margin of the text box from the window's corner, in pixels; its background's opacity.
constexpr float overlay_margin = 8.0f;
constexpr float overlay_background_alpha = 0.6f;

}  // namespace

Overlay::Overlay(VulkanContext& context, GLFWwindow* window, vk::RenderPass pass, uint32_t min_images, uint32_t images) {
  with_vulkan_errors("starting the overlay", [&] {
    // The backend's one descriptor set: the font texture.
    const vk::DescriptorPoolSize size(vk::DescriptorType::eCombinedImageSampler, 1);
    pool_ = vk::raii::DescriptorPool(
        context.device, vk::DescriptorPoolCreateInfo(vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, 1, size));
    imgui_ = ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini written into the working folder
    // No callbacks: the overlay takes no input, the viewer's own callbacks stay alone.
    ImGui_ImplGlfw_InitForVulkan(window, false);
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = *context.instance;
    info.PhysicalDevice = *context.physical_device;
    info.Device = *context.device;
    info.QueueFamily = context.queue_family;
    info.Queue = *context.queue;
    info.DescriptorPool = *pool_;
    info.PipelineCache = *context.pipeline_cache->handle();
    info.MinImageCount = min_images;
    info.ImageCount = images;
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = check_imgui_vulkan;
    ImGui_ImplVulkan_Init(&info, pass);
    context.pipeline_cache->save();
    context.submit_and_wait([](const vk::raii::CommandBuffer& commands) { ImGui_ImplVulkan_CreateFontsTexture(*commands); });
    ImGui_ImplVulkan_DestroyFontUploadObjects();
  });
}

Overlay::~Overlay() {
  ImGui_ImplVulkan_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext(imgui_);
}

void Overlay::set_min_image_count(uint32_t min_images) { ImGui_ImplVulkan_SetMinImageCount(min_images); }

void Overlay::draw(const std::vector<std::string>& lines, const std::string& error, vk::CommandBuffer commands) {
  // Laid out twice, drawn once: an auto-resized ImGui window takes its size from the frame before
  // (a new one is hidden on its first frame), and a viewer that waits for input draws no next
  // frame, so with one pass the first frame had no overlay and a new error line stayed clipped.
  for (int pass = 0; pass < 2; ++pass) {
    ImGui_ImplVulkan_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(overlay_margin, overlay_margin));
    ImGui::SetNextWindowBgAlpha(overlay_background_alpha);
    ImGui::Begin("vkray", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoInputs |
                     ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
    for (const std::string& line : lines) ImGui::TextUnformatted(line.c_str());
    if (!error.empty()) {
      ImGui::PushTextWrapPos(ImGui::GetFontSize() * 40.0f);
      ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.4f, 1.0f), "%s", error.c_str());
      ImGui::PopTextWrapPos();
    }
    ImGui::End();
    if (pass == 0) ImGui::EndFrame();
  }
  ImGui::Render();
  ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), commands);
}

}  // namespace vkray
