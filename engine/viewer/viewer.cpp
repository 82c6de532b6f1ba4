#include "engine/viewer/viewer.hpp"

#include "engine/io/image_io.hpp"
#include "engine/io/preview.hpp"
#include "engine/render/renderer.hpp"
#include "engine/vulkan/preview_pass.hpp"
#include "engine/viewer/camera_controller.hpp"
#include "engine/viewer/display.hpp"
#include "engine/viewer/file_watch.hpp"
#include "engine/viewer/overlay.hpp"
#include "engine/viewer/window.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <numbers>

namespace vkray {
namespace {

// A renderer of `scene` as the options ask: their traversal and their rays' mask.
std::unique_ptr<Renderer> make_renderer(GpuDevice& device, const Scene& scene, const ViewerOptions& options) {
  RendererOptions renderer_options;
  renderer_options.scene.search = options.traversal;
  auto renderer = std::make_unique<Renderer>(device, scene, renderer_options);
  renderer->set_ray_mask(options.mask);
  return renderer;
}

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// How often an idle viewer looks at the scene file: a stat() 4 times a second.
constexpr double watch_interval_s = 0.25;
// How often the overlay's numbers change: a few times a second stays readable.
constexpr double overlay_refresh_s = 0.25;
// Flying speed in distances between `from` and `to` per second; the longest step one frame may
// take, so a slow frame does not throw the camera far.
constexpr double fly_speed = 0.5;
constexpr double max_fly_step_s = 0.1;
// Dragging across the shorter side of the window orbits half a turn.
constexpr double orbit_per_shorter_side = std::numbers::pi;
// Attempts at the final screenshot while the swapchain keeps going out of date.
constexpr int capture_attempts = 3;

const char* aov_name(Aov aov) { return aov == Aov::depth ? "depth" : aov == Aov::normal ? "normal" : "uv"; }

std::string format(const char* pattern, auto... values) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, values...);
  return text;
}

std::string vector_text(const glm::dvec3& v) { return format("%.4g, %.4g, %.4g", v.x, v.y, v.z); }

// The first of vkray-view-1.exr, vkray-view-2.exr, ... in the working folder that is not there yet.
std::filesystem::path free_save_path() {
  for (int n = 1;; ++n) {
    std::filesystem::path path = "vkray-view-" + std::to_string(n) + ".exr";
    if (!std::filesystem::exists(path)) return path;
  }
}

class Viewer {
 public:
  explicit Viewer(const ViewerOptions& options);
  void run();

 private:
  void resize();
  void handle(const WindowInput& input, double dt);
  void press(const KeyPress& press);
  void reload();
  void save();
  void render();
  bool present(std::vector<uint8_t>* capture);
  std::vector<std::string> overlay_lines() const;

  const ViewerOptions& options_;
  Scene scene_;
  CameraController controller_;
  Aov output_;
  Window window_;
  PresentationSupport presentation_;
  GpuDevice device_;
  Display display_;
  std::optional<Overlay> overlay_;
  std::unique_ptr<Renderer> renderer_;
  // The frame stays on the device: rendered into target_, mapped to 8 bits by preview_, copied
  // onto the swapchain by display_.
  std::unique_ptr<ImageTarget> target_;
  PreviewPass preview_;
  std::optional<FileWatch> watch_;
  std::string error_;  // of the last reload or save, shown until the next one succeeds

  bool dirty_ = true;     // what is shown changed: render again
  bool damaged_ = false;  // the rendered picture must be presented (again)
  bool stale_ = true;     // the swapchain must be made again
  // The window size the swapchain was last made for (its extent may differ where the surface
  // decides it).
  vk::Extent2D sized_for_;
  uint64_t renders_ = 0, presents_ = 0;
  // Between one present and the next, for --stats; an interval with an idle wait in it is not a
  // frame's and is left out.
  std::vector<double> present_intervals_ms_;
  bool waited_ = false;  // the viewer waited for input since the last present
  double gpu_ms_ = 0.0;  // of the last render
  DepthRange depths_;    // of the last render of depth: the overlay's legend
  // One rendered frame's figures, both of the same frame: the last one's, and those the overlay
  // shows (refreshed every overlay_refresh_s, and before the viewer goes idle).
  struct FrameFigures {
    double frame_ms = 0.0, gpu_ms = 0.0;
    bool operator==(const FrameFigures&) const = default;
  };
  FrameFigures last_frame_, shown_;
  bool refresh_figures_ = false;
  Clock::time_point shown_at_{};
  Clock::time_point last_present_{};
};

