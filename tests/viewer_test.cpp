// `vkray view` end to end, in a virtual X server (Xvfb) each test starts for itself, with real
// input sent through that server by xdotool (XTEST, as a keyboard and mouse would). Screenshots the
// viewer saves when it quits are compared pixel for pixel with `vkray render`'s PNG preview of
// the same view. Skips with a message where Xvfb or xdotool is missing.
#include "tests/temp_dir_test.hpp"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef VKRAY_BINARY
#error "VKRAY_BINARY comes from CMake"
#endif

namespace vkray::test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Generous: under the validation layer on two shared cores, the viewer's start (pipeline
// creation included) takes seconds.
constexpr auto start_timeout = 120s;

std::string read_text(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream contents;
  contents << file.rdbuf();
  return contents.str();
}

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

struct Picture {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
};

Picture read_png(const fs::path& path) {
  Picture picture;
  auto input = OIIO::ImageInput::open(path.string());
  if (!input) {
    ADD_FAILURE() << path << ": " << OIIO::geterror();
    return picture;
  }
  picture.width = input->spec().width;
  picture.height = input->spec().height;
  EXPECT_EQ(input->spec().nchannels, 3) << path;
  picture.rgb.resize(size_t(picture.width) * picture.height * 3);
  EXPECT_TRUE(input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, picture.rgb.data())) << path;
  return picture;
}

// Number of pixels that differ; -1 when the sizes differ.
long differing_pixels(const Picture& a, const Picture& b) {
  if (a.width != b.width || a.height != b.height) return -1;
  long count = 0;
  for (size_t p = 0; p < a.rgb.size(); p += 3) {
    count += a.rgb[p] != b.rgb[p] || a.rgb[p + 1] != b.rgb[p + 1] || a.rgb[p + 2] != b.rgb[p + 2];
  }
  return count;
}

// A process started with `sh -c`, its stdout and stderr in files.
struct Process {
  pid_t pid = -1;
  fs::path out, err;

  std::string stdout_text() const { return read_text(out); }
  std::string stderr_text() const { return read_text(err); }

