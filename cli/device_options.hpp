// The options every command that opens a device shares: which device, how data reaches it, how rays
// find the primitives and which they see (--mask).
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/scene/scene.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace vkray::cli {

struct DeviceOptions {
  std::string device;           // as choose_gpu_device takes it
  std::string transfer = "auto";
  TransferMode transfer_mode() const;
};

// Adds --device and --transfer to `command`; returns --device (for options that exclude it).
CLI::Option* add_device_options(CLI::App* command, DeviceOptions& options);

// Adds --traversal (render, view): how rays find the primitives, by traversal_from_name's names.
void add_traversal_option(CLI::App* command, std::string& traversal);
// --mask: the rays' mask (Renderer::set_ray_mask), 1..255.
void add_mask_option(CLI::App* command, uint32_t& mask);
// Prints a note on stderr where --mask `mask` hides every object of `scene`: its image would be all
// misses, most likely a mistyped mask.
void print_mask_note(const Scene& scene, uint32_t mask);

// Prints cpu_device_note for `device` on stderr, when it has one.
void print_cpu_device_note(const GpuDeviceInfo& device);

}  // namespace vkray::cli