Viewer::Viewer(const ViewerOptions& options)
    : options_(options),
      scene_(options.load_scene()),
      controller_(scene_.camera),
      output_(options.output),
      window_(options.width ? options.width : scene_.width, options.height ? options.height : scene_.height,
              "vkray: " + options.title),
      presentation_(window_.presentation()),
      device_(options.device, presentation_, options.transfer),
      display_(device_.vulkan(), window_.create_surface(device_.vulkan().instance), options.vsync),
      renderer_(make_renderer(device_, scene_, options)),
      preview_(device_.vulkan()) {
  if (options.on_device) options.on_device(device_.info());
  resize();
  if (options.overlay) {
    // The backend needs at least 2 images, even for a window that starts minimized.
    overlay_.emplace(device_.vulkan(), window_.handle(), display_.overlay_pass(), std::max(2u, display_.min_image_count()),
                     std::max(2u, display_.image_count()));
  }
  if (!options.watched.empty()) watch_.emplace(options.watched);
}

void Viewer::run() {
  const bool continuous = options_.frames > 0;
  auto last_tick = Clock::now();
  bool announced = false;
  while (!window_.should_close()) {
    const bool minimized = display_.extent().width == 0 && !stale_;
    const bool flying = std::ranges::any_of(std::initializer_list<int>{GLFW_KEY_W, GLFW_KEY_A, GLFW_KEY_S, GLFW_KEY_D,
                                                                        GLFW_KEY_Q, GLFW_KEY_E},
                                            [&](int key) { return window_.key_held(key); });
    if (!minimized && (dirty_ || damaged_ || stale_ || flying || continuous)) {
      window_.poll();
    } else {
      // Idle: sleep until an event, waking only to look at the scene file.
      window_.wait(watch_ ? watch_interval_s : -1.0);
      waited_ = true;
    }
    const double dt = std::min(seconds_since(last_tick), max_fly_step_s);
    last_tick = Clock::now();
    handle(window_.take_input(), dt);
    if (watch_ && watch_->changed()) reload();
    if (continuous) {
      dirty_ = true;
      if (options_.spin_degrees != 0.0) controller_.orbit(options_.spin_degrees * std::numbers::pi / 180.0, 0.0);
    }

    if (stale_ || window_.framebuffer_size() != sized_for_) resize();
    if (display_.extent().width == 0) continue;  // minimized: nothing to show
    const auto frame_start = Clock::now();
    const bool rendering = dirty_;
    if (rendering) render();
    if (damaged_) {
      if (!present(nullptr)) continue;
      if (rendering) {
        last_frame_ = {seconds_since(frame_start) * 1e3, gpu_ms_};
        // About to wait for input with older figures shown: present once more to show this frame's.
        if (!continuous && !flying && !dirty_ && shown_ != last_frame_) refresh_figures_ = damaged_ = true;
      }
      if (!announced) {
        std::printf("vkray view: showing %s at %ux%u on %s\n", options_.title.c_str(), display_.extent().width,
                    display_.extent().height, device_.info().name.c_str());
        std::fflush(stdout);
        announced = true;
      }
    }
    if (continuous && presents_ >= options_.frames) window_.close();
  }

  if (options_.screenshot) {
    std::vector<uint8_t> rgb;
    for (int attempt = 0; attempt < capture_attempts && rgb.empty(); ++attempt) {
      if (stale_ || window_.framebuffer_size() != sized_for_) resize();
      if (display_.extent().width == 0) break;
      if (dirty_) render();
      if (!present(&rgb)) rgb.clear(), stale_ = true;
    }
    if (rgb.empty()) throw GpuError("no screenshot: the window was minimized or kept changing size");
    write_rgb_png(*options_.screenshot, display_.extent().width, display_.extent().height, rgb);
    std::printf("vkray view: wrote %s (%ux%u)\n", options_.screenshot->c_str(), display_.extent().width,
                display_.extent().height);
  }
  if (options_.stats) {
    // Both figures from the same intervals between presents, so that frames/s is 1000 / the mean
    // frame: start-up (scene upload, pipeline creation) comes before the first present and stays out.
    std::vector<double> sorted = present_intervals_ms_;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
    double sum_ms = 0.0;
    for (double ms : sorted) sum_ms += ms;
    const double mean = sorted.empty() ? 0.0 : sum_ms / static_cast<double>(sorted.size());
    std::printf("vkray view: %llu frames presented, %llu renders dispatched; %.1f frames/s (mean frame %.2f ms, "
                "median %.2f ms, from present to present, idle waits left out), last GPU time %.1f ms\n",
                static_cast<unsigned long long>(presents_), static_cast<unsigned long long>(renders_),
                mean > 0.0 ? 1000.0 / mean : 0.0, mean, median, gpu_ms_);
  }
}

