// The viewer's camera control maths (host only, no window): orbit, pan, zoom, fly, reset, and the
// camera JSON that users paste into scenes.
#include <cmath>

#include <gtest/gtest.h>

#include "render/gpu_scene.h"
#include "scene/scene_loader.h"
#include "viewer/camera_controller.h"

namespace vkray::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

Camera showcaseCamera() {
  Camera c;
  c.position = {0.0, 2.2, 7.5};
  c.lookAt = {0.0, 0.9, 0.0};
  c.up = {0.0, 1.0, 0.0};
  c.fovY = 45.0;
  return c;
}

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tol, const char* what) {
  EXPECT_NEAR(glm::length(a - b), 0.0, tol)
      << what << ": (" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", " << b.y << ", " << b.z << ")";
}

// Pixel coordinates (x right, y down) where the camera sees point p, through the renderer's own
// camera frame (gpu_scene.h), so the tests check what the user sees.
glm::dvec2 project(const Camera& camera, const glm::dvec3& p, std::uint32_t w, std::uint32_t h) {
  CameraFrame f = makeCameraFrame(camera, w, h);
  glm::dvec3 d = p - camera.position;
  double z = glm::dot(d, f.forward);
  double x = glm::dot(d, f.right) / (z * f.tanHalfFovY * f.aspect);
  double y = glm::dot(d, f.up) / (z * f.tanHalfFovY);
  return {(x + 1.0) * 0.5 * w, (1.0 - y) * 0.5 * h};
}

TEST(Camera, StartsAtTheSceneCameraExactly) {
  CameraController c(showcaseCamera());
  EXPECT_EQ(c.camera().position, showcaseCamera().position);
  EXPECT_EQ(c.camera().lookAt, showcaseCamera().lookAt);
  EXPECT_EQ(c.mode(), CameraMode::Orbit);
}

TEST(Camera, OrbitKeepsTheTargetAndTheDistance) {
  CameraController c(showcaseCamera());
  double d0 = c.distance();
  for (int i = 0; i < 50; ++i) {
    c.orbit(0.13, (i % 7 - 3) * 0.05);
    EXPECT_NEAR(c.distance(), d0, 1e-9 * d0);
    EXPECT_EQ(c.camera().lookAt, showcaseCamera().lookAt);
  }
}

TEST(Camera, YawTurnsAboutTheUpAxis) {
  CameraController c(showcaseCamera());
  double height = c.camera().position.y;
  c.orbit(kPi / 2, 0.0);
  // A quarter turn about +y takes the eye from +z to +x (right-handed), at the same height.
  EXPECT_NEAR(c.camera().position.y, height, 1e-12);
  EXPECT_NEAR(c.camera().position.x, 7.5, 1e-12);
  EXPECT_NEAR(c.camera().position.z, 0.0, 1e-12);
  c.orbit(3 * kPi / 2, 0.0); // the rest of the full turn
  expectNear(c.camera().position, showcaseCamera().position, 1e-12, "full turn");
}

TEST(Camera, PositivePitchRaisesTheEye) {
  CameraController c(showcaseCamera());
  double y0 = c.camera().position.y;
  c.orbit(0.0, 0.2);
  EXPECT_GT(c.camera().position.y, y0);
  c.orbit(0.0, -0.4);
  EXPECT_LT(c.camera().position.y, y0);
}

TEST(Camera, PitchStopsShortOfThePoles) {
  CameraController c(showcaseCamera());
  for (double pitch : {10.0, -10.0}) {
    c.orbit(0.0, pitch); // far past straight up / straight down
    glm::dvec3 f = c.forward();
    double angle = std::acos(std::abs(glm::dot(f, glm::dvec3(0, 1, 0))));
    EXPECT_NEAR(angle, CameraController::kPoleMargin, 1e-9) << "pitch " << pitch;
    // The view stays well defined: the renderer gets a right vector, no NaN.
    CameraFrame frame = makeCameraFrame(c.camera(), 64, 48);
    EXPECT_TRUE(std::isfinite(frame.right.x) && std::isfinite(frame.up.y));
    EXPECT_NEAR(glm::length(frame.right), 1.0, 1e-9);
  }
}

