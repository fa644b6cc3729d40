// GLFW window, surface and input (see window.h).
#include "viewer/window.h"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "util/error.h"

namespace vkray {

namespace {

// GLFW reports failures through a callback; the last one is kept to explain a failed call.
std::string gLastGlfwError;

void onGlfwError(int /*code*/, const char* description) {
  gLastGlfwError = description ? description : "unknown GLFW error";
}

std::string glfwFailure(const std::string& what) {
  return what + (gLastGlfwError.empty() ? "" : ": " + gLastGlfwError);
}

} // namespace

GlfwSession::GlfwSession() {
  glfwSetErrorCallback(onGlfwError);
  if (glfwInit() != GLFW_TRUE) {
    throw Error(glfwFailure("cannot open a window") +
                " (the viewer needs a display; for scripted runs without one use xvfb-run -a vkray view ...)");
  }
  if (glfwVulkanSupported() != GLFW_TRUE) {
    glfwTerminate();
    throw DeviceError(glfwFailure("GLFW found no Vulkan loader for windows"));
  }
}

GlfwSession::~GlfwSession() {
  glfwTerminate();
}

std::vector<std::string> GlfwSession::requiredInstanceExtensions() const {
  std::uint32_t count = 0;
  const char** names = glfwGetRequiredInstanceExtensions(&count);
  if (names == nullptr) throw DeviceError(glfwFailure("no Vulkan surface support for this display"));
  return std::vector<std::string>(names, names + count);
}

void Window::Destroy::operator()(GLFWwindow* w) const {
  glfwDestroyWindow(w);
}

Window::Window(const GlfwSession& /*session*/, std::uint32_t width, std::uint32_t height, const std::string& title) {
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API); // Vulkan draws, not OpenGL
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  window_.reset(glfwCreateWindow(static_cast<int>(width), static_cast<int>(height), title.c_str(), nullptr, nullptr));
  if (!window_)
    throw Error(glfwFailure("cannot create a " + std::to_string(width) + "x" + std::to_string(height) + " window"));
  glfwSetWindowUserPointer(window_.get(), this);
  // Installed before the overlay's GLFW backend, which chains to them.
  glfwSetKeyCallback(window_.get(), onKey);
  glfwSetCursorPosCallback(window_.get(), onCursor);
  glfwSetScrollCallback(window_.get(), onScroll);
  glfwSetMouseButtonCallback(window_.get(), onMouseButton);
  glfwSetFramebufferSizeCallback(window_.get(), onFramebufferSize);
}

Window::~Window() = default;

vk::raii::SurfaceKHR Window::createSurface(const vk::raii::Instance& instance) const {
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  VkResult result = glfwCreateWindowSurface(*instance, window_.get(), nullptr, &surface);
  if (result != VK_SUCCESS) {
    throw DeviceError(glfwFailure("creating the window surface: glfwCreateWindowSurface: " +
                                  vk::to_string(static_cast<vk::Result>(result))));
  }
  return vk::raii::SurfaceKHR(instance, surface);
}

void Window::pollEvents(bool wait, double timeoutSeconds) {
  if (wait)
    glfwWaitEventsTimeout(timeoutSeconds);
  else
    glfwPollEvents();
}

bool Window::shouldClose() const {
  return glfwWindowShouldClose(window_.get()) == GLFW_TRUE;
}

bool Window::iconified() const {
  return glfwGetWindowAttrib(window_.get(), GLFW_ICONIFIED) == GLFW_TRUE;
}

void Window::requestClose() {
  glfwSetWindowShouldClose(window_.get(), GLFW_TRUE);
}

vk::Extent2D Window::framebufferSize() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_.get(), &w, &h);
  return vk::Extent2D(static_cast<std::uint32_t>(std::max(w, 0)), static_cast<std::uint32_t>(std::max(h, 0)));
}

double Window::heightInCursorUnits() const {
  int w = 0, h = 0;
  glfwGetWindowSize(window_.get(), &w, &h);
  return std::max(h, 1);
}