void Viewer::resize() {
  sized_for_ = window_.framebuffer_size();
  display_.resize(sized_for_);
  if (overlay_ && display_.min_image_count() > 0) overlay_->set_min_image_count(std::max(2u, display_.min_image_count()));
  stale_ = false;
  dirty_ = true;
}

void Viewer::press(const KeyPress& press) {
  switch (press.key) {
    case GLFW_KEY_ESCAPE: window_.close(); break;
    case GLFW_KEY_1: output_ = Aov::depth, dirty_ = true; break;
    case GLFW_KEY_2: output_ = Aov::normal, dirty_ = true; break;
    case GLFW_KEY_3: output_ = Aov::uv, dirty_ = true; break;
    case GLFW_KEY_R: controller_.reset(), dirty_ = true; break;
    case GLFW_KEY_C:
      std::printf("%s\n", controller_.json().c_str());
      std::fflush(stdout);
      break;
    case GLFW_KEY_S:
      if (press.mods & GLFW_MOD_CONTROL) save();  // plain S flies backwards
      break;
    default: break;
  }
}

void Viewer::handle(const WindowInput& input, double dt) {
  const vk::Extent2D extent = display_.extent();
  const double shorter = std::max(1u, std::min(extent.width, extent.height));
  for (const InputEvent& event : input.events) {
    switch (event.kind) {
      case InputEvent::Kind::key: press(event.key); break;
      case InputEvent::Kind::orbit:
        controller_.orbit(-event.x * orbit_per_shorter_side / shorter, event.y * orbit_per_shorter_side / shorter);
        dirty_ = true;
        break;
      case InputEvent::Kind::pan:
        controller_.pan(2.0 * event.x / shorter, -2.0 * event.y / shorter, extent.width, extent.height);
        dirty_ = true;
        break;
      case InputEvent::Kind::scroll: controller_.zoom(event.y), dirty_ = true; break;
    }
  }
  if (!(window_.key_held(GLFW_KEY_LEFT_CONTROL) || window_.key_held(GLFW_KEY_RIGHT_CONTROL))) {
    auto axis = [&](int positive, int negative) {
      return (window_.key_held(positive) ? 1.0 : 0.0) - (window_.key_held(negative) ? 1.0 : 0.0);
    };
    const double right = axis(GLFW_KEY_D, GLFW_KEY_A), up = axis(GLFW_KEY_E, GLFW_KEY_Q), ahead = axis(GLFW_KEY_W, GLFW_KEY_S);
    if (right != 0.0 || up != 0.0 || ahead != 0.0) {
      const double step = fly_speed * dt;
      controller_.fly(right * step, up * step, ahead * step);
      dirty_ = true;
    }
  }
  if (input.damaged) damaged_ = true;
}

void Viewer::reload() {
  try {
    Scene scene = options_.load_scene();
    auto renderer = make_renderer(device_, scene, options_);
    renderer_ = std::move(renderer);
    scene_ = std::move(scene);
    controller_.set_home(scene_.camera);
    error_.clear();
    std::printf("vkray view: reloaded %s\n", options_.watched.c_str());
  } catch (const DeviceLostError&) {
    throw;  // nothing more can be shown: the run ends with its one line
  } catch (const std::exception& error) {
    // The last good scene stays on screen, with the error over it.
    error_ = error.what();
    std::fprintf(stderr, "vkray: %s\n", error_.c_str());
  }
  std::fflush(stdout);
  dirty_ = true;
}

