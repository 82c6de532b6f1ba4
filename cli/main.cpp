// vkray: ray-cast a scene on the GPU (Vulkan compute) into depth and normal images.
// Exit codes: 0 success, 2 usage or input errors, 1 runtime failures (no Vulkan device, I/O).
#include "cli/commands.hpp"
#include "engine/device/gpu_device.hpp"
#include "engine/io/image_io.hpp"
#include "engine/typed_names.hpp"
#include "engine/scene/scene.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <iostream>

#ifndef VKRAY_VERSION
#error "VKRAY_VERSION comes from CMake"
#endif

namespace {

// Ctrl-C (or a kill) ends vkray at once, wherever it is: only the temporary files of outputs being
// written are removed, so no half-written image is left behind, and the exit code is 128 + the
// signal (130 for Ctrl-C), as shells expect.
extern "C" void end_on_signal(int signal) {
  vkray::remove_partial_outputs();
  _exit(128 + signal);
}

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = end_on_signal;
  sigemptyset(&action.sa_mask);
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
  // A reader of what vkray prints that went away (`vkray ... | head -1`) is no reason to die in the
  // middle: the write to it fails, and the files vkray writes are finished all the same.
  signal(SIGPIPE, SIG_IGN);
}

}  // namespace

int main(int argc, char** argv) {
  install_signal_handlers();
  CLI::App app("vkray: a Vulkan compute raycaster that writes per-pixel depth and normal images.", "vkray");
  app.set_version_flag("--version", "vkray " VKRAY_VERSION);
  app.require_subcommand(1);
  app.fallthrough(false);
  const vkray::cli::Action render = vkray::cli::add_render_command(app);
  const vkray::cli::Action info = vkray::cli::add_info_command(app);
  const vkray::cli::Action bench = vkray::cli::add_bench_command(app);
  const vkray::cli::Action view = vkray::cli::add_view_command(app);
  const vkray::cli::Action manifest = vkray::cli::add_manifest_command(app);
  const vkray::cli::Action report = vkray::cli::add_report_command(app);
  const vkray::cli::Action points = vkray::cli::add_points_command(app);

  // A mistyped command would otherwise read as a stray argument ("A subcommand is required").
  if (argc > 1 && argv[1][0] != '-') {
    std::vector<std::string> commands;
    for (const CLI::App* command : app.get_subcommands({})) commands.push_back(command->get_name());
    if (std::find(commands.begin(), commands.end(), argv[1]) == commands.end()) {
      const auto nearest = vkray::nearest_name(argv[1], commands);
      std::string known;
      for (const auto& name : commands) known += (known.empty() ? "" : ", ") + name;
      std::cerr << "vkray: unknown command '" << argv[1] << "'; "
                << (nearest ? "did you mean '" + *nearest + "'?" : "the commands are " + known) << " (see 'vkray --help')\n";
      return 2;
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version end parsing with exit code 0 and print to stdout; real errors get one
    // line on stderr and exit code 2.
    if (error.get_exit_code() == 0) return app.exit(error);
    std::cerr << "vkray: " << error.what() << " (see 'vkray --help')\n";
    return 2;
  }

  try {
    if (app.got_subcommand("render")) return render();
    if (app.got_subcommand("bench")) return bench();
    if (app.got_subcommand("view")) return view();
    if (app.got_subcommand("manifest")) return manifest();
    if (app.got_subcommand("report")) return report();
    if (app.got_subcommand("points")) return points();
    return info();
  } catch (const vkray::InputError& error) {
    std::cerr << "vkray: " << error.what() << '\n';
    return 2;
  } catch (const std::exception& error) {
    std::cerr << "vkray: " << error.what() << '\n';
    return 1;
  }
}
