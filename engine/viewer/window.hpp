// The viewer's window (GLFW): opening it, its Vulkan surface, and the input that arrived since the
// last look. Nothing here knows about cameras or rendering.
#pragma once

#include "engine/device/gpu_device.hpp"
#include "engine/vulkan/context.hpp"

#include <string>
#include <vector>

struct GLFWwindow;

namespace vkray {

struct KeyPress {
  int key;   // GLFW_KEY_*
  int mods;  // GLFW_MOD_*
};

// One thing the user did: a key pressed, or the pointer dragged or the wheel turned (consecutive
// ones of a kind added up).
struct InputEvent {
  enum class Kind { key, orbit, pan, scroll };
  Kind kind;
  KeyPress key{};     // Kind::key
  double x = 0, y = 0;  // orbit, pan: the drag in pixels (left button; right or middle); scroll: notches in y
};

// What happened since the last take_input(), in the order it happened: a slow frame can gather a
// drag and a key in one batch, and C after a drag must print the camera the drag made.
struct WindowInput {
  std::vector<InputEvent> events;
  bool damaged = false;  // the window's contents must be shown again (exposed, restored)
};

class Window {
 public:
  // Throws NoWindowError when there is no display or GLFW cannot open a window there.
  Window(uint32_t width, uint32_t height, const std::string& title);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // The instance extensions and present test a device needs for this window's surface.
  PresentationSupport presentation() const;
  vk::raii::SurfaceKHR create_surface(const vk::raii::Instance& instance) const;

  // Blocks until an event arrives or `timeout_s` passes (for ever when negative), then handles it.
  void wait(double timeout_s);
  // Handles pending events without blocking.
  void poll();
  WindowInput take_input();
  bool key_held(int key) const;
  bool should_close() const;
  void close();
  // In pixels; 0 x 0 while minimized.
  vk::Extent2D framebuffer_size() const;
  GLFWwindow* handle() const { return window_; }

 private:
  static void on_key(GLFWwindow* window, int key, int scancode, int action, int mods);
  static void on_cursor(GLFWwindow* window, double x, double y);
  static void on_scroll(GLFWwindow* window, double x, double y);
  static void on_refresh(GLFWwindow* window);
  void add_motion(InputEvent::Kind kind, double x, double y);

  GLFWwindow* window_ = nullptr;
  WindowInput input_;
  double cursor_x_ = 0, cursor_y_ = 0;
};

}  // namespace vkray
