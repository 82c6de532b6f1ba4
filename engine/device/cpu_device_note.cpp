// Saying so when the device is a CPU implementation of Vulkan, and why no GPU was used when one
// seems present. The signs are the ones a user can act on: a GPU device node with no Vulkan driver
// listed for it, or an NVIDIA container started without the graphics capability (its compute-only
// default hides the Vulkan driver, so the loader finds llvmpipe alone).
#include "engine/device/gpu_device.hpp"

#include <dlfcn.h>

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <fstream>
#include <string_view>
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

// Where NVIDIA's Vulkan manifest lies in containers that mount the driver from the host, a place the
// loader does not search (it reads /usr/share, /usr/local/share and /etc): empty if none is there.
std::string unsearched_nvidia_manifest() {
  for (const char* manifest : {"/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json", "/usr/local/nvidia/icd.d/nvidia_icd.json"}) {
    if (exists(manifest)) return manifest;
  }
  return "";
}

// The first driver manifest named by VK_DRIVER_FILES (or the older VK_ICD_FILENAMES) whose library
// does not load, with the dynamic linker's reason ("libGLdispatch.so.0: cannot open shared object
// file"): the loader itself only says that it found no driver. Empty where each loads.
std::string driver_that_does_not_load() {
  const char* listed = std::getenv("VK_DRIVER_FILES");
  if (!listed || !*listed) listed = std::getenv("VK_ICD_FILENAMES");
  if (!listed) return "";
  std::string_view manifests(listed);
  while (!manifests.empty()) {
    const size_t colon = manifests.find(':');
    const std::string manifest(manifests.substr(0, colon));
    manifests = colon == std::string_view::npos ? std::string_view() : manifests.substr(colon + 1);
    std::ifstream file(manifest);
    if (!file) return "VK_DRIVER_FILES names " + manifest + ", which cannot be read";
    const nlohmann::json json = nlohmann::json::parse(file, nullptr, false);
    if (json.is_discarded() || !json.contains("ICD") || !json["ICD"].contains("library_path")) continue;
    std::string library = json["ICD"]["library_path"].get<std::string>();
    if (library.find('/') != std::string::npos && library.front() != '/') {
      library = (std::filesystem::path(manifest).parent_path() / library).string();  // relative to the manifest
    }
    if (void* handle = dlopen(library.c_str(), RTLD_LAZY | RTLD_LOCAL)) {
      dlclose(handle);
      continue;
    }
    const char* why = dlerror();
    return manifest + " names " + library + ", which does not load (" + (why ? why : "no reason given") + ")";
  }
  return "";
}

// The libglvnd libraries NVIDIA's Vulkan driver needs that do not load here ("libGLX.so.0,
// libEGL.so.1"), where an NVIDIA GPU is present: containers that mount the driver from the host
// often lack them, and then the loader only finds no driver (seen on an H100 in such a container:
// with libGLdispatch alone still none; with libglvnd0, libglx0 and libegl1 the GPU).
std::string missing_nvidia_libraries() {
  if (!exists("/dev/nvidia0") && !exists("/proc/driver/nvidia/version")) return "";
  std::string missing;
  for (const char* library : {"libGLdispatch.so.0", "libGLX.so.0", "libEGL.so.1"}) {
    if (void* handle = dlopen(library, RTLD_LAZY | RTLD_LOCAL)) {
      dlclose(handle);
    } else {
      missing += std::string(missing.empty() ? "" : ", ") + library;
    }
  }
  return missing;
}

}  // namespace

std::string vulkan_driver_advice() {
  const char* driver_files = std::getenv("VK_DRIVER_FILES");
  if (const std::string manifest = unsearched_nvidia_manifest(); !manifest.empty() && !(driver_files && *driver_files)) {
    return "NVIDIA's driver is here, but its manifest lies where the loader does not look: set VK_DRIVER_FILES=" + manifest;
  }
  if (const std::string missing = missing_nvidia_libraries(); !missing.empty()) {
    return "NVIDIA's Vulkan driver needs libglvnd, and " + missing + " do not load here: install them (Debian and "
           "Ubuntu: libglvnd0 libglx0 libegl1; Fedora and RHEL: libglvnd-glx libglvnd-egl)";
  }
  const std::string install = "install a Vulkan driver: on Debian, 'apt-get install mesa-vulkan-drivers' provides "
                              "lavapipe, a software GPU that always works";
  if (const std::string broken = driver_that_does_not_load(); !broken.empty()) return broken + "; or " + install;
  return install;
}

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
    if (const std::string manifest = unsearched_nvidia_manifest(); !manifest.empty()) {
      return note + ", though an NVIDIA GPU is present (/dev/nvidia0): its driver's manifest lies where the Vulkan "
                    "loader does not look; set VK_DRIVER_FILES=" + manifest + ", then `vkray info` lists the GPU";
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
