#include "engine/vulkan/context.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <mutex>

namespace vkray {
namespace {


// VKRAY_VALIDATION=1 runs vkray under the Khronos validation layer with synchronization
// validation; the test suite sets it for every test (tests/CMakeLists.txt). Any error prints the
// layer's message and aborts, so the test (or command) that caused it fails, and a debugger or core
// dump shows where. VKRAY_VALIDATION=if-installed does the same where the layer is installed and
// says once that it runs without it elsewhere (a GPU server seldom has it; the GPU report records
// which). VKRAY_VALIDATION=verbose prints warnings too: the best-practices checks are on,
// and the warnings they leave are accepted, each for its reason:
// - BestPractices-vkAllocateMemory-small-allocation and -vkBindMemory-small-dedicated-allocation:
//   every buffer has its own allocation. A scene has at most ten buffers, created once, and the
//   output buffers are reused across renders: sub-allocation would save nothing measurable.
// - BestPractices-vkCreateInstance-specialuse-extension: VK_EXT_debug_utils is a debugging
//   extension; it is enabled only in this mode, for this messenger.
constexpr const char* validation_layer = "VK_LAYER_KHRONOS_validation";

enum class Validation { off, errors, verbose, errors_if_installed };

Validation validation_mode() {
  const char* value = std::getenv("VKRAY_VALIDATION");
  if (!value || !*value || std::string_view(value) == "0") return Validation::off;
  if (std::string_view(value) == "if-installed") return Validation::errors_if_installed;
  return std::string_view(value) == "verbose" ? Validation::verbose : Validation::errors;
}

bool validation_layer_installed(const vk::raii::Context& context) {
  const auto layers = context.enumerateInstanceLayerProperties();
  return std::any_of(layers.begin(), layers.end(), [](const vk::LayerProperties& layer) {
    return std::string_view(layer.layerName.data()) == validation_layer;
  });
}

// The mode in effect: errors_if_installed becomes errors or off, the latter said once a process.
Validation effective_validation(const vk::raii::Context& context) {
  const Validation mode = validation_mode();
  if (mode != Validation::errors_if_installed) return mode;
  if (validation_layer_installed(context)) return Validation::errors;
  static std::once_flag said;
  std::call_once(said, [] {
    std::fprintf(stderr, "vkray: note: VKRAY_VALIDATION=if-installed, and the Khronos validation layer is not installed: "
                         "running without it\n");
  });
  return Validation::off;
}

// Errors of the validation layer abort; the loader's own messages (type "general", e.g. a driver
// file it cannot open, which vkray then reports in its own words) are shown in verbose mode only.
VKAPI_ATTR VkBool32 VKAPI_CALL report_validation(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                 VkDebugUtilsMessageTypeFlagsEXT types,
                                                 const VkDebugUtilsMessengerCallbackDataEXT* data, void* /*user*/) {
  const bool error = (severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT) != 0;
  const bool from_layer = (types & VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT) == 0;
  if (!from_layer && validation_mode() != Validation::verbose) return VK_FALSE;
  std::fprintf(stderr, "vkray: Vulkan validation %s: %s\n", error ? "error" : "warning", data->pMessage);
  if (error && from_layer) std::abort();
  return VK_FALSE;
}

vk::DebugUtilsMessengerCreateInfoEXT messenger_info(Validation mode) {
  vk::DebugUtilsMessageSeverityFlagsEXT severities = vk::DebugUtilsMessageSeverityFlagBitsEXT::eError;
  if (mode == Validation::verbose) severities |= vk::DebugUtilsMessageSeverityFlagBitsEXT::eWarning;
  return vk::DebugUtilsMessengerCreateInfoEXT(
      {}, severities,
      vk::DebugUtilsMessageTypeFlagBitsEXT::eGeneral | vk::DebugUtilsMessageTypeFlagBitsEXT::eValidation |
          vk::DebugUtilsMessageTypeFlagBitsEXT::ePerformance,
      report_validation);
}

vk::raii::Instance create_instance(const vk::raii::Context& context, std::vector<const char*> extension_names = {}) {
  // 1.2 lets us query VkPhysicalDeviceDriverProperties on devices that have it; a 1.1 device still
  // works (describe() checks each device's own version).
  const vk::ApplicationInfo application("vkray", 1, "vkray", 1, VK_API_VERSION_1_2);
  try {
    // Where the loader offers it, devices that implement Vulkan only in part (MoltenVK on macOS)
    // are listed too; without it such a loader lists none.
    vk::InstanceCreateFlags flags;
    const auto available = context.enumerateInstanceExtensionProperties();
    if (std::any_of(available.begin(), available.end(), [](const vk::ExtensionProperties& extension) {
          return std::string_view(extension.extensionName.data()) == VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME;
        })) {
      extension_names.push_back(VK_KHR_PORTABILITY_ENUMERATION_EXTENSION_NAME);
      flags |= vk::InstanceCreateFlagBits::eEnumeratePortabilityKHR;
    }
    const Validation mode = effective_validation(context);
    if (mode == Validation::off) {
      return vk::raii::Instance(context, vk::InstanceCreateInfo(flags, &application, {}, extension_names));
    }
    if (!validation_layer_installed(context)) {
      throw GpuError("VKRAY_VALIDATION is set, but the Khronos validation layer is missing: on Debian, "
                     "'apt-get install vulkan-validationlayers'");
    }
    const std::array enabled_features = {vk::ValidationFeatureEnableEXT::eSynchronizationValidation,
                                         vk::ValidationFeatureEnableEXT::eBestPractices};
    const char* layer_names[] = {validation_layer};
    extension_names.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    // The messenger in the chain also reports what happens while the instance is created.
    vk::StructureChain<vk::InstanceCreateInfo, vk::ValidationFeaturesEXT, vk::DebugUtilsMessengerCreateInfoEXT> chain(
        vk::InstanceCreateInfo(flags, &application, layer_names, extension_names),
        vk::ValidationFeaturesEXT(enabled_features), messenger_info(mode));
    return vk::raii::Instance(context, chain.get<vk::InstanceCreateInfo>());
  } catch (const vk::SystemError& error) {
    if (static_cast<vk::Result>(error.code().value()) == vk::Result::eErrorIncompatibleDriver) {
      throw GpuError("no Vulkan driver found by the Vulkan loader " + vulkan_loader_description() + ": " + vulkan_driver_advice());
    }
    throw GpuError(std::string("cannot start Vulkan (") + error.what() + "): " + vulkan_driver_advice());
  }
}

// The messenger for the whole life of the device (see create_instance); none without validation.
vk::raii::DebugUtilsMessengerEXT create_validation_messenger(const vk::raii::Context& context,
                                                             const vk::raii::Instance& instance) {
  const Validation mode = effective_validation(context);
  if (mode == Validation::off) return vk::raii::DebugUtilsMessengerEXT(nullptr);
  return vk::raii::DebugUtilsMessengerEXT(instance, messenger_info(mode));
}

std::string type_name(vk::PhysicalDeviceType type) {
  switch (type) {
    case vk::PhysicalDeviceType::eDiscreteGpu: return "discrete";
    case vk::PhysicalDeviceType::eIntegratedGpu: return "integrated";
    case vk::PhysicalDeviceType::eVirtualGpu: return "virtual";
    case vk::PhysicalDeviceType::eCpu: return "cpu";
    default: return "other";
  }
}

int type_rank(const std::string& type) {
  const char* order[] = {"discrete", "integrated", "virtual", "cpu", "other"};
  return static_cast<int>(std::find(std::begin(order), std::end(order), type) - std::begin(order));
}

std::string lower(std::string_view text) {
  std::string result(text);
  std::transform(result.begin(), result.end(), result.begin(), [](unsigned char c) { return std::tolower(c); });
  return result;
}

// First queue family with compute (and, when `presentation` is given, graphics for the viewer's
// overlay pass, and presentation to its window); UINT32_MAX if none.
uint32_t compute_queue_family(const vk::raii::PhysicalDevice& physical_device,
                              const PresentationSupport* presentation = nullptr, vk::Instance instance = {}) {
  const auto families = physical_device.getQueueFamilyProperties();
  for (uint32_t i = 0; i < families.size(); ++i) {
    if (!(families[i].queueFlags & vk::QueueFlagBits::eCompute)) continue;
    if (presentation && !(families[i].queueFlags & vk::QueueFlagBits::eGraphics)) continue;
    if (presentation && !presentation->can_present(instance, *physical_device, i)) continue;
    return i;
  }
  return UINT32_MAX;
}

// Whether the device's main memory (its largest device-local heap) is also host-visible and
// coherent: then the host writes and reads it directly, and staging copies would only add work.
bool main_memory_is_host_visible(const vk::PhysicalDeviceMemoryProperties& memory) {
  uint32_t main_heap = UINT32_MAX;
  for (uint32_t h = 0; h < memory.memoryHeapCount; ++h) {
    if ((memory.memoryHeaps[h].flags & vk::MemoryHeapFlagBits::eDeviceLocal) &&
        (main_heap == UINT32_MAX || memory.memoryHeaps[h].size > memory.memoryHeaps[main_heap].size)) {
      main_heap = h;
    }
  }
  for (uint32_t t = 0; t < memory.memoryTypeCount; ++t) {
    if (memory.memoryTypes[t].heapIndex == main_heap && (memory.memoryTypes[t].propertyFlags & host_access_flags) == host_access_flags) {
      return true;
    }
  }
  return false;
}

bool has_device_extension(const vk::raii::PhysicalDevice& physical_device, std::string_view name) {
  const auto extensions = physical_device.enumerateDeviceExtensionProperties();
  return std::any_of(extensions.begin(), extensions.end(),
                     [&](const vk::ExtensionProperties& extension) { return extension.extensionName.data() == name; });
}

// The device extensions the ray-query traversal takes, and whether the device has each feature it
// needs: checked, not assumed, so that a device without them walks vkray's own tree.
constexpr const char* ray_query_extensions[] = {VK_KHR_ACCELERATION_STRUCTURE_EXTENSION_NAME,
                                                VK_KHR_RAY_QUERY_EXTENSION_NAME,
                                                VK_KHR_DEFERRED_HOST_OPERATIONS_EXTENSION_NAME};

bool has_ray_queries(const vk::raii::PhysicalDevice& physical_device) {
  if (physical_device.getProperties().apiVersion < VK_API_VERSION_1_2) return false;
  for (const char* name : ray_query_extensions) {
    if (!has_device_extension(physical_device, name)) return false;
  }
  const auto features = physical_device.getFeatures2<vk::PhysicalDeviceFeatures2, vk::PhysicalDeviceVulkan12Features,
                                                     vk::PhysicalDeviceAccelerationStructureFeaturesKHR,
                                                     vk::PhysicalDeviceRayQueryFeaturesKHR>();
  return features.get<vk::PhysicalDeviceVulkan12Features>().bufferDeviceAddress &&
         features.get<vk::PhysicalDeviceAccelerationStructureFeaturesKHR>().accelerationStructure &&
         features.get<vk::PhysicalDeviceRayQueryFeaturesKHR>().rayQuery;
}

// The GPUs measured to run the triangle test's doubles faster than float's error-free fallback
// (`vkray report`, docs/gpu-reports/): NVIDIA's Hopper data-centre parts, whose float64 rate is half
// their float32 rate. By name: Vulkan tells no float64 rate.
bool runs_doubles_at_half_rate(std::string_view name) {
  for (const std::string_view measured : {"NVIDIA H100", "NVIDIA H200", "NVIDIA GH200"}) {
    if (name.starts_with(measured)) return true;
  }
  return false;
}

// VKRAY_DEVICE_OVERRIDE: a comma-separated list that makes a device present itself as a GPU would,
// so that the paths a GPU takes run on lavapipe in the test suite: `discrete` (its type: float edge
// functions, no packet walk, staging by default), `no-ray-query`, `no-float64`, `no-host-import`.
// What it cannot change stays: lavapipe's loop limit, its memory types.
void apply_device_override(GpuDeviceInfo& info) {
  const char* value = std::getenv("VKRAY_DEVICE_OVERRIDE");
  if (!value || !*value) return;
  std::string_view list(value);
  while (!list.empty()) {
    const size_t comma = list.find(',');
    const std::string_view word = list.substr(0, comma);
    if (word == "discrete") {
      info.type = "discrete";
      info.favours_packet_walk = false;
      info.fast_float64 = runs_doubles_at_half_rate(info.name);
    } else if (word == "no-ray-query") {
      info.ray_query = false;
    } else if (word == "no-host-import") {
      info.host_import_alignment = 0;
    } else if (word == "no-float64") {
      info.shader_float64 = false;
      info.fast_float64 = false;
      info.favours_packet_walk = false;
    } else {
      throw GpuError("VKRAY_DEVICE_OVERRIDE: unknown word '" + std::string(word) +
                     "' (it takes a comma-separated list of discrete, no-ray-query, no-float64, no-host-import)");
    }
    list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
  }
  info.overridden = value;
}

GpuDeviceInfo describe(const vk::raii::PhysicalDevice& physical_device) {
  const auto chain = physical_device.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceSubgroupProperties,
                                                    vk::PhysicalDeviceMaintenance3Properties>();
  const auto& properties = chain.get<vk::PhysicalDeviceProperties2>().properties;
  const auto& limits = properties.limits;
  GpuDeviceInfo info;
  info.name = properties.deviceName.data();
  const auto uuid = physical_device.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceIDProperties>()
                        .get<vk::PhysicalDeviceIDProperties>()
                        .deviceUUID;
  for (size_t k = 0; k < uuid.size(); ++k) {
    char hex[3];
    std::snprintf(hex, sizeof hex, "%02x", uuid[k]);
    info.uuid += (k == 4 || k == 6 || k == 8 || k == 10 ? "-" : "") + std::string(hex);
  }
  info.type = type_name(properties.deviceType);
  info.max_allocation_bytes = chain.get<vk::PhysicalDeviceMaintenance3Properties>().maxMemoryAllocationSize;
  // VkPhysicalDeviceDriverProperties is core in Vulkan 1.2 only.
  bool llvmpipe = info.name.starts_with("llvmpipe");
  int mesa_major = 0;  // from driverInfo, "Mesa 25.0.7 (LLVM 15.0.6)": lavapipe's driverVersion is 1
  if (properties.apiVersion >= VK_API_VERSION_1_2) {
    const auto driver = physical_device.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceDriverProperties>()
                            .get<vk::PhysicalDeviceDriverProperties>();
    info.driver = std::string(driver.driverName.data()) + " " + driver.driverInfo.data();
    llvmpipe = driver.driverID == vk::DriverId::eMesaLlvmpipe;
    const std::string_view driver_info(driver.driverInfo.data());
    if (const size_t at = driver_info.find("Mesa "); at != std::string_view::npos) {
      std::from_chars(driver_info.data() + at + 5, driver_info.data() + driver_info.size(), mesa_major);
    }
  } else {
    info.driver = "driver version " + std::to_string(properties.driverVersion);
  }
  // LP_MAX_TGSI_LOOP_ITERATIONS in Mesa's gallivm: one counter per shader invocation, shared by
  // every loop.
  if (llvmpipe) info.max_loop_iterations = 65535;
  info.api_version = std::to_string(VK_API_VERSION_MAJOR(properties.apiVersion)) + "." +
                     std::to_string(VK_API_VERSION_MINOR(properties.apiVersion)) + "." +
                     std::to_string(VK_API_VERSION_PATCH(properties.apiVersion));
  for (int k = 0; k < 3; ++k) info.max_workgroup_count[k] = limits.maxComputeWorkGroupCount[k];
  info.max_workgroup_invocations = limits.maxComputeWorkGroupInvocations;
  info.max_storage_buffer_range = limits.maxStorageBufferRange;
  info.subgroup_size = chain.get<vk::PhysicalDeviceSubgroupProperties>().subgroupSize;
  info.shader_float64 = physical_device.getFeatures().shaderFloat64 == VK_TRUE;
  info.fast_float64 = info.shader_float64 && (info.type == "cpu" || runs_doubles_at_half_rate(info.name));
  info.main_memory_host_visible = main_memory_is_host_visible(physical_device.getMemoryProperties());
  const uint32_t family = compute_queue_family(physical_device);
  const auto& subgroups = chain.get<vk::PhysicalDeviceSubgroupProperties>();
  const bool subgroup_operations =
      (subgroups.supportedStages & vk::ShaderStageFlagBits::eCompute) &&
      (subgroups.supportedOperations & vk::SubgroupFeatureFlagBits::eVote) &&
      (subgroups.supportedOperations & vk::SubgroupFeatureFlagBits::eBallot) &&
      (subgroups.supportedOperations & vk::SubgroupFeatureFlagBits::eArithmetic) &&
      (subgroups.supportedOperations & vk::SubgroupFeatureFlagBits::eShuffle);
  info.can_compute = family != UINT32_MAX && subgroup_operations;
  if (!info.can_compute) info.unusable_reason = "no compute queue, or no subgroup vote, ballot, arithmetic and shuffle";
  info.favours_packet_walk = llvmpipe && mesa_major >= 25 && info.subgroup_size == 8;
  info.ray_query = has_ray_queries(physical_device);
  if (has_device_extension(physical_device, VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME)) {
    info.host_import_alignment =
        physical_device.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>()
            .get<vk::PhysicalDeviceExternalMemoryHostPropertiesEXT>()
            .minImportedHostPointerAlignment;
  }
  if (info.ray_query) {
    const auto structures = physical_device
                                .getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceAccelerationStructurePropertiesKHR>()
                                .get<vk::PhysicalDeviceAccelerationStructurePropertiesKHR>();
    info.max_structure_primitives = structures.maxPrimitiveCount;
    info.structure_scratch_alignment = structures.minAccelerationStructureScratchOffsetAlignment;
  }
  if (info.can_compute && physical_device.getQueueFamilyProperties()[family].timestampValidBits > 0) {
    info.timestamp_period_ns = limits.timestampPeriod;
  }
  apply_device_override(info);
  return info;
}

}  // namespace

uint32_t find_memory_type(const VulkanContext& context, uint32_t type_bits, vk::MemoryPropertyFlags required,
                          vk::MemoryPropertyFlags preferred) {
  const auto& memory = context.memory_properties;
  for (const auto wanted : {required | preferred, required}) {
    for (uint32_t i = 0; i < memory.memoryTypeCount; ++i) {
      if ((type_bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & wanted) == wanted) return i;
    }
  }
  throw GpuError("no suitable Vulkan memory type for a buffer or image");
}

vk::MemoryPropertyFlags shader_memory_required(const VulkanContext& context) {
  if (context.staging) return {};
  return vk::MemoryPropertyFlagBits::eHostVisible | vk::MemoryPropertyFlagBits::eHostCoherent;
}

std::string describe_vulkan_failure(const vk::SystemError& error) {
  const auto result = static_cast<vk::Result>(error.code().value());
  switch (result) {
    case vk::Result::eErrorOutOfDeviceMemory:
    case vk::Result::eErrorOutOfHostMemory:
      return std::string("out of ") + (result == vk::Result::eErrorOutOfDeviceMemory ? "device" : "host") +
             " memory: the scene or the image is too large for this device; try a smaller image (--width, "
             "--height) or another device (--device) (" + error.what() + ")";
    case vk::Result::eErrorDeviceLost:
      return std::string("the device was lost (its driver reset it or it stopped responding); run again, or "
                         "use another device (--device) (") + error.what() + ")";
    default:
      return error.what();
  }
}

std::vector<GpuDeviceInfo> list_gpu_devices() {
  return with_vulkan_errors("listing Vulkan devices", [] {
    vk::raii::Context context(vulkan_loader_entry());
    const vk::raii::Instance instance = create_instance(context);
    std::vector<GpuDeviceInfo> devices;
    for (const auto& physical_device : vk::raii::PhysicalDevices(instance)) devices.push_back(describe(physical_device));
    return devices;
  });
}

size_t choose_gpu_device(const std::vector<GpuDeviceInfo>& devices, std::string_view name_filter) {
  if (devices.empty()) throw GpuError(std::string("no Vulkan device found: ") + vulkan_driver_advice());
  // By index or UUID, as `vkray info` prints them: that device or none.
  const bool is_index = !name_filter.empty() && name_filter.size() < 6 &&
                        std::all_of(name_filter.begin(), name_filter.end(), [](unsigned char c) { return std::isdigit(c); });
  for (size_t i = 0; i < devices.size(); ++i) {
    const bool named = is_index ? std::to_string(i) == name_filter : lower(devices[i].uuid) == lower(name_filter);
    if (!named) continue;
    if (!devices[i].can_compute) {
      throw GpuError("Vulkan device " + std::string(name_filter) + " ('" + devices[i].name + "') cannot be used: " +
                     devices[i].unusable_reason);
    }
    return i;
  }
  if (is_index) {
    throw GpuError("no Vulkan device number " + std::string(name_filter) + ": this machine has " +
                   std::to_string(devices.size()) + ", numbered from 0 as `vkray info` lists them");
  }
  size_t best = devices.size();
  for (size_t i = 0; i < devices.size(); ++i) {
    if (!devices[i].can_compute) continue;
    if (!name_filter.empty()) {
      if (lower(devices[i].name).find(lower(name_filter)) != std::string::npos) return i;
    } else if (best == devices.size() || type_rank(devices[i].type) < type_rank(devices[best].type)) {
      best = i;
    }
  }
  if (best == devices.size()) {
    std::string names;
    for (const auto& device : devices) {
      if (!names.empty()) names += ", ";
      names += "'" + device.name + "'" + (device.can_compute ? "" : " (" + device.unusable_reason + ")");
    }
    throw GpuError(name_filter.empty() ? "no usable Vulkan device among " + names
                                       : "no usable Vulkan device named like '" + std::string(name_filter) + "'; found " + names);
  }
  return best;
}

void VulkanContext::submit_and_wait(const std::function<void(const vk::raii::CommandBuffer&)>& record) {
  check_usable();
  command_pool.reset();  // the pool's one command buffer, recorded anew for every submission
  command_buffer.begin(vk::CommandBufferBeginInfo(vk::CommandBufferUsageFlagBits::eOneTimeSubmit));
  record(command_buffer);
  command_buffer.end();
  device.resetFences(*fence);
  const vk::CommandBuffer buffers[] = {*command_buffer};
  queue.submit(vk::SubmitInfo({}, {}, buffers), *fence);
  const vk::Result waited = device.waitForFences(*fence, VK_TRUE, fence_timeout_ns);
  if (waited == vk::Result::eSuccess) return;
  if (waited != vk::Result::eTimeout) throw GpuError("waiting for the GPU failed: " + vk::to_string(waited));
  timed_out = true;
  // A grace before the objects the work uses are destroyed while the error unwinds: work that only
  // overran its time ends here, and nothing is destroyed under it. As long as the default timeout:
  // 2 s was too short for lavapipe under AddressSanitizer with another test beside it (given rays of
  // the report's, VKRAY_FENCE_TIMEOUT_MS=1: the validation layer saw a buffer destroyed in use).
  constexpr uint64_t grace_ns = default_fence_timeout_ms * 1'000'000;
  (void)device.waitForFences(*fence, VK_TRUE, grace_ns);
  throw DeviceLostError("the GPU did not finish a submission within " + std::to_string(fence_timeout_ns / 1'000'000) +
                        " ms (VKRAY_FENCE_TIMEOUT_MS): a shader that never ends, or work far over its dispatch "
                        "budget; the device is treated as lost");
}

void VulkanContext::check_usable() const {
  if (timed_out) throw DeviceLostError("the device did not finish earlier work in time; nothing more runs on it");
}

uint64_t fence_timeout_from_environment() {
  const char* value = std::getenv("VKRAY_FENCE_TIMEOUT_MS");
  if (!value || !*value) return default_fence_timeout_ms * 1'000'000;
  uint64_t ms = 0;
  const std::string_view text(value);
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), ms);
  if (error != std::errc() || end != text.data() + text.size() || ms == 0 || ms > UINT64_MAX / 1'000'000) {
    throw GpuError("VKRAY_FENCE_TIMEOUT_MS is '" + std::string(text) + "': it takes a whole number of milliseconds, at least 1");
  }
  return ms * 1'000'000;
}