void Viewer::save() {
  const vk::Extent2D extent = display_.extent();
  try {
    // What `vkray render` writes for this camera and size: depth and normals, EXR and preview.
    const Frame frame = renderer_->render(controller_.camera(), extent.width, extent.height, AovSet{Aov::depth, Aov::normal});
    const std::filesystem::path exr = free_save_path();
    const std::filesystem::path preview = std::filesystem::path(exr).replace_extension(".png");
    write_outputs(exr, &preview, frame);
    std::printf("vkray view: wrote %s and %s (%ux%u, depth,normal)\n", exr.c_str(), preview.c_str(), extent.width,
                extent.height);
    std::fflush(stdout);
    error_.clear();
  } catch (const DeviceLostError&) {
    throw;
  } catch (const std::exception& error) {
    error_ = error.what();
    std::fprintf(stderr, "vkray: %s\n", error_.c_str());
  }
  damaged_ = true;  // the overlay shows the outcome
}

void Viewer::render() {
  const vk::Extent2D extent = display_.extent();
  if (!target_ || target_->width() != extent.width || target_->height() != extent.height) {
    target_.reset();  // its memory first
    target_ = std::make_unique<ImageTarget>(device_, extent.width, extent.height);
  }
  const DepthRange depths = renderer_->render(controller_.camera(), output_, *target_);
  if (output_ == Aov::depth) depths_ = depths;
  preview_.run(*target_, output_, depths, display_.bgra());
  gpu_ms_ = renderer_->timings().dispatch_gpu_ms;
  ++renders_;
  dirty_ = false;
  damaged_ = true;
}

bool Viewer::present(std::vector<uint8_t>* capture) {
  if (refresh_figures_ || seconds_since(shown_at_) >= overlay_refresh_s) {
    shown_ = last_frame_;
    shown_at_ = Clock::now();
    refresh_figures_ = false;
  }
  bool shown = false;
  if (overlay_) {
    const std::vector<std::string> lines = overlay_lines();
    const Display::OverlayDraw draw = [&](vk::CommandBuffer commands) { overlay_->draw(lines, error_, commands); };
    shown = display_.present(preview_.picture(), &draw, capture);
  } else {
    shown = display_.present(preview_.picture(), nullptr, capture);
  }
  damaged_ = !shown;
  if (shown && !capture) {  // the screenshot's present shows the last frame again: not a frame
    const Clock::time_point now = Clock::now();
    if (presents_ > 0 && !waited_) {
      present_intervals_ms_.push_back(std::chrono::duration<double, std::milli>(now - last_present_).count());
    }
    ++presents_;
    last_present_ = now;
    waited_ = false;
  } else if (!shown) {
    stale_ = true;
  }
  return shown;
}

std::vector<std::string> Viewer::overlay_lines() const {
  const vk::Extent2D extent = display_.extent();
  const double pixels = double(extent.width) * extent.height;
  const Camera& camera = controller_.camera();
  std::vector<std::string> lines;
  lines.push_back(format("frame %.1f ms   GPU %.1f ms   %.1f Mrays/s", shown_.frame_ms, shown_.gpu_ms,
                         shown_.gpu_ms > 0.0 ? pixels / (shown_.gpu_ms * 1e3) : 0.0));
  lines.push_back(format("%s   %ux%u   %s", aov_name(output_), extent.width, extent.height, device_.info().name.c_str()));
  lines.push_back("from " + vector_text(camera.from) + "   to " + vector_text(camera.to));
  lines.push_back(format("fovy %.4g   (1 depth, 2 normal, 3 uv, R reset, C print)", camera.fovy_degrees));
  if (output_ == Aov::depth) lines.push_back(depth_legend(depths_));
  return lines;
}

}  // namespace

void run_viewer(const ViewerOptions& options) {
  Viewer viewer(options);
  viewer.run();
}

}  // namespace vkray