bool Window::takeResized() {
  bool r = resized_;
  resized_ = false;
  return r;
}

InputFrame Window::takeInput() {
  InputFrame in = std::move(pending_);
  pending_ = InputFrame();
  GLFWwindow* w = window_.get();
  auto down = [&](int key) { return glfwGetKey(w, key) == GLFW_PRESS; };
  in.leftDown = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  in.rightDown = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  in.middleDown = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  in.shift = down(GLFW_KEY_LEFT_SHIFT) || down(GLFW_KEY_RIGHT_SHIFT);
  in.move = glm::dvec3(double(down(GLFW_KEY_D)) - double(down(GLFW_KEY_A)),
                       double(down(GLFW_KEY_E)) - double(down(GLFW_KEY_Q)),
                       double(down(GLFW_KEY_W)) - double(down(GLFW_KEY_S)));
  return in;
}

void Window::setTitle(const std::string& title) {
  glfwSetWindowTitle(window_.get(), title.c_str());
}

void Window::setSize(std::uint32_t width, std::uint32_t height) {
  glfwSetWindowSize(window_.get(), static_cast<int>(width), static_cast<int>(height));
}

void Window::setClipboard(const std::string& text) {
  glfwSetClipboardString(window_.get(), text.c_str());
}

void Window::onKey(GLFWwindow* w, int key, int /*scancode*/, int action, int /*mods*/) {
  if (action != GLFW_PRESS) return;
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  auto& actions = self->pending_.actions;
  switch (key) {
  case GLFW_KEY_F:
  case GLFW_KEY_TAB:
    actions.push_back(ViewerAction::ToggleFly);
    break;
  case GLFW_KEY_R:
  case GLFW_KEY_HOME:
    actions.push_back(ViewerAction::ResetCamera);
    break;
  case GLFW_KEY_C:
    actions.push_back(ViewerAction::SaveCamera);
    break;
  case GLFW_KEY_P:
  case GLFW_KEY_F12:
    actions.push_back(ViewerAction::Screenshot);
    break;
  case GLFW_KEY_H:
  case GLFW_KEY_F1:
    actions.push_back(ViewerAction::ToggleOverlay);
    break;
  case GLFW_KEY_M: // E moves the camera in fly mode
    actions.push_back(ViewerAction::CycleDisplay);
    break;
  case GLFW_KEY_ESCAPE:
    actions.push_back(ViewerAction::Quit);
    break;
  default:
    break;
  }
}

void Window::onCursor(GLFWwindow* w, double x, double y) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  glm::dvec2 p(x, y);
  if (self->haveCursor_) {
    self->pending_.cursorDelta += p - self->lastCursor_;
    self->dragged_ += glm::length(p - self->lastCursor_);
  }
  self->lastCursor_ = p;
  self->haveCursor_ = true;
}

void Window::onMouseButton(GLFWwindow* w, int button, int action, int /*mods*/) {
  if (button != GLFW_MOUSE_BUTTON_LEFT) return;
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(w, &x, &y);
  if (action == GLFW_PRESS) {
    self->pressedAt_ = glm::dvec2(x, y);
    self->dragged_ = 0.0;
    return;
  }
  // A press and release within a few cursor units is a click; more is an orbit drag.
  int width = 0, height = 0;
  glfwGetWindowSize(w, &width, &height);
  if (action == GLFW_RELEASE && self->dragged_ < 4.0 && width > 0 && height > 0)
    self->pending_.click = glm::dvec2(x / width, y / height);
}

void Window::onScroll(GLFWwindow* w, double /*dx*/, double dy) {
  static_cast<Window*>(glfwGetWindowUserPointer(w))->pending_.scroll += dy;
}

void Window::onFramebufferSize(GLFWwindow* w, int /*width*/, int /*height*/) {
  static_cast<Window*>(glfwGetWindowUserPointer(w))->resized_ = true;
}

} // namespace vkray
