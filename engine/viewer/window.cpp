#include "engine/viewer/window.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cstdlib>

namespace vkray {
namespace {

std::string last_glfw_error() {
  const char* description = nullptr;
  glfwGetError(&description);
  return description ? description : "unknown GLFW error";
}

Window& owner(GLFWwindow* window) { return *static_cast<Window*>(glfwGetWindowUserPointer(window)); }

bool has_env(const char* name) {
  const char* value = std::getenv(name);
  return value && *value;
}

}  // namespace

Window::Window(uint32_t width, uint32_t height, const std::string& title) {
  if (!has_env("DISPLAY") && !has_env("WAYLAND_DISPLAY")) {
    throw NoWindowError("no display (DISPLAY and WAYLAND_DISPLAY are unset)");
  }
  if (!glfwInit()) throw NoWindowError("GLFW cannot start (" + last_glfw_error() + ")");
  if (!glfwVulkanSupported()) {
    glfwTerminate();
    throw NoWindowError("GLFW finds no Vulkan loader");
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);  // Vulkan draws, not OpenGL
  window_ = glfwCreateWindow(static_cast<int>(width), static_cast<int>(height), title.c_str(), nullptr, nullptr);
  if (!window_) {
    const std::string error = last_glfw_error();
    glfwTerminate();
    throw NoWindowError("GLFW cannot open a window (" + error + ")");
  }
  glfwSetWindowUserPointer(window_, this);
  glfwGetCursorPos(window_, &cursor_x_, &cursor_y_);
  glfwSetKeyCallback(window_, on_key);
  glfwSetCursorPosCallback(window_, on_cursor);
  glfwSetScrollCallback(window_, on_scroll);
  glfwSetWindowRefreshCallback(window_, on_refresh);
}

Window::~Window() {
  glfwDestroyWindow(window_);
  glfwTerminate();
}

PresentationSupport Window::presentation() const {
  PresentationSupport support;
  uint32_t count = 0;
  const char** names = glfwGetRequiredInstanceExtensions(&count);
  support.instance_extensions.assign(names, names + count);
  support.can_present = [](vk::Instance instance, vk::PhysicalDevice device, uint32_t family) {
    return glfwGetPhysicalDevicePresentationSupport(instance, device, family) == GLFW_TRUE;
  };
  return support;
}

vk::raii::SurfaceKHR Window::create_surface(const vk::raii::Instance& instance) const {
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  if (glfwCreateWindowSurface(*instance, window_, nullptr, &surface) != VK_SUCCESS) {
    throw NoWindowError("no Vulkan surface for the window (" + last_glfw_error() + ")");
  }
  return vk::raii::SurfaceKHR(instance, surface);
}

void Window::wait(double timeout_s) {
  if (timeout_s < 0) {
    glfwWaitEvents();
  } else {
    glfwWaitEventsTimeout(timeout_s);
  }
}

void Window::poll() { glfwPollEvents(); }

WindowInput Window::take_input() { return std::exchange(input_, WindowInput{}); }

bool Window::key_held(int key) const { return glfwGetKey(window_, key) == GLFW_PRESS; }

bool Window::should_close() const { return glfwWindowShouldClose(window_); }

void Window::close() { glfwSetWindowShouldClose(window_, GLFW_TRUE); }

vk::Extent2D Window::framebuffer_size() const {
  int width = 0, height = 0;
  glfwGetFramebufferSize(window_, &width, &height);
  return {static_cast<uint32_t>(width), static_cast<uint32_t>(height)};
}

void Window::on_key(GLFWwindow* window, int key, int /*scancode*/, int action, int mods) {
  if (action == GLFW_PRESS) owner(window).input_.events.push_back({InputEvent::Kind::key, {key, mods}});
}

void Window::on_cursor(GLFWwindow* window, double x, double y) {
  Window& self = owner(window);
  const double dx = x - self.cursor_x_, dy = y - self.cursor_y_;
  self.cursor_x_ = x, self.cursor_y_ = y;
  if (glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
    self.add_motion(InputEvent::Kind::orbit, dx, dy);
  } else if (glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
             glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS) {
    self.add_motion(InputEvent::Kind::pan, dx, dy);
  }
}

void Window::on_scroll(GLFWwindow* window, double /*x*/, double y) { owner(window).add_motion(InputEvent::Kind::scroll, 0, y); }

void Window::add_motion(InputEvent::Kind kind, double x, double y) {
  if (!input_.events.empty() && input_.events.back().kind == kind) {
    input_.events.back().x += x, input_.events.back().y += y;
  } else {
    input_.events.push_back({kind, {}, x, y});
  }
}

void Window::on_refresh(GLFWwindow* window) { owner(window).input_.damaged = true; }

}  // namespace vkray