  // False once it has ended (its exit status then in `status`).
  bool running() {
    int raw = 0;
    if (pid > 0 && waitpid(pid, &raw, WNOHANG) == pid) {
      pid = -1;
      status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
    }
    return pid > 0;
  }
  // Exit status, or -1 if it did not end within `timeout` (it is killed then).
  int wait(std::chrono::seconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (running() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(20ms);
    if (!running()) return status;
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    pid = -1;
    return -1;
  }
  int status = -1;
  ~Process() {
    if (pid > 0) wait(0s);
  }
};

class ViewerTest : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    for (const char* tool : {"/usr/bin/Xvfb", "/usr/bin/xdotool"}) {
      if (!fs::exists(tool)) GTEST_SKIP() << tool << " is missing (apt-get install xvfb xdotool): viewer tests skipped";
    }
    // Two servers starting at once may pick the same display number, and the loser then ends:
    // a server counts as started once it has kept running while a client connected to it.
    constexpr int server_attempts = 5;
    for (int attempt = 0; attempt < server_attempts && display_.empty(); ++attempt) start_server();
    ASSERT_FALSE(display_.empty()) << "Xvfb did not start";
  }

  // Starts Xvfb on a display number it picks itself (-displayfd: written to the pipe once it
  // accepts clients); sets display_ when it runs.
  void start_server() {
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    xvfb_ = fork();
    ASSERT_GE(xvfb_, 0);
    if (xvfb_ == 0) {
      close(fds[0]);
      // Above the standard descriptors, which ctest may have left closed for the pipe to take.
      const std::string fd = std::to_string(fcntl(fds[1], F_DUPFD, 10));
      std::freopen("/dev/null", "w", stderr);
      // -fbdir: the screen's memory is an XWD file in the test's folder (screen_of reads it).
      execl("/usr/bin/Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24", "-nolisten", "tcp",
            "-fbdir", dir_.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    std::string number;
    char c = 0;
    while (read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    close(fds[0]);
    const std::string display = ":" + number;
    const std::string probe = "DISPLAY=" + display + " xdotool getdisplaygeometry > /dev/null 2>&1";
    if (!number.empty() && std::system(probe.c_str()) == 0) {
      std::this_thread::sleep_for(100ms);
      if (waitpid(xvfb_, nullptr, WNOHANG) == 0) {
        display_ = display;
        return;
      }
    }
    kill(xvfb_, SIGTERM);
    waitpid(xvfb_, nullptr, 0);
    xvfb_ = -1;
  }

  void TearDown() override {
    if (xvfb_ > 0) {
      kill(xvfb_, SIGTERM);
      waitpid(xvfb_, nullptr, 0);
    }
    TempDirTest::TearDown();
  }

  // Starts `vkray ARGS` in the test's folder on the virtual display.
  Process start_vkray(const std::string& args, bool with_display = true) {
    Process process;
    process.out = dir_ / ("out-" + std::to_string(runs_) + ".txt");
    process.err = dir_ / ("err-" + std::to_string(runs_++) + ".txt");
    const std::string display = with_display ? "env DISPLAY=" + display_ : "env -u DISPLAY -u WAYLAND_DISPLAY";
    const std::string command = "cd " + shell_quote(dir_.string()) + " && exec " + display + " " +
                                shell_quote(VKRAY_BINARY) + " " + args + " > " + shell_quote(process.out.string()) +
                                " 2> " + shell_quote(process.err.string());
    process.pid = fork();
    if (process.pid == 0) {
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    return process;
  }

  // `vkray ARGS` to its end; its exit status.
  int run_vkray(const std::string& args, Process* finished = nullptr) {
    Process process = start_vkray(args);
    const int status = process.wait(start_timeout);
    if (finished) finished->out = process.out, finished->err = process.err;
    EXPECT_EQ(status, 0) << "vkray " << args << ": " << process.stderr_text();
    return status;
  }

  // Waits until the viewer's stdout holds `text`.
  ::testing::AssertionResult wait_for_output(Process& process, const std::string& text) {
    const auto end = std::chrono::steady_clock::now() + start_timeout;
    while (std::chrono::steady_clock::now() < end) {
      if (process.stdout_text().find(text) != std::string::npos) return ::testing::AssertionSuccess();
      if (!process.running()) break;
      std::this_thread::sleep_for(50ms);
    }
    return ::testing::AssertionFailure() << "no '" << text << "' from the viewer; stderr: " << process.stderr_text();
  }

  // Runs xdotool on the virtual display; its stdout.
  std::string xdotool(const std::string& args) {
    const fs::path out = dir_ / "xdotool.txt";
    const std::string command = "DISPLAY=" + display_ + " xdotool " + args + " > " + shell_quote(out.string());
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    return read_text(out);
  }

  // The viewer's window id, with the pointer over it so that key presses go to it (Xvfb has no
  // window manager: the focus follows the pointer).
  std::string viewer_window() {
    std::string id = xdotool("search --sync --name '^vkray: '");
    id = id.substr(0, id.find('\n'));
    xdotool("mousemove --sync --window " + id + " 10 10");
    return id;
  }

  // What the virtual screen shows now where `window` is: Xvfb draws into its XWD file (-fbdir), a
  // big-endian header of 25 32-bit fields, a colour map of 12 bytes an entry, then the pixels.
  Picture screen_of(const std::string& window) {
    const std::string geometry = xdotool("getwindowgeometry --shell " + window);
    auto field = [&](const char* name) {
      std::smatch match;
      EXPECT_TRUE(std::regex_search(geometry, match, std::regex(std::string("\\b") + name + "=([0-9]+)"))) << geometry;
      return match.empty() ? 0 : std::stoi(match[1]);
    };
    const int x = field("X"), y = field("Y");
    Picture picture;
    picture.width = field("WIDTH"), picture.height = field("HEIGHT");
    const std::string xwd = read_text(dir_ / "Xvfb_screen0");
    auto word = [&](size_t index) {
      const auto* bytes = reinterpret_cast<const unsigned char*>(xwd.data() + 4 * index);
      return uint32_t{bytes[0]} << 24 | uint32_t{bytes[1]} << 16 | uint32_t{bytes[2]} << 8 | bytes[3];
    };
    if (xwd.size() < 100 || word(11) != 32) {
      ADD_FAILURE() << "the screen's XWD file is missing or not 32 bits a pixel";
      return picture;
    }
    const size_t header = word(0), colours = word(19), bytes_per_line = word(12);
    const bool lsb_first = word(7) == 0;
    const size_t pixels = header + 12 * colours;
    picture.rgb.resize(size_t(picture.width) * picture.height * 3);
    for (int row = 0; row < picture.height; ++row) {
      for (int column = 0; column < picture.width; ++column) {
        const size_t at = pixels + size_t(y + row) * bytes_per_line + 4 * size_t(x + column);
        if (at + 4 > xwd.size()) return ADD_FAILURE() << "the window lies outside the screen", picture;
        const auto* p = reinterpret_cast<const unsigned char*>(xwd.data() + at);
        const uint32_t value = lsb_first ? uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16
                                         : uint32_t{p[3]} | uint32_t{p[2]} << 8 | uint32_t{p[1]} << 16;
        unsigned char* rgb = &picture.rgb[(size_t(row) * picture.width + column) * 3];
        rgb[0] = value >> 16 & 0xff, rgb[1] = value >> 8 & 0xff, rgb[2] = value & 0xff;
      }
    }
    return picture;
  }

  // vkray render's preview of one output at width x height, with `extra` options.
  Picture render_preview(const std::string& output, int width, int height, const std::string& extra = "") {
    const fs::path exr = dir_ / ("render-" + std::to_string(runs_) + ".exr");
    run_vkray("render " + extra + " --aov " + output + " --width " + std::to_string(width) + " --height " +
              std::to_string(height) + " -o " + shell_quote(exr.string()));
    return read_png(fs::path(exr).replace_extension(".png"));
  }

  pid_t xvfb_ = -1;
  std::string display_;
  int runs_ = 0;
};

TEST_F(ViewerTest, ScreenshotAfterNFramesMatchesRenderPixelForPixel) {
  for (const std::string output : {"depth", "normal", "uv"}) {
    for (auto [width, height] : {std::pair{160, 120}, std::pair{90, 140}}) {
      const fs::path shot = dir_ / ("shot-" + output + ".png");
      Process viewer;
      run_vkray("view --no-overlay --frames 2 --output " + output + " --size " + std::to_string(width) + "x" +
                    std::to_string(height) + " --screenshot " + shell_quote(shot.string()),
                &viewer);
      EXPECT_EQ(differing_pixels(read_png(shot), render_preview(output, width, height)), 0)
          << output << " " << width << "x" << height;
    }
  }
}

// --stats counts the frames --frames asked for (the screenshot shows the last one again: not a
// frame), and its frames per second and mean frame time come from the same intervals: 1000 / mean.
TEST_F(ViewerTest, StatsCountTheFramesAndAgreeWithThemselves) {
  const fs::path shot = dir_ / "shot.png";
  Process viewer;
  run_vkray("view --no-overlay --frames 6 --size 64x48 --stats --screenshot " + shell_quote(shot.string()), &viewer);
  const std::string out = viewer.stdout_text();
  std::smatch stats;
  ASSERT_TRUE(std::regex_search(out, stats, std::regex(R"(vkray view: ([0-9]+) frames presented, ([0-9]+) renders dispatched; )"
                                                       R"(([0-9.]+) frames/s \(mean frame ([0-9.]+) ms, median ([0-9.]+) ms)")))
      << out;
  EXPECT_EQ(stats[1], "6") << out;
  EXPECT_EQ(stats[2], "6") << out;
  const double fps = std::stod(stats[3]), mean_ms = std::stod(stats[4]);
  ASSERT_GT(mean_ms, 0.0) << out;
  // Printed to 0.1 frames/s and 0.01 ms.
  EXPECT_NEAR(fps, 1000.0 / mean_ms, 0.05 + 1000.0 * 0.005 / (mean_ms * mean_ms)) << out;
}

TEST_F(ViewerTest, WithoutADisplayOneLineNamesRender) {
  Process viewer = start_vkray("view", false);
  EXPECT_EQ(viewer.wait(start_timeout), 1);
  const std::string err = viewer.stderr_text();
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("no display"), std::string::npos) << err;
  EXPECT_NE(err.find("'vkray render'"), std::string::npos) << err;
}

// An idle viewer dispatches nothing: over two idle seconds and more, one key press makes the only
// render beside the first. And an interactive session's pauses are not frames: --stats leaves out
// the intervals between presents that the viewer spent waiting for input.
TEST_F(ViewerTest, AnIdleViewerDoesNotDispatchAgainAndStatsLeaveIdleWaitsOut) {
  Process viewer = start_vkray("view --size 160x120 --stats");
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: showing"));
  viewer_window();
  std::this_thread::sleep_for(1200ms);  // idle
  xdotool("key 2");
  std::this_thread::sleep_for(1200ms);  // idle again
  xdotool("key Escape");
  ASSERT_EQ(viewer.wait(start_timeout), 0) << viewer.stderr_text();
  const std::string out = viewer.stdout_text();
  std::smatch stats;
  ASSERT_TRUE(std::regex_search(out, stats, std::regex(R"(([0-9]+) renders dispatched; .*mean frame ([0-9.]+) ms)"))) << out;
  EXPECT_EQ(stats[1], "2") << out;
  EXPECT_LT(std::stod(stats[2]), 1000.0) << out;
}

TEST_F(ViewerTest, KeyTwoSwitchesToNormals) {
  const fs::path shot = dir_ / "shot.png";
  Process viewer = start_vkray("view --no-overlay --size 160x120 --output depth --screenshot " + shell_quote(shot.string()));
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: showing"));
  viewer_window();
  xdotool("key 2");
  xdotool("key Escape");
  ASSERT_EQ(viewer.wait(start_timeout), 0) << viewer.stderr_text();
  EXPECT_EQ(differing_pixels(read_png(shot), render_preview("normal", 160, 120)), 0);
  // lavapipe, the one device here: the viewer says it renders on the CPU, as render does.
  EXPECT_NE(viewer.stderr_text().find("a CPU implementation of Vulkan"), std::string::npos) << viewer.stderr_text();
}

TEST_F(ViewerTest, ALeftDragOrbitsAndCPrintsTheCameraRenderSees) {
  const fs::path shot = dir_ / "shot.png";
  Process viewer = start_vkray("view --no-overlay --size 160x120 --output normal --screenshot " + shell_quote(shot.string()));
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: showing"));
  const std::string window = viewer_window();
  // The drag and C in one go, as a quick hand gives them: the viewer may take both in one batch of
  // input, and must still print the camera the drag made.
  xdotool("mousemove --sync --window " + window + " 80 60 mousedown 1 mousemove --sync --window " + window +
          " 120 40 mouseup 1 key c");
  ASSERT_TRUE(wait_for_output(viewer, "\"camera\""));
  xdotool("key Escape");
  ASSERT_EQ(viewer.wait(start_timeout), 0) << viewer.stderr_text();

  // The printed snippet is a scene file's camera; it moved, and render from it sees the screenshot.
  const std::string out = viewer.stdout_text();
  const size_t start = out.find("\"camera\"");
  const auto camera = nlohmann::json::parse("{" + out.substr(start, out.find('\n', start) - start) + "}").at("camera");
  EXPECT_NE(camera.at("from"), nlohmann::json({0, 1.8, 6})) << out;
  auto triple = [&](const char* key) {
    const auto& v = camera.at(key);
    return v[0].dump() + "," + v[1].dump() + "," + v[2].dump();
  };
  const std::string option = "--camera " + shell_quote("from=" + triple("from") + " to=" + triple("to") + " up=" +
                                                       triple("up") + " fovy=" + camera.at("fovy").dump());
  EXPECT_EQ(differing_pixels(read_png(shot), render_preview("normal", 160, 120, option)), 0);
  EXPECT_GT(differing_pixels(read_png(shot), render_preview("normal", 160, 120)), 100);
}

TEST_F(ViewerTest, AfterAResizeTheDiskStillTouchesTheShorterBorders) {
  const fs::path shot = dir_ / "shot.png";
  Process viewer = start_vkray("view --no-overlay --size 200x120 --output uv --screenshot " + shell_quote(shot.string()));
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: showing"));
  const std::string window = viewer_window();
  xdotool("windowsize --sync " + window + " 100 180");
  xdotool("key Escape");
  ASSERT_EQ(viewer.wait(start_timeout), 0) << viewer.stderr_text();
  const Picture picture = read_png(shot);
  ASSERT_EQ(picture.width, 100);
  ASSERT_EQ(picture.height, 180);
  // Bright inside the disk, dimmed outside: in the middle row the outermost pixels are inside, in
  // the middle column the top and bottom ones outside.
  auto blue = [&](int i, int j) { return picture.rgb[(size_t(j) * picture.width + i) * 3 + 2]; };
  const int inside = 128, outside = 38;  // 0.5 and 0.15 of 255, as the preview draws them
  EXPECT_EQ(blue(0, 90), inside);
  EXPECT_EQ(blue(99, 90), inside);
  EXPECT_EQ(blue(50, 0), outside);
  EXPECT_EQ(blue(50, 179), outside);
  EXPECT_EQ(differing_pixels(picture, render_preview("uv", 100, 180)), 0);
}

// An idle viewer draws nothing more, so its first frame and the frame with an error must show the
// overlay whole at once (an auto-sized ImGui window took its size a frame late: no overlay on the
// first frame, an error cut short). On screen while it waits: the overlay over the picture on the
// first frame, and with the error exactly what its screenshot at exit (drawn again) shows.
TEST_F(ViewerTest, TheOverlayIsWholeOnTheFirstFrameAndWithAnError) {
  const std::string scene = R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
                               "spheres": [{"center": [0, 0, 0], "radius": RADIUS}]})";
  auto with_radius = [&](const char* radius) { return std::regex_replace(scene, std::regex("RADIUS"), radius); };
  write("scene.json", with_radius("1"));
  const fs::path shot = dir_ / "shot.png";
  Process viewer = start_vkray("view scene.json --size 480x360 --screenshot " + shell_quote(shot.string()));
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: showing"));
  const std::string window = viewer_window();
  xdotool("mousemove 1270 1010");  // out of the window: Xvfb draws the pointer into its screen
  std::this_thread::sleep_for(1s);  // idle
  const Picture first = screen_of(window);
  write("scene.json", with_radius("-2"));
  const auto end = std::chrono::steady_clock::now() + start_timeout;
  while (viewer.stderr_text().find("radius") == std::string::npos && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(50ms);
  }
  std::this_thread::sleep_for(1s);  // idle again, the error shown
  const Picture with_error = screen_of(window);
  viewer_window();  // the pointer back over it, for the key
  xdotool("key Escape");
  ASSERT_EQ(viewer.wait(start_timeout), 0) << viewer.stderr_text();
  EXPECT_EQ(differing_pixels(with_error, read_png(shot)), 0) << "the error's overlay was not whole on screen";
  // The first frame: the picture, with the overlay's box (five lines of text and more) over its top left.
  write("good.json", with_radius("1"));
  const Picture picture = render_preview("depth", 480, 360, "good.json");
  ASSERT_EQ(differing_pixels(first, picture) >= 0, true);
  long overlaid = 0, elsewhere = 0;
  for (int row = 0; row < first.height; ++row) {
    for (int column = 0; column < first.width; ++column) {
      const size_t p = (size_t(row) * first.width + column) * 3;
      const bool differs = !std::equal(&first.rgb[p], &first.rgb[p] + 3, &picture.rgb[p]);
      (row < first.height / 2 ? overlaid : elsewhere) += differs;
    }
  }
  EXPECT_GT(overlaid, 480 * 30) << "no overlay on the first frame";
  EXPECT_EQ(elsewhere, 0);
}