TEST(Camera, PanMovesThePointUnderTheCursorWithTheCursor) {
  // A point at the target's depth, seen at pixel p, is seen at p + drag after the pan.
  const std::uint32_t w = 640, h = 480;
  CameraController c(showcaseCamera());
  c.orbit(0.4, 0.3); // a view not aligned with the axes
  glm::dvec3 target = c.camera().lookAt;
  glm::dvec3 p = target + 0.5 * c.right(); // on the target's depth plane
  glm::dvec2 before = project(c.camera(), p, w, h);
  glm::dvec3 dir0 = c.forward();
  c.pan(37.0, -21.0, h);
  glm::dvec2 after = project(c.camera(), p, w, h);
  EXPECT_NEAR(after.x - before.x, 37.0, 1e-6);
  EXPECT_NEAR(after.y - before.y, -21.0, 1e-6);
  // Panning translates: same direction, same distance to the (moved) target.
  expectNear(c.forward(), dir0, 1e-12, "view direction");
  EXPECT_NEAR(glm::length(c.camera().lookAt - c.camera().position),
              glm::length(showcaseCamera().lookAt - showcaseCamera().position), 1e-9);
}

TEST(Camera, ZoomScalesTheDistanceAndNeverReachesTheTarget) {
  CameraController c(showcaseCamera());
  double d0 = c.distance();
  glm::dvec3 dir0 = c.forward();
  c.zoom(1.0);
  EXPECT_NEAR(c.distance(), d0 / CameraController::kZoomStep, 1e-12);
  c.zoom(-2.0);
  EXPECT_NEAR(c.distance(), d0 * CameraController::kZoomStep, 1e-12);
  c.zoom(1000.0);
  EXPECT_GE(c.distance(), CameraController::kMinDistance * 0.999);
  expectNear(c.forward(), dir0, 1e-9, "zoom keeps the direction");
  EXPECT_EQ(c.camera().lookAt, showcaseCamera().lookAt);
}

TEST(Camera, FlyLookTurnsAboutTheEye) {
  CameraController c(showcaseCamera());
  c.setMode(CameraMode::Fly);
  double d0 = c.distance();
  c.look(kPi / 2, 0.0); // turn left a quarter: looking down -z becomes looking down -x
  EXPECT_EQ(c.camera().position, showcaseCamera().position);
  EXPECT_NEAR(c.distance(), d0, 1e-12);
  EXPECT_LT(c.forward().x, -0.9);
  double y0 = c.forward().y;
  c.look(0.0, 0.2); // look up
  EXPECT_GT(c.forward().y, y0);
}

TEST(Camera, FlyMoveTranslatesEyeAndTarget) {
  CameraController c(showcaseCamera());
  c.setMode(CameraMode::Fly);
  glm::dvec3 f = c.forward(), r = c.right();
  c.move({1.0, 2.0, 3.0});
  glm::dvec3 expected = showcaseCamera().position + r * 1.0 + glm::dvec3(0, 2, 0) + f * 3.0;
  expectNear(c.camera().position, expected, 1e-12, "eye");
  expectNear(c.camera().lookAt - c.camera().position, showcaseCamera().lookAt - showcaseCamera().position, 1e-12,
             "view unchanged");
}

