#include "cli/device_options.hpp"

#include "engine/render/search.hpp"

#include <cstdio>
#include <set>

namespace vkray::cli {

TransferMode DeviceOptions::transfer_mode() const {
  if (transfer == "staging") return TransferMode::staging;
  if (transfer == "direct") return TransferMode::direct;
  return TransferMode::automatic;
}

CLI::Option* add_device_options(CLI::App* command, DeviceOptions& options) {
  CLI::Option* device = command->add_option(
      "--device", options.device,
      "The Vulkan device: its number or UUID as 'vkray info' prints them, or text its name contains");
  command
      ->add_option("--transfer", options.transfer,
                   "How data reaches the device: staging (host buffers and device copies, what discrete GPUs "
                   "need), direct (the device reads host-mapped memory), or auto (what its memory types suggest)")
      ->check(CLI::IsMember({"auto", "staging", "direct"}))
      ->capture_default_str();
  return device;
}

void add_traversal_option(CLI::App* command, std::string& traversal) {
  command
      ->add_option("--traversal", traversal,
                   "How rays find the primitives: " + traversal_names() +
                       " (auto: per ray with instances; else brute force for a handful, packets on llvmpipe from Mesa 25, per ray elsewhere)")
      ->check([](const std::string& name) {
        return traversal_from_name(name) ? std::string()
                                         : "unknown traversal '" + name + "' (choose from " + traversal_names() + ")";
      })
      ->capture_default_str();
}

void add_mask_option(CLI::App* command, uint32_t& mask) {
  command
      ->add_option("--mask", mask,
                   "The rays' mask, 1..255: they hit only the meshes, spheres and planes whose \"mask\" in the scene "
                   "file shares a bit with it (a layer left out of a view)")
      ->check(CLI::Range(1, 255))
      ->capture_default_str();
}

void print_mask_note(const Scene& scene, uint32_t mask) {
  std::set<uint32_t> masks;
  for (const Mask drawn : drawn_masks(scene)) {  // an instanced mesh's instances' in place of its own
    if (mask_hits(drawn, static_cast<Mask>(mask))) return;
    masks.insert(drawn);
  }
  if (masks.empty()) return;
  std::string listed;
  for (const uint32_t object_mask : masks) listed += (listed.empty() ? "" : ", ") + std::to_string(object_mask);
  std::fprintf(stderr, "vkray: note: --mask %u shares no bit with the mask of any object of the scene (%s): every ray misses\n",
               mask, listed.c_str());
}

void print_cpu_device_note(const GpuDeviceInfo& device) {
  if (const std::string note = cpu_device_note(device); !note.empty()) std::fprintf(stderr, "%s\n", note.c_str());
}

}  // namespace vkray::cli