TEST_F(ViewerTest, TheSceneFileIsReloadedAndABrokenOneKeepsTheLastGoodScene) {
  const std::string scene = R"({"camera": {"from": [0, 0, 5], "to": [0, 0, 0], "fovy": 40},
                               "spheres": [{"center": [0, 0, 0], "radius": RADIUS}]})";
  auto with_radius = [&](const char* radius) { return std::regex_replace(scene, std::regex("RADIUS"), radius); };
  const fs::path path = write("scene.json", with_radius("1"));
  const fs::path shot = dir_ / "shot.png";
  Process viewer = start_vkray("view scene.json --no-overlay --size 120x120 --screenshot " + shell_quote(shot.string()));
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: showing"));
  write("scene.json", with_radius("1.5"));
  ASSERT_TRUE(wait_for_output(viewer, "vkray view: reloaded"));
  write("scene.json", with_radius("-2"));
  const auto end = std::chrono::steady_clock::now() + start_timeout;
  while (viewer.stderr_text().find("radius") == std::string::npos && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_NE(viewer.stderr_text().find("scene.json: spheres[0].radius"), std::string::npos) << viewer.stderr_text();
  viewer_window();
  xdotool("key Escape");
  ASSERT_EQ(viewer.wait(start_timeout), 0) << viewer.stderr_text();
  // On screen: the last good scene, the sphere of radius 1.5.
  write("good.json", with_radius("1.5"));
  const fs::path exr = dir_ / "good.exr";
  run_vkray("render good.json --aov depth --width 120 --height 120 -o " + shell_quote(exr.string()));
  EXPECT_EQ(differing_pixels(read_png(shot), read_png(fs::path(exr).replace_extension(".png"))), 0);
}

}  // namespace
}  // namespace vkray::test
