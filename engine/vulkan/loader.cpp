#include "engine/vulkan/loader.hpp"

#include "engine/device/gpu_device.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <mutex>

namespace vkray {
namespace {

constexpr const char* loader_name = "libvulkan.so.1";

// The bundle's copy: lib/vulkan/ beside the folder of the file this code is in (the Python
// module's python/, or the executable's libexec/). dladdr names a shared object by its path, but
// the executable by how it was started (argv[0]): that one is /proc/self/exe.
std::filesystem::path bundled_loader() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&bundled_loader), &info) == 0 || !info.dli_fname) return {};
  const std::filesystem::path named(info.dli_fname);
  const bool shared_object = named.is_absolute() && named.filename().string().find(".so") != std::string::npos;
  std::error_code error;
  const std::filesystem::path here = std::filesystem::canonical(shared_object ? named : "/proc/self/exe", error);
  if (error) return {};
  return here.parent_path().parent_path() / "lib" / "vulkan" / loader_name;
}

struct Loader {
  void* handle = nullptr;
  PFN_vkGetInstanceProcAddr entry = nullptr;
  std::string file;
  bool bundled = false;
};

const Loader& loader() {
  static Loader loaded;
  static std::once_flag once;
  std::call_once(once, [] {
    loaded.handle = dlopen(loader_name, RTLD_NOW | RTLD_LOCAL);
    if (!loaded.handle) {
      const std::filesystem::path copy = bundled_loader();
      std::error_code error;
      if (!copy.empty() && std::filesystem::exists(copy, error)) {
        loaded.handle = dlopen(copy.c_str(), RTLD_NOW | RTLD_LOCAL);
      }
    }
    if (!loaded.handle) return;
    loaded.entry = reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loaded.handle, "vkGetInstanceProcAddr"));
    Dl_info info{};
    if (loaded.entry && dladdr(reinterpret_cast<const void*>(loaded.entry), &info) != 0 && info.dli_fname) {
      loaded.file = info.dli_fname;
      // The launcher of a bundle puts its copy first on LD_LIBRARY_PATH where the machine has none:
      // loaded by name, it is still the bundle's.
      std::error_code error;
      const std::filesystem::path copy = bundled_loader();
      loaded.bundled = !copy.empty() && std::filesystem::equivalent(loaded.file, copy, error);
    }
  });
  return loaded;
}

}  // namespace

PFN_vkGetInstanceProcAddr vulkan_loader_entry() {
  if (!loader().entry) {
    throw GpuError(std::string("no Vulkan loader (") + loader_name +
                   ") on this machine: install it (Debian and Ubuntu: libvulkan1; Fedora and RHEL: vulkan-loader), "
                   "or run vkray from its bundle, which carries one");
  }
  return loader().entry;
}

std::string vulkan_loader_description() {
  if (!loader().entry) return std::string("none (no ") + loader_name + " on this machine)";
  return loader().file + (loader().bundled ? " (the bundle's: this machine has none)" : " (the machine's)");
}

}  // namespace vkray
