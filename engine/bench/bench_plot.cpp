#include "engine/bench/bench_plot.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>

extern char** environ;

namespace vkray {

extern const char* const bench_plot_script;

constexpr const char* debian_python = "/usr/bin/python3";

namespace {

struct RemoveOnExit {
  std::string path;
  ~RemoveOnExit() { std::remove(path.c_str()); }
};

}  // namespace

void plot_bench(const std::filesystem::path& json, const std::filesystem::path& png) {
  std::string script_path = (std::filesystem::temp_directory_path() / "vkray-bench-plot-XXXXXX").string();
  const int descriptor = mkstemp(script_path.data());
  if (descriptor < 0) throw std::runtime_error("--plot: cannot create a temporary file for the plot script");
  close(descriptor);
  const RemoveOnExit remove_script{script_path};
  std::ofstream(script_path) << bench_plot_script;

  // Like every output, the plot is written under a temporary name and renamed when complete.
  const std::filesystem::path png_temp =
      png.parent_path() / ("." + png.stem().string() + ".vkray-" + std::to_string(getpid()) + png.extension().string());
  const RemoveOnExit remove_plot{png_temp.string()};
  const std::string json_text = json.string(), png_text = png_temp.string();
  // Debian's python3-matplotlib (cmake/debian-packages.txt) is installed for Debian's python3, which
  // another python3 earlier on the PATH (pyenv, a virtualenv) may not see.
  std::string python = std::filesystem::exists(debian_python) ? debian_python : "python3";
  char* arguments[] = {python.data(), script_path.data(), const_cast<char*>(json_text.c_str()),
                       const_cast<char*>(png_text.c_str()), nullptr};
  pid_t child = 0;
  if (posix_spawnp(&child, python.c_str(), nullptr, nullptr, arguments, environ) != 0) {
    throw std::runtime_error("--plot needs python3 with matplotlib (Debian: apt install python3-matplotlib)");
  }
  int status = 0;
  waitpid(child, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error("--plot: the plot script failed (see above); it needs python3-matplotlib");
  }
  std::error_code error;
  std::filesystem::rename(png_temp, png, error);
  if (error) throw std::runtime_error(png.string() + ": cannot write: " + error.message());
}

}  // namespace vkray
