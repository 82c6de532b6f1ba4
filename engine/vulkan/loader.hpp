// The Vulkan loader (libvulkan.so.1) vkray talks to, found at run time rather than linked: the
// machine's wherever the dynamic linker finds one (it knows the machine's drivers and layers), else
// the copy a relocatable bundle carries in lib/vulkan/ (docs/install.md, "Installing on a GPU server"), for
// machines that have a driver but no loader. Only engine/ code includes this file.
#pragma once

#include <vulkan/vulkan.h>

namespace vkray {

// vkGetInstanceProcAddr of the loader, loaded on first use and kept for the life of the process.
// Throws GpuError naming what to install where neither loader is there.
PFN_vkGetInstanceProcAddr vulkan_loader_entry();


}  // namespace vkray