namespace {

TransferMode resolve_transfer(TransferMode requested, const GpuDeviceInfo& info) {
  if (requested != TransferMode::automatic) return requested;
  if (const char* forced = std::getenv("VKRAY_TRANSFER"); forced && *forced) {
    if (std::string_view(forced) == "staging") return TransferMode::staging;
    if (std::string_view(forced) == "direct") return TransferMode::direct;
    throw GpuError("VKRAY_TRANSFER is '" + std::string(forced) + "': it takes staging or direct");
  }
  return automatic_transfer(info).mode;
}

// "memory type 4: device-local, host-visible, coherent".
std::string describe_memory_type(const vk::PhysicalDeviceMemoryProperties& memory, uint32_t type) {
  const auto flags = memory.memoryTypes[type].propertyFlags;
  std::string words;
  for (const auto& [bit, name] : {std::pair{vk::MemoryPropertyFlagBits::eDeviceLocal, "device-local"},
                                  {vk::MemoryPropertyFlagBits::eHostVisible, "host-visible"},
                                  {vk::MemoryPropertyFlagBits::eHostCoherent, "coherent"},
                                  {vk::MemoryPropertyFlagBits::eHostCached, "cached"}}) {
    if (flags & bit) words += std::string(words.empty() ? "" : ", ") + name;
  }
  return "memory type " + std::to_string(type) + ": " + (words.empty() ? "no flags" : words);
}


void open_device(VulkanContext& vk_context, std::string_view name_filter, const PresentationSupport* presentation,
                 TransferMode transfer) {
  with_vulkan_errors("opening the Vulkan device", [&] {
    vk_context.instance =
        create_instance(vk_context.context, presentation ? presentation->instance_extensions : std::vector<const char*>{});
    vk_context.validation_messenger = create_validation_messenger(vk_context.context, vk_context.instance);
    vk::raii::PhysicalDevices physical_devices(vk_context.instance);
    std::vector<GpuDeviceInfo> infos;
    for (const auto& physical_device : physical_devices) {
      infos.push_back(describe(physical_device));
      // A device that cannot present is no candidate for a window.
      if (presentation && infos.back().can_compute &&
          compute_queue_family(physical_device, presentation, *vk_context.instance) == UINT32_MAX) {
        infos.back().can_compute = false;
        infos.back().unusable_reason = "no queue of it presents to this display (with compute and graphics)";
      }
    }
    size_t chosen = 0;
    try {
      chosen = choose_gpu_device(infos, name_filter);
    } catch (const GpuError& error) {
      if (!presentation) throw;
      throw NoWindowError(std::string("no Vulkan device presents to this display (") + error.what() + ")");
    }
    vk_context.physical_device = std::move(physical_devices[chosen]);
    vk_context.info = infos[chosen];
    vk_context.limits = vk_context.physical_device.getProperties().limits;
    vk_context.memory_properties = vk_context.physical_device.getMemoryProperties();
    vk_context.staging = resolve_transfer(transfer, vk_context.info) == TransferMode::staging;
    vk_context.queue_family = compute_queue_family(vk_context.physical_device, presentation, *vk_context.instance);
    // Timestamps as the queue in use has them (the viewer's may be another family than describe's).
    if (vk_context.physical_device.getQueueFamilyProperties()[vk_context.queue_family].timestampValidBits == 0) {
      vk_context.info.timestamp_period_ns = 0.0;
    } else {
      vk_context.info.timestamp_period_ns = vk_context.limits.timestampPeriod;
    }

    const float priority = 1.0f;
    const vk::DeviceQueueCreateInfo queue_info({}, vk_context.queue_family, 1, &priority);
    std::vector<const char*> device_extensions;
    if (presentation) device_extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
    // A device that implements Vulkan in part must be opened with this extension (its spec's rule).
    if (has_device_extension(vk_context.physical_device, "VK_KHR_portability_subset")) {
      device_extensions.push_back("VK_KHR_portability_subset");
    }
    // Results copied straight into host memory vkray already has (engine/vulkan/host_import.hpp).
    if (vk_context.info.host_import_alignment > 0) device_extensions.push_back(VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME);
    // float64 arithmetic, where the device has it, for the `--precision double` shader; ray queries
    // where it has them, for the ray-query traversal.
    vk::StructureChain<vk::PhysicalDeviceFeatures2, vk::PhysicalDeviceVulkan12Features,
                       vk::PhysicalDeviceAccelerationStructureFeaturesKHR, vk::PhysicalDeviceRayQueryFeaturesKHR>
        features;
    features.get<vk::PhysicalDeviceFeatures2>().features.shaderFloat64 = vk_context.info.shader_float64 ? VK_TRUE : VK_FALSE;
    if (vk_context.info.ray_query) {
      device_extensions.insert(device_extensions.end(), std::begin(ray_query_extensions), std::end(ray_query_extensions));
      features.get<vk::PhysicalDeviceVulkan12Features>().bufferDeviceAddress = VK_TRUE;
      features.get<vk::PhysicalDeviceAccelerationStructureFeaturesKHR>().accelerationStructure = VK_TRUE;
      features.get<vk::PhysicalDeviceRayQueryFeaturesKHR>().rayQuery = VK_TRUE;
    } else {
      features.unlink<vk::PhysicalDeviceAccelerationStructureFeaturesKHR>();
      features.unlink<vk::PhysicalDeviceRayQueryFeaturesKHR>();
      // Vulkan 1.1 devices know no Vulkan12Features structure.
      features.unlink<vk::PhysicalDeviceVulkan12Features>();
    }
    vk_context.device = vk::raii::Device(
        vk_context.physical_device,
        vk::DeviceCreateInfo({}, queue_info, {}, device_extensions, nullptr, &features.get<vk::PhysicalDeviceFeatures2>()));
    vk_context.queue = vk::raii::Queue(vk_context.device, vk_context.queue_family, 0);
    vk_context.command_pool = vk::raii::CommandPool(
        vk_context.device, vk::CommandPoolCreateInfo(vk::CommandPoolCreateFlagBits::eTransient, vk_context.queue_family));
    vk_context.command_buffer = std::move(vk::raii::CommandBuffers(
        vk_context.device,
        vk::CommandBufferAllocateInfo(*vk_context.command_pool, vk::CommandBufferLevel::ePrimary, 1))[0]);
    vk_context.fence = vk::raii::Fence(vk_context.device, vk::FenceCreateInfo());
    vk_context.fence_timeout_ns = fence_timeout_from_environment();
    // The memory the shaders' buffers take (create_storage_buffer), read off a small one: what the
    // transfer really is, for `vkray info`, the bench and the GPU report.
    const vk::raii::Buffer probe(vk_context.device, vk::BufferCreateInfo({}, 16, vk::BufferUsageFlagBits::eStorageBuffer));
    vk_context.shader_memory = describe_memory_type(
        vk_context.memory_properties,
        find_memory_type(vk_context, probe.getMemoryRequirements().memoryTypeBits, shader_memory_required(vk_context),
                         vk::MemoryPropertyFlagBits::eDeviceLocal));
    vk_context.pipeline_cache = std::make_unique<PipelineCache>(
        vk_context.device, vk_context.physical_device.getProperties(), pipeline_cache_folder());
  });
}

}  // namespace

