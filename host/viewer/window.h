// The viewer's window: GLFW's lifetime, one window with a Vulkan surface, and the input it received
// since the last frame, turned into viewer terms (drags, wheel steps, fly keys, actions).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <vulkan/vulkan_raii.hpp>

struct GLFWwindow;

namespace vkray {

// glfwInit/glfwTerminate. Without a display it throws one line that says so.
class GlfwSession {
public:
  GlfwSession();
  ~GlfwSession();
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;

  // The instance extensions a Vulkan surface on this platform needs.
  std::vector<std::string> requiredInstanceExtensions() const;
};

// Keys that do something once per press.
enum class ViewerAction { ToggleFly, ResetCamera, SaveCamera, Screenshot, ToggleOverlay, CycleDisplay, Quit };

struct InputFrame {
  glm::dvec2 cursorDelta{0.0}; // pixels since the last frame, y down
  bool leftDown = false;       // buttons held now
  bool rightDown = false;
  bool middleDown = false;
  bool shift = false;
  double scroll = 0.0;               // wheel steps since the last frame
  glm::dvec3 move{0.0};              // fly keys held: x = D - A, y = E - Q, z = W - S
  std::vector<ViewerAction> actions; // in the order pressed
  // A left click that did not drag: where it was released, as a fraction of the window (0..1, y
  // down). The viewer inspects that pixel's ray tree.
  std::optional<glm::dvec2> click;
};

class Window {
public:
  Window(const GlfwSession& session, std::uint32_t width, std::uint32_t height, const std::string& title);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  GLFWwindow* handle() const { return window_.get(); }
  vk::raii::SurfaceKHR createSurface(const vk::raii::Instance& instance) const;

  // Processes pending events; with `wait`, sleeps until one arrives or timeout passes.
  void pollEvents(bool wait = false, double timeoutSeconds = 0.1);
  bool shouldClose() const;
  // Minimized by the window manager. On X11 the drawable keeps its size then, so a zero
  // framebuffer alone does not tell.
  bool iconified() const;
  void requestClose();
  // The drawable size in pixels (0 x 0 while minimized).
  vk::Extent2D framebufferSize() const;
  // The window's height in the units of cursor positions (screen coordinates; pixels unless scaled).
  double heightInCursorUnits() const;
  // True once after the framebuffer size changed.
  bool takeResized();
  // The input since the previous call.
  InputFrame takeInput();

  void setTitle(const std::string& title);
  void setSize(std::uint32_t width, std::uint32_t height);
  void setClipboard(const std::string& text);

private:
  static void onKey(GLFWwindow* w, int key, int scancode, int action, int mods);
  static void onCursor(GLFWwindow* w, double x, double y);
  static void onScroll(GLFWwindow* w, double dx, double dy);
  static void onMouseButton(GLFWwindow* w, int button, int action, int mods);
  static void onFramebufferSize(GLFWwindow* w, int width, int height);

  struct Destroy {
    void operator()(GLFWwindow* w) const;
  };
  std::unique_ptr<GLFWwindow, Destroy> window_;
  InputFrame pending_;
  glm::dvec2 lastCursor_{0.0};
  bool haveCursor_ = false;
  glm::dvec2 pressedAt_{0.0}; // the cursor when the left button went down
  double dragged_ = 0.0;      // cursor travel since then
  bool resized_ = false;
};

} // namespace vkray
