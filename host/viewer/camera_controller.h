// The viewer's camera control as pure maths on a scene Camera: orbit, pan and zoom about a target,
// fly mode (turn about the eye, move along the view), reset, and the camera as scene-file JSON.
// No window or input library here, so every rule is unit-tested on the host (tests/camera_test.cpp).
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace vkray {

enum class CameraMode { Orbit, Fly };

// What one frame of input asks of the camera, already stripped of the window library's key codes.
struct CameraInput {
  glm::dvec2 drag{0.0};      // pixels the cursor moved with a button held (x right, y down)
  bool orbitDrag = false;    // the drag orbits (orbit mode) or turns the view (fly mode)
  bool panDrag = false;      // the drag pans
  double scroll = 0.0;       // wheel steps, positive away from the user
  glm::dvec3 move{0.0};      // fly keys held: x right, y up, z forward, each -1..1
  bool fast = false;         // fly 4x faster (shift)
  double dtSeconds = 0.0;    // time since the previous frame, for fly speed
  double viewportHeight = 1; // pixels, for angle and pan scale
};

class CameraController {
public:
  // Each wheel step moves the eye this factor closer to (or farther from) the target.
  static constexpr double kZoomStep = 1.1;
  // Dragging across the whole viewport height turns the view by this many radians.
  static constexpr double kRadiansPerViewport = 3.14159265358979323846;
  // The eye never gets closer to the up axis through the target than this angle (no flip at the poles).
  static constexpr double kPoleMargin = 1e-3;
  static constexpr double kMinDistance = 1e-4;

  explicit CameraController(const Camera& home);

  const Camera& camera() const { return camera_; }
  const Camera& home() const { return home_; }
  CameraMode mode() const { return mode_; }
  void setMode(CameraMode mode) { mode_ = mode; }

  // The scene's camera changed (a reloaded file): the new home; the view follows it when asked.
  void setHome(const Camera& home, bool resetView);
  // Back to the scene's camera, exactly.
  void reset() { camera_ = home_; }

  // Turns the eye about the target: yaw about the up axis, pitch towards it (radians; positive pitch
  // raises the eye). Distance to the target is preserved.
  void orbit(double yaw, double pitch);
  // Moves eye and target in the view plane; dx, dy in pixels of a viewport `viewportHeight` tall
  // (y down), scaled so that a point at the target's depth follows the cursor.
  void pan(double dxPixels, double dyPixels, double viewportHeight);
  // Wheel steps: positive moves the eye towards the target (never reaching it).
  void zoom(double steps);
  // Fly mode: turns the view about the eye (radians; positive pitch looks up). The target stays at
  // the same distance ahead, so switching back to orbit turns about what is in front.
  void look(double yaw, double pitch);
  // Fly mode: moves eye and target by x along the view's right, y along the up axis and z along the
  // view direction (world units).
  void move(const glm::dvec3& rightUpForward);

  // Applies one frame of input for the current mode. Returns true if the camera changed.
  bool apply(const CameraInput& input);

  // Fly speed in world units per second: proportional to the distance to the target, so small and
  // large scenes feel alike.
  double flySpeed() const;

  double distance() const;
  glm::dvec3 forward() const; // unit, eye to target
  glm::dvec3 right() const;   // unit, perpendicular to forward and up

private:
  Camera home_;
  Camera camera_;
  CameraMode mode_ = CameraMode::Orbit;
};

// The camera as the scene file's "camera" member, to paste into a scene:
// "camera": { "position": [...], "look_at": [...], "up": [...], "fov_y": 45 }
// Numbers are written in their shortest form that reads back to the same double.
std::string cameraJson(const Camera& camera);

} // namespace vkray
