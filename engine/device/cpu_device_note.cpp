// Saying so when the device is a CPU implementation of Vulkan, and why no GPU was used when one
// seems present. The signs are the ones a user can act on: a GPU device node with no Vulkan driver
// listed for it, or an NVIDIA container started without the graphics capability (its compute-only
// default hides the Vulkan driver, so the loader finds llvmpipe alone).
#include "engine/device/gpu_device.hpp"

#include <cstdlib>
#include <filesystem>
#include <string>

namespace vkray {
namespace {

bool exists(const char* path) {
  std::error_code error;
  return std::filesystem::exists(path, error);
}

// The first DRM render node (/dev/dri/renderD128 and on), which every Linux GPU driver creates; empty
// if none.
std::string render_node() {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/dev/dri", error)) {
    if (entry.path().filename().string().starts_with("renderD")) return entry.path().string();
  }
  return "";
}

}  // namespace

std::string cpu_device_note(const GpuDeviceInfo& device) {
  if (device.type != "cpu") return "";
  const std::string note = "vkray: note: rendering on " + device.name + ", a CPU implementation of Vulkan";
  if (exists("/dev/nvidia0") || exists("/proc/driver/nvidia/version")) {
    const char* capabilities = std::getenv("NVIDIA_DRIVER_CAPABILITIES");
    const std::string given = capabilities ? capabilities : "";
    if (capabilities && given.find("graphics") == std::string::npos && given.find("all") == std::string::npos) {
      return note + ", though an NVIDIA GPU is present: this container lacks the graphics capability that NVIDIA's "
                    "Vulkan driver needs (NVIDIA_DRIVER_CAPABILITIES=" + given +
             "; start it with NVIDIA_DRIVER_CAPABILITIES=all, or compute,utility,graphics)";
    }
    return note + ", though an NVIDIA GPU is present (/dev/nvidia0): Vulkan lists no driver for it; install NVIDIA's "
                  "Vulkan driver (Debian: nvidia-vulkan-icd), then `vkray info` lists the GPU";
  }
  if (const std::string node = render_node(); !node.empty()) {
    return note + ", though a GPU is present (" + node + "): Vulkan lists no driver for it; install one (Debian: "
                  "mesa-vulkan-drivers for AMD and Intel), then `vkray info` lists the GPU";
  }
  return note + " (no GPU is visible here): expect the CPU's speed";
}

}  // namespace vkray
