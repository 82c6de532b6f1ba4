#include "cli/commands.hpp"
#include "cli/device_options.hpp"
#include "cli/scene_argument.hpp"
#include "engine/scene/scene_or_model.hpp"
#include "engine/io/image_io.hpp"
#include "engine/viewer/viewer.hpp"

#include <memory>
#include <optional>
#include <tuple>

namespace vkray::cli {
namespace {

struct ViewCommandOptions {
  std::string scene_path;
  std::optional<std::string> size;
  std::optional<std::string> camera;
  std::optional<std::string> view;
  std::string output = "depth";
  DeviceOptions device_options;
  std::string traversal = "auto";
  uint32_t mask = every_mask_bit;
  bool no_vsync = false;
  bool no_overlay = false;
  uint32_t frames = 0;
  double spin = 0.0;
  std::optional<std::string> screenshot;
  bool stats = false;
};

int run_view(const ViewCommandOptions& options) {
  ViewerOptions viewer;
  std::optional<uint32_t> width, height;
  if (options.size) std::tie(width, height) = parse_size(*options.size);
  const auto output = aov_from_name(options.output);
  if (!output || !AovSet{*output}.device_outputs_only()) {
    throw InputError("--output: '" + options.output + "' is not an output the viewer shows (choose from depth, normal, uv)");
  }
  if (options.screenshot && lower_extension(*options.screenshot) != ".png") {
    throw InputError("--screenshot: '" + *options.screenshot + "' must end in .png (what the window shows, 8 bits)");
  }
  if (options.screenshot) check_output_path(*options.screenshot);
  viewer.load_scene = [options, width, height] {
    Scene scene = load_scene_argument(options.scene_path, width, height, options.view);
    print_mask_note(scene, options.mask);
    if (options.camera) apply_camera_option(*options.camera, scene.camera);
    check_scene_camera(scene, options.camera.has_value(), options.scene_path);
    if (scene.camera.projection != Projection::perspective) {
      throw InputError(std::string("the viewer draws perspective cameras; `vkray render` writes ") +
                       projection_name(scene.camera.projection) + " ones");
    }
    return scene;
  };
  viewer.watched = options.scene_path;
  viewer.title = options.scene_path.empty() ? "built-in scene" : options.scene_path;
  viewer.device = options.device_options.device;
  viewer.transfer = options.device_options.transfer_mode();
  viewer.traversal = *traversal_from_name(options.traversal);
  viewer.mask = static_cast<Mask>(options.mask);
  viewer.on_device = print_cpu_device_note;
  viewer.vsync = !options.no_vsync;
  viewer.output = *output;
  viewer.overlay = !options.no_overlay;
  viewer.frames = options.frames;
  viewer.spin_degrees = options.spin;
  if (options.screenshot) viewer.screenshot = *options.screenshot;
  viewer.stats = options.stats;
  run_viewer(viewer);
  return 0;
}

}  // namespace

Action add_view_command(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "view", "Show a scene (or the built-in one) in a window, rendered as 'render' does, with a movable camera.");
  auto options = std::make_shared<ViewCommandOptions>();
  command->add_option("scene", options->scene_path,
                      "Scene file (.json, reloaded when it changes) or model (.obj, .ply, .gltf, .glb); the built-in scene when omitted");
  command->add_option("--size", options->size, "Window size WIDTHxHEIGHT (default: the scene's image size)");
  command->add_option("--view", options->view,
                      "Frame the scene from a side: front, back, left, right, top, bottom, or the direction X,Y,Z from "
                      "its centre to the eye");
  command->add_option("--camera", options->camera,
                      "Override the camera: 'from=X,Y,Z to=X,Y,Z up=X,Y,Z fovy=DEGREES' (any of the keys), or the "
                      "scene file's camera as JSON '{\"from\": [0, 1, 5]}'");
  command->add_option("--output", options->output, "Output shown first: depth, normal, uv")
      ->capture_default_str();
  add_device_options(command, options->device_options);
  add_traversal_option(command, options->traversal);
  add_mask_option(command, options->mask);
  command->add_flag("--no-vsync", options->no_vsync, "Present without waiting for the display's refresh");
  command->add_flag("--no-overlay", options->no_overlay, "Show the picture alone, without the text overlay");
  command->add_option("--frames", options->frames, "Quit after presenting N frames, each rendered anew (benchmarks, tests)");
  command->add_option("--spin", options->spin, "Orbit the camera this many degrees every frame (with --frames: a benchmark)");
  command->add_option("--screenshot", options->screenshot, "On quitting, save what was presented last as this PNG");
  command->add_flag("--stats", options->stats, "On quitting, print frames presented, renders dispatched and frames/s");
  return [options] { return run_view(*options); };
}

}  // namespace vkray::cli
