// The GPU as the rest of the program sees it: which Vulkan devices exist, which one is used, and
// an opened device to render with. No Vulkan type appears here, so the CLI never touches Vulkan.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace vkray {

// A failure of the Vulkan runtime: no driver, no device, out of memory, a lost device. The CLI
// maps it to exit code 1.
class GpuError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// No window can be shown: no display, or no device presents to it (the viewer). The message
// names the headless alternative.
class NoWindowError : public GpuError {
 public:
  explicit NoWindowError(const std::string& reason)
      : GpuError("cannot open a window: " + reason + "; 'vkray render' renders without one") {}
};

struct GpuDeviceInfo {
  std::string name;
  std::string type;  // "discrete", "integrated", "virtual", "cpu" or "other"
  std::string driver;
  std::string api_version;
  // A compute queue, and subgroup vote, ballot and arithmetic operations in compute shaders: vkray's
  // one ray-casting module declares them (the packet walk, the viewer's depth range), so a device
  // without them cannot create its pipeline. Every Vulkan 1.1 desktop driver and lavapipe have them.
  bool can_compute = false;
  uint32_t max_workgroup_count[3] = {0, 0, 0};
  uint32_t max_workgroup_invocations = 0;
  uint64_t max_storage_buffer_range = 0;
  uint64_t max_allocation_bytes = 0;
  uint32_t subgroup_size = 0;
  double timestamp_period_ns = 0.0;  // 0: the compute queue has no timestamps
  bool shader_float64 = false;
  // Loop iterations a shader invocation may run before the driver silently stops it: llvmpipe
  // (lavapipe) caps them at 65535 in total; 0 for no known limit.
  uint64_t max_loop_iterations = 0;
};

// Every Vulkan device, in enumeration order. Throws GpuError when Vulkan itself is unavailable.
std::vector<GpuDeviceInfo> list_gpu_devices();

// Index into `devices` of the one vkray uses: when `name_filter` is empty, the first discrete GPU,
// else integrated, virtual, then CPU (lavapipe); otherwise the first whose name contains
// `name_filter`, ignoring case. Throws GpuError when none fits.
size_t choose_gpu_device(const std::vector<GpuDeviceInfo>& devices, std::string_view name_filter);

struct VulkanContext;        // engine/vulkan/context.hpp
struct PresentationSupport;  // engine/vulkan/context.hpp

// An opened Vulkan device with a compute queue.
class GpuDevice {
 public:
  explicit GpuDevice(std::string_view name_filter = {});
  // A device whose compute queue can also present to a window (the viewer's): only devices with
  // such a queue are candidates. Throws NoWindowError when none is.
  GpuDevice(std::string_view name_filter, const PresentationSupport& presentation);
  ~GpuDevice();
  GpuDevice(const GpuDevice&) = delete;
  GpuDevice& operator=(const GpuDevice&) = delete;

  const GpuDeviceInfo& info() const;
  VulkanContext& vulkan() { return *context_; }

 private:
  std::unique_ptr<VulkanContext> context_;
};

}  // namespace vkray