GpuDevice::GpuDevice(std::string_view choice, TransferMode transfer) : context_(std::make_unique<VulkanContext>()) {
  open_device(*context_, choice, nullptr, transfer);
}

GpuDevice::GpuDevice(std::string_view choice, const PresentationSupport& presentation, TransferMode transfer)
    : context_(std::make_unique<VulkanContext>()) {
  open_device(*context_, choice, &presentation, transfer);
}

TransferMode GpuDevice::transfer() const { return context_->staging ? TransferMode::staging : TransferMode::direct; }

std::string GpuDevice::transfer_description() const {
  return std::string(context_->staging ? "staging" : "direct") + " (shaders' buffers in " + context_->shader_memory + ")";
}

bool GpuDevice::validation() const { return static_cast<bool>(*context_->validation_messenger); }

TransferChoice automatic_transfer(const GpuDeviceInfo& device) {
  if (!device.main_memory_host_visible) return {TransferMode::staging, "its main memory is not host-visible"};
  if (device.type == "discrete") {
    return {TransferMode::staging, "a discrete GPU: the host would read its memory uncached across the bus"};
  }
  return {TransferMode::direct, "its main memory is the host's and host-visible"};
}

GpuDevice::~GpuDevice() = default;

const GpuDeviceInfo& GpuDevice::info() const { return context_->info; }

std::filesystem::path GpuDevice::pipeline_cache_file() const { return context_->pipeline_cache->file(); }

size_t GpuDevice::pipeline_cache_bytes_read() const { return context_->pipeline_cache->bytes_read(); }

}  // namespace vkray
