// Camera control maths (see camera_controller.h).
#include "viewer/camera_controller.h"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace vkray {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Rodrigues' rotation of v about the unit axis k.
glm::dvec3 rotateAbout(const glm::dvec3& v, double angle, const glm::dvec3& k) {
  double c = std::cos(angle);
  double s = std::sin(angle);
  return v * c + glm::cross(k, v) * s + k * (glm::dot(k, v) * (1.0 - c));
}

glm::dvec3 upAxis(const Camera& camera) {
  return glm::normalize(camera.up);
}

// A unit vector perpendicular to the unit vector u.
glm::dvec3 anyPerpendicular(const glm::dvec3& u) {
  glm::dvec3 axis = std::abs(u.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  return glm::normalize(glm::cross(u, axis));
}

// Tilts the unit vector v towards (positive angle) or away from the unit axis u, keeping it at
// least kPoleMargin away from either pole so that v and u never become parallel.
glm::dvec3 tiltTowardsAxis(const glm::dvec3& v, double angle, const glm::dvec3& u, double margin) {
  double theta = std::acos(std::clamp(glm::dot(v, u), -1.0, 1.0));
  double target = std::clamp(theta - angle, margin, kPi - margin);
  glm::dvec3 horizontal = v - u * glm::dot(v, u);
  double len = glm::length(horizontal);
  horizontal = len > 1e-12 ? horizontal / len : anyPerpendicular(u);
  return u * std::cos(target) + horizontal * std::sin(target);
}

void appendNumber(std::string& out, double v) {
  char buffer[32];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  out.append(buffer, ec == std::errc() ? end : buffer);
}

void appendVec3(std::string& out, const glm::dvec3& v) {
  out += '[';
  for (int i = 0; i < 3; ++i) {
    if (i > 0) out += ", ";
    appendNumber(out, v[i]);
  }
  out += ']';
}

} // namespace

CameraController::CameraController(const Camera& home) : home_(home), camera_(home) {}

void CameraController::setHome(const Camera& home, bool resetView) {
  home_ = home;
  if (resetView) camera_ = home;
}

double CameraController::distance() const {
  return glm::length(camera_.lookAt - camera_.position);
}

glm::dvec3 CameraController::forward() const {
  return glm::normalize(camera_.lookAt - camera_.position);
}

glm::dvec3 CameraController::right() const {
  // The same fallback as the renderer's camera frame when `up` is parallel to the view.
  glm::dvec3 f = forward();
  const glm::dvec3 candidates[] = {camera_.up, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
  for (const auto& u : candidates) {
    glm::dvec3 c = glm::cross(f, u);
    double len = glm::length(c);
    if (len > 1e-9 * glm::length(u)) return c / len;
  }
  return {1, 0, 0};
}

void CameraController::orbit(double yaw, double pitch) {
  const glm::dvec3 u = upAxis(camera_);
  double d = distance();
  glm::dvec3 offset = (camera_.position - camera_.lookAt) / d;
  if (yaw != 0.0) offset = rotateAbout(offset, yaw, u);
  if (pitch != 0.0) offset = tiltTowardsAxis(offset, pitch, u, kPoleMargin);
  camera_.position = camera_.lookAt + offset * d;
}

void CameraController::look(double yaw, double pitch) {
  const glm::dvec3 u = upAxis(camera_);
  double d = distance();
  glm::dvec3 f = forward();
  if (yaw != 0.0) f = rotateAbout(f, yaw, u);
  if (pitch != 0.0) f = tiltTowardsAxis(f, pitch, u, kPoleMargin);
  camera_.lookAt = camera_.position + f * d;
}

void CameraController::pan(double dxPixels, double dyPixels, double viewportHeight) {
  // World size of one pixel at the target's depth: the view plane there is 2 d tan(fov/2) tall.
  double worldPerPixel = 2.0 * distance() * std::tan(glm::radians(camera_.fovY) * 0.5) / std::max(viewportHeight, 1.0);
  glm::dvec3 r = right();
  glm::dvec3 screenUp = glm::cross(r, forward());
  // The scene follows the cursor, so the camera moves the other way.
  glm::dvec3 delta = (-dxPixels * r + dyPixels * screenUp) * worldPerPixel;
  camera_.position += delta;
  camera_.lookAt += delta;
}

void CameraController::zoom(double steps) {
  double d = distance();
  double next = std::max(d * std::pow(kZoomStep, -steps), kMinDistance);
  camera_.position = camera_.lookAt - forward() * next;
}

void CameraController::move(const glm::dvec3& rightUpForward) {
  glm::dvec3 delta = right() * rightUpForward.x + upAxis(camera_) * rightUpForward.y + forward() * rightUpForward.z;
  camera_.position += delta;
  camera_.lookAt += delta;
}

double CameraController::flySpeed() const {
  return std::max(distance(), 1e-3) * 0.75;
}

bool CameraController::apply(const CameraInput& in) {
  const Camera before = camera_;
  const double radiansPerPixel = kRadiansPerViewport / std::max(in.viewportHeight, 1.0);
  const bool dragged = in.drag.x != 0.0 || in.drag.y != 0.0;
  if (dragged && in.panDrag) {
    pan(in.drag.x, in.drag.y, in.viewportHeight);
  } else if (dragged && in.orbitDrag) {
    if (mode_ == CameraMode::Orbit) {
      // The scene turns with the cursor: dragging right swings the eye left, dragging down raises it.
      orbit(-in.drag.x * radiansPerPixel, in.drag.y * radiansPerPixel);
    } else {
      // Mouse look: dragging right turns right, dragging down looks down.
      look(-in.drag.x * radiansPerPixel, -in.drag.y * radiansPerPixel);
    }
  }
  if (in.scroll != 0.0) zoom(in.scroll);
  if (mode_ == CameraMode::Fly && in.move != glm::dvec3(0.0) && in.dtSeconds > 0.0) {
    double step = flySpeed() * in.dtSeconds * (in.fast ? 4.0 : 1.0);
    move(in.move * step);
  }
  return camera_.position != before.position || camera_.lookAt != before.lookAt;
}

std::string cameraJson(const Camera& camera) {
  std::string out = "\"camera\": { \"position\": ";
  appendVec3(out, camera.position);
  out += ", \"look_at\": ";
  appendVec3(out, camera.lookAt);
  out += ", \"up\": ";
  appendVec3(out, camera.up);
  out += ", \"fov_y\": ";
  appendNumber(out, camera.fovY);
  if (camera.aperture > 0.0) { // a pinhole's line stays as it was
    out += ", \"aperture\": ";
    appendNumber(out, camera.aperture);
  }
  if (camera.focusDistance) {
    out += ", \"focus_distance\": ";
    appendNumber(out, *camera.focusDistance);
  }
  out += " }";
  return out;
}

} // namespace vkray
