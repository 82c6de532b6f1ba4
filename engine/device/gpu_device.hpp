// The GPU as the rest of the program sees it: which Vulkan devices exist, which one is used, and
// an opened device to render with. No Vulkan type appears here, so the CLI never touches Vulkan.
#pragma once

#include <cstdint>
#include <filesystem>
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

// The device stopped responding or its driver reset it (VK_ERROR_DEVICE_LOST): nothing more can be
// done with it, so a bench stops rather than going on to its next row.
class DeviceLostError : public GpuError {
 public:
  using GpuError::GpuError;
};

// No window can be shown: no display, or no device presents to it (the viewer). The message
// names the headless alternative.
class NoWindowError : public GpuError {
 public:
  explicit NoWindowError(const std::string& reason)
      : GpuError("cannot open a window: " + reason + "; 'vkray render' renders without one") {}
};

// How scene data reaches the device and results come back (`--transfer`). direct: the shaders'
// buffers are memory the host maps (device-local where a type is also host-visible and coherent,
// else host memory the device reads across the bus); staging: device-local buffers filled and read
// through host buffers and copies on the device. automatic: see automatic_transfer; the environment
// variable VKRAY_TRANSFER (staging or direct) overrides it, which is how the test suite runs every
// path on lavapipe.
enum class TransferMode { automatic, staging, direct };

struct GpuDeviceInfo {
  std::string name;
  std::string uuid;  // VkPhysicalDeviceIDProperties::deviceUUID as 8-4-4-4-12 hex digits
  std::string type;  // "discrete", "integrated", "virtual", "cpu" or "other"
  std::string driver;
  std::string api_version;
  // A compute queue, and subgroup vote, ballot, arithmetic and shuffle operations in compute shaders:
  // the ray-casting modules declare them (the packet walk, the viewer's depth range), so a device
  // without them cannot create its pipeline. Every Vulkan 1.1 desktop driver and lavapipe have them.
  bool can_compute = false;
  std::string unusable_reason;  // why not, where it cannot
  uint32_t max_workgroup_count[3] = {0, 0, 0};
  uint32_t max_workgroup_invocations = 0;
  uint64_t max_storage_buffer_range = 0;
  uint64_t max_allocation_bytes = 0;
  uint32_t subgroup_size = 0;
  double timestamp_period_ns = 0.0;  // 0: the compute queue has no timestamps
  bool shader_float64 = false;
  // Doubles cost the triangle test less than float's error-free fallback: CPU devices with
  // shaderFloat64, and the GPUs measured so (data-centre GPUs that run doubles at half the float
  // rate: an H200 took 0.63 against 0.68 ms for the bunny at 3840x2160 in `vkray report`; consumer
  // GPUs run doubles at 1/32 to 1/64 of it). Chooses double edge functions (EdgeArithmetic).
  bool fast_float64 = false;
  // Its largest device-local memory heap is also host-visible: TransferMode::automatic is direct.
  bool main_memory_host_visible = false;
  // Loop iterations a shader invocation may run before the driver silently stops it: llvmpipe
  // (lavapipe) caps them at 65535 in total; 0 for no known limit.
  uint64_t max_loop_iterations = 0;
  // The packet walk (shaders/packet_walk.glsl) is the faster tree walk here: llvmpipe from Mesa 25
  // on, with subgroups of 8, where a constant-lane broadcast is one vector shuffle (the bunny at
  // 1920x1080: 36 against 149 ms per ray). Mesa 22.3 runs subgroup operations as loops over the
  // lanes (239 against 145 ms), and no GPU has measured it yet.
  bool favours_packet_walk = false;
  // Ray queries from compute shaders (VK_KHR_ray_query with VK_KHR_acceleration_structure and
  // buffer device addresses, Vulkan 1.2): what the ray-query traversal needs. With it, the largest
  // number of triangles (or boxes) one bottom-level structure may hold, and the alignment of build
  // scratch memory.
  bool ray_query = false;
  uint64_t max_structure_primitives = 0;
  uint32_t structure_scratch_alignment = 0;
  // VK_EXT_external_memory_host: the alignment of host memory the device imports, so that staging
  // copies results straight into a frame's planes (engine/vulkan/host_import.hpp); 0 without it.
  uint64_t host_import_alignment = 0;
  // VKRAY_DEVICE_OVERRIDE as it changed this description (engine/vulkan/context.cpp); empty: as the driver says.
  std::string overridden;
};

