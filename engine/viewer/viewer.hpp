// `vkray view`: a window showing one output of the scene as `vkray render` computes it, with a
// camera moved by mouse and keys. No Vulkan or GLFW type appears here: the CLI calls run_viewer.
#pragma once

#include "engine/scene/camera.hpp"
#include "engine/frame.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/render/gpu_scene.hpp"
#include "engine/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace vkray {

struct ViewerOptions {
  // Loads the scene (again when `watched` changes); throws InputError naming the file.
  std::function<Scene()> load_scene;
  // The scene file, reloaded when it changes on disk; empty for the built-in scene.
  std::filesystem::path watched;
  std::string title;               // the window's, after "vkray: "
  uint32_t width = 0, height = 0;  // the window's first size; 0: the scene's image size
  std::string device;              // as --device
  TransferMode transfer = TransferMode::automatic;
  PrimitiveSearch traversal = PrimitiveSearch::automatic;  // as --traversal
  Mask mask = every_mask_bit;                               // the rays', as --mask
  bool vsync = true;
  Aov output = Aov::depth;  // shown first; keys 1, 2, 3 switch
  bool overlay = true;
  // Frames to present before quitting, each rendered anew (0: until the window closes). With
  // `spin_degrees`, the camera orbits that much each frame: a benchmark.
  uint32_t frames = 0;
  double spin_degrees = 0.0;
  // Where to save what was presented last, as PNG, when the viewer quits.
  std::optional<std::filesystem::path> screenshot;
  bool stats = false;  // print frame and dispatch counts on exit
  // Called once the device is chosen (the command line says there when it is a CPU implementation).
  std::function<void(const GpuDeviceInfo&)> on_device;
};

// Runs the viewer until the window is closed (or `frames` are shown). Throws NoWindowError (a
// GpuError) when there is no display or no device presents to it, InputError when the first
// scene cannot be loaded.
void run_viewer(const ViewerOptions& options);

}  // namespace vkray
