#include "cli/commands.hpp"
#include "cli/device_options.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/render/gpu_scene.hpp"

#include <iostream>
#include <memory>
#include <string>

namespace vkray::cli {

Action add_info_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand("info", "List the Vulkan devices, the one vkray would use, and its limits.");
  auto device_filter = std::make_shared<std::string>();
  command->add_option("--device", *device_filter,
                      "Show which device a number, a UUID or a name (substring, any case) picks");
  return [device_filter] {
    const auto devices = list_gpu_devices();
    const size_t chosen = choose_gpu_device(devices, *device_filter);
    for (size_t i = 0; i < devices.size(); ++i) {
      const GpuDeviceInfo& d = devices[i];
      std::cout << (i == chosen ? "* " : "  ") << "[" << i << "] " << d.name << " (" << d.type << ", Vulkan "
                << d.api_version << ", " << d.driver << ")" << (d.can_compute ? "" : " - unusable: " + d.unusable_reason) << '\n'
                << "      UUID " << d.uuid << '\n';
    }
    const GpuDeviceInfo& d = devices[chosen];
    std::cout << "\nvkray uses [" << chosen << "] " << d.name << '\n'
              << "  max workgroup count        " << d.max_workgroup_count[0] << " x " << d.max_workgroup_count[1]
              << " x " << d.max_workgroup_count[2] << '\n'
              << "  max workgroup invocations  " << d.max_workgroup_invocations << '\n'
              << "  max storage buffer range   " << d.max_storage_buffer_range << " bytes ("
              << (d.max_storage_buffer_range >> 20) << " MiB)\n"
              << "  max allocation size        " << (d.max_allocation_bytes >> 20) << " MiB\n"
              << "  subgroup size              " << d.subgroup_size << '\n'
              << "  timestamps                 "
              << (d.timestamp_period_ns > 0.0 ? std::to_string(d.timestamp_period_ns) + " ns per tick" : "none") << '\n'
              << "  shaderFloat64              " << (d.shader_float64 ? "yes" : "no")
              << (d.fast_float64 ? " (fast: triangle edge functions in double)" : "") << '\n'
              << "  --transfer auto            " << (automatic_transfer(d).mode == TransferMode::direct ? "direct" : "staging")
              << " (" << automatic_transfer(d).reason << ")\n"
              << "  transfer as opened         " << GpuDevice(std::to_string(chosen)).transfer_description() << '\n'
              << "  ray queries                "
              << (d.ray_query ? "yes (--traversal ray-query)" : "no") << '\n'
              << "  host memory import         "
              << (d.host_import_alignment > 0 ? "yes (staging copies results straight into the frame)" : "no") << '\n'
              << "  tree walk                  "
              << (d.favours_packet_walk ? "packets of 8x8 camera rays (llvmpipe from Mesa 25 on)" : "per ray") << '\n';
    std::cout << "  Vulkan loader              " << vulkan_loader_description() << '\n';
    const std::filesystem::path cache = pipeline_cache_folder();
    std::cout << "  pipeline cache folder      "
              << (cache.empty() ? std::string("none (VKRAY_CACHE_DIR=off)") : cache.string()) << '\n';
    if (!d.overridden.empty()) std::cout << "  described as overridden by VKRAY_DEVICE_OVERRIDE=" << d.overridden << '\n';
    print_cpu_device_note(d);
    const GeometryLayout layout;
    std::cout << "\ngeometry on the device, bytes (render --timings gives a scene's bytes a triangle)\n"
              << "  a triangle or tree sphere  " << layout.primitive_slot << " + a normal of " << layout.normal_float32
              << " (" << layout.normal_float64 << " with --precision double)\n"
              << "  a distinct vertex          " << layout.vertex << " (position in two float parts, or a double)\n"
              << "  a tree node                " << layout.tree_node << " (two children's boxes)\n";
    return 0;
  };
}

}  // namespace vkray::cli