// What TransferMode::automatic takes on `device`, and why in a few words: direct where its main
// memory is the host's (integrated GPUs, lavapipe) and host-visible, staging elsewhere, also on a
// discrete GPU whose memory is host-visible (resizable BAR), since the host's reads of it are
// uncached across the bus.
struct TransferChoice {
  TransferMode mode;
  const char* reason;
};
TransferChoice automatic_transfer(const GpuDeviceInfo& device);

// Every Vulkan device, in enumeration order. Throws GpuError when Vulkan itself is unavailable.
std::vector<GpuDeviceInfo> list_gpu_devices();

// Index into `devices` of the one vkray uses: when `choice` is empty, the first discrete GPU, else
// integrated, virtual, then CPU (lavapipe); otherwise the device at that index (`vkray info`
// numbers them from 0), the one with that UUID, or the first whose name contains `choice`, ignoring
// case. Throws GpuError when none fits.
size_t choose_gpu_device(const std::vector<GpuDeviceInfo>& devices, std::string_view choice);

// One line for stderr when `device` is a CPU implementation of Vulkan (lavapipe, SwiftShader):
// rendering there is the CPU's speed, so the user should know, and why no GPU was used when one
// seems present (a GPU device node without a Vulkan driver for it, or an NVIDIA container without
// the graphics capability). Empty for any other device.
std::string cpu_device_note(const GpuDeviceInfo& device);

// The Vulkan loader in use, in words: its file and whether it is the machine's or a bundle's copy
// (engine/vulkan/loader.hpp); "none (...)" where there is none.
std::string vulkan_loader_description();

// What to do when Vulkan lists no driver, in a sentence: where an NVIDIA driver's manifest lies
// outside the loader's search path (a container's /usr/local/nvidia), point VK_DRIVER_FILES at it;
// otherwise install one (lavapipe always works).
std::string vulkan_driver_advice();

// Where pipelines compiled by the driver are kept between runs (engine/vulkan/pipeline_cache.hpp):
// VKRAY_CACHE_DIR when set ("off": nowhere), else $XDG_CACHE_HOME/vkray, else $HOME/.cache/vkray
// (the XDG base directory rule); empty when none can be named.
std::filesystem::path pipeline_cache_folder();

struct VulkanContext;        // engine/vulkan/context.hpp
struct PresentationSupport;  // engine/vulkan/context.hpp

// An opened Vulkan device with a compute queue.
class GpuDevice {
 public:
  // `choice` as choose_gpu_device takes it.
  explicit GpuDevice(std::string_view choice = {}, TransferMode transfer = TransferMode::automatic);
  // A device whose compute queue can also present to a window (the viewer's): only devices with
  // such a queue are candidates. Throws NoWindowError when none is.
  GpuDevice(std::string_view choice, const PresentationSupport& presentation,
            TransferMode transfer = TransferMode::automatic);
  ~GpuDevice();
  GpuDevice(const GpuDevice&) = delete;
  GpuDevice& operator=(const GpuDevice&) = delete;

  const GpuDeviceInfo& info() const;
  // staging or direct, as chosen when the device opened.
  TransferMode transfer() const;
  // That, and the memory type the shaders' buffers take: "staging (shaders' buffers in memory type 1: device-local)".
  std::string transfer_description() const;
  // Whether the Khronos validation layer checks this device's calls (VKRAY_VALIDATION).
  bool validation() const;
  VulkanContext& vulkan() { return *context_; }
  // The device's pipeline cache file (empty: none), and how many bytes of it the driver was given
  // when the device opened (0: every pipeline is compiled from scratch).
  std::filesystem::path pipeline_cache_file() const;
  size_t pipeline_cache_bytes_read() const;

 private:
  std::unique_ptr<VulkanContext> context_;
};

}  // namespace vkray