TEST(Camera, InputDragsOrbitInOrbitModeAndLookInFlyMode) {
  CameraInput in;
  in.drag = {100.0, 0.0};
  in.orbitDrag = true;
  in.viewportHeight = 480;
  CameraController orbit(showcaseCamera());
  EXPECT_TRUE(orbit.apply(in));
  // Dragging right swings the eye to the left (-x), the scene turns with the cursor.
  EXPECT_LT(orbit.camera().position.x, 0.0);
  EXPECT_EQ(orbit.camera().lookAt, showcaseCamera().lookAt);
  // One viewport height of drag is kRadiansPerViewport.
  in.drag = {0.0, 0.0};
  EXPECT_FALSE(orbit.apply(in));

  CameraController fly(showcaseCamera());
  fly.setMode(CameraMode::Fly);
  in.drag = {100.0, 0.0};
  EXPECT_TRUE(fly.apply(in));
  EXPECT_EQ(fly.camera().position, showcaseCamera().position);
  EXPECT_GT(fly.forward().x, 0.0); // dragging right looks right
}

TEST(Camera, FlyKeysMoveAtTheirSpeedOnlyInFlyMode) {
  CameraInput in;
  in.move = {0.0, 0.0, 1.0};
  in.dtSeconds = 0.5;
  CameraController orbit(showcaseCamera());
  EXPECT_FALSE(orbit.apply(in)) << "WASD does nothing in orbit mode";
  CameraController fly(showcaseCamera());
  fly.setMode(CameraMode::Fly);
  double speed = fly.flySpeed();
  ASSERT_TRUE(fly.apply(in));
  EXPECT_NEAR(glm::length(fly.camera().position - showcaseCamera().position), speed * 0.5, 1e-12);
  in.fast = true;
  CameraController fast(showcaseCamera());
  fast.setMode(CameraMode::Fly);
  ASSERT_TRUE(fast.apply(in));
  EXPECT_NEAR(glm::length(fast.camera().position - showcaseCamera().position), 4.0 * speed * 0.5, 1e-12);
}

TEST(Camera, ResetReturnsToTheSceneCameraExactly) {
  CameraController c(showcaseCamera());
  c.orbit(1.0, 0.3);
  c.pan(10, 10, 480);
  c.zoom(3);
  c.setMode(CameraMode::Fly);
  c.move({1, 1, 1});
  c.reset();
  EXPECT_EQ(c.camera().position, showcaseCamera().position);
  EXPECT_EQ(c.camera().lookAt, showcaseCamera().lookAt);
  EXPECT_EQ(c.camera().up, showcaseCamera().up);
}

TEST(Camera, NewHomeIsFollowedOnlyWhenAsked) {
  CameraController c(showcaseCamera());
  c.orbit(0.5, 0.0);
  Camera moved = c.camera();
  Camera home = showcaseCamera();
  home.position.z = 9.0;
  c.setHome(home, false);
  EXPECT_EQ(c.camera().position, moved.position);
  c.reset();
  EXPECT_EQ(c.camera().position, home.position);
}

TEST(Camera, JsonReadsBackThroughTheSceneLoaderExactly) {
  CameraController c(showcaseCamera());
  c.orbit(0.7, 0.2);
  c.pan(13, 5, 480);
  c.zoom(0.5);
  Camera want = c.camera();
  want.fovY = 37.25;
  std::string json = cameraJson(want);
  EXPECT_EQ(json.find('\n'), std::string::npos) << "one line, to paste";
  Scene s = loadSceneFromString("{ " + json + " }", "camera.json");
  // Shortest round-trip formatting: every double reads back bit for bit.
  EXPECT_EQ(s.camera.position, want.position);
  EXPECT_EQ(s.camera.lookAt, want.lookAt);
  EXPECT_EQ(s.camera.up, want.up);
  EXPECT_EQ(s.camera.fovY, want.fovY);
}

TEST(Camera, JsonOfTheShowcaseCameraIsWhatAPersonWouldWrite) {
  EXPECT_EQ(cameraJson(showcaseCamera()),
            R"("camera": { "position": [0, 2.2, 7.5], "look_at": [0, 0.9, 0], "up": [0, 1, 0], "fov_y": 45 })");
}

} // namespace
} // namespace vkray::test
