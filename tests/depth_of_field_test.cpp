// Depth of field: the thin-lens camera (camera.aperture, camera.focus_distance). A lens of radius 0
// is the pinhole bit for bit; a bright point off the plane in focus spreads into the thin-lens
// circle of confusion, measured from the image's second moment against the formula in double; a
// flat target in the plane in focus stays as sharp as through the pinhole.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "image/image_io.h"
#include "render/gpu_scene.h"
#include "scene/scene_loader.h"
#include "test_support.h"
#include "util/error.h"

namespace vkray::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

// An emissive-like sphere (ambient 1, diffuse 0) of radius r at (0, 0, z) on black, seen from
// (0, 0, 5) looking at the origin: on the axis, so its image centres on the image's centre.
Scene brightSphere(double z, double r, double aperture, double fovY, int size, int spp) {
  Scene s = sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": )" +
                          std::to_string(fovY) + R"(, "aperture": )" + std::to_string(aperture) + R"( },
    "image": { "width": )" +
                          std::to_string(size) + R"(, "height": )" + std::to_string(size) + R"(, "ambient": [1, 1, 1] },
    "materials": { "white": { "color": [1, 1, 1], "ambient": 1, "diffuse": 0 } },
    "objects": [ { "type": "sphere", "material": "white", "center": [0, 0, )" +
                          std::to_string(z) + R"(], "radius": )" + std::to_string(r) + R"( } ] })");
  s.render.spp = spp;
  return s;
}

// The radial second moment of an image's brightness about a point (pixel units, pixel centres at
// i + 0.5), and the farthest lit pixel centre.
struct Spread {
  double energy = 0.0;
  double meanSquaredRadius = 0.0;
  double farthestLit = 0.0;
};

Spread spreadAbout(const Image& img, double cx, double cy) {
  Spread s;
  double moment = 0.0;
  for (std::uint32_t y = 0; y < img.height; ++y) {
    for (std::uint32_t x = 0; x < img.width; ++x) {
      double v = img.at(x, y).r;
      if (v <= 0.0) continue;
      double r2 = (x + 0.5 - cx) * (x + 0.5 - cx) + (y + 0.5 - cy) * (y + 0.5 - cy);
      s.energy += v;
      moment += v * r2;
      s.farthestLit = std::max(s.farthestLit, std::sqrt(r2));
    }
  }
  s.meanSquaredRadius = moment / s.energy;
  return s;
}

// Through a thin lens of radius A focused at distance f, a point at depth d reaches the plane in
// focus on a uniform disk of radius A |d - f| / d around its pinhole image (similar triangles: the
// ray from lens point o through the point lands at p f / d + o (1 - f / d)). The sphere's own image
// (radius r f / d there, the small-angle silhouette) is that disk's other summand, and the pixel's
// box filter a third: for independent summands the mean squared radii add, a uniform disk of radius
// R contributing R^2 / 2 and a unit pixel 1/12 per axis. So the measured circle of confusion is
// sqrt(2 (E[rho^2] - r_img^2 / 2 - 1/6)), in pixels.
struct Blur {
  double expected = 0.0; // circle of confusion, pixels
  double measured = 0.0;
  double sharpRadius = 0.0; // the sphere's pinhole image, pixels
  Spread spread;
};

Blur measureBlur(double z, double r, double aperture) {
  const double fovY = 20.0;
  const int size = 64;
  const int spp = 256;
  const double f = 5.0;     // |look_at - position|: the default focus distance
  const double d = 5.0 - z; // the sphere centre's depth
  const double pixelsPerUnit = size / (2.0 * f * std::tan(fovY * kPi / 360.0)); // at the focus plane
  Blur b;
  b.expected = aperture * std::abs(d - f) / d * pixelsPerUnit;
  b.sharpRadius = f * std::tan(std::asin(r / d)) * pixelsPerUnit;
  Image img = render(brightSphere(z, r, aperture, fovY, size, spp)).image;
  b.spread = spreadAbout(img, size / 2.0, size / 2.0);
  double m2 = b.spread.meanSquaredRadius - b.sharpRadius * b.sharpRadius / 2.0 - 1.0 / 6.0;
  b.measured = std::sqrt(2.0 * std::max(m2, 0.0));
  return b;
}

void expectBlurMatchesThinLens(double z, double r, double aperture) {
  Blur b = measureBlur(z, r, aperture);
  // 256 stratified samples per pixel over ~250 lit pixels: the second moment is good to well under
  // 1 %; the small-angle silhouette and the sphere's depth extent (r = 1 % of d) add about as much.
  // Stated tolerance: 3 % of the radius.
  EXPECT_NEAR(b.measured, b.expected, 0.03 * b.expected)
      << "z " << z << ": circle of confusion " << b.expected << " px, measured " << b.measured << " px";
  // A disk, not a spread-out glow: nothing lit beyond the two radii plus half a pixel's diagonal.
  EXPECT_LE(b.spread.farthestLit, b.expected * 1.02 + b.sharpRadius * 1.05 + std::sqrt(0.5));
  // The lens moves light, it neither adds nor loses any: the energy is the sharp image's area.
  EXPECT_NEAR(b.spread.energy, kPi * b.sharpRadius * b.sharpRadius, 0.05 * kPi * b.sharpRadius * b.sharpRadius);
  ::testing::Test::RecordProperty("coc_expected_px_z" + std::to_string(static_cast<int>(z * 10)),
                                  std::to_string(b.expected));
  ::testing::Test::RecordProperty("coc_measured_px_z" + std::to_string(static_cast<int>(z * 10)),
                                  std::to_string(b.measured));
}

TEST(RenderDepthOfField, NearPointBlursToTheThinLensCircle) {
  expectBlurMatchesThinLens(2.5, 0.03, 0.5);
}

TEST(RenderDepthOfField, FarPointBlursToTheThinLensCircle) {
  expectBlurMatchesThinLens(-5.0, 0.1, 0.5);
}

// A flat square in the plane in focus: every lens ray through a point of the image lands on the
// same point of the square as the pinhole ray (up to float rounding), with the same sub-pixel
// offsets, so the images agree but for the odd sample within rounding of an edge.
TEST(RenderDepthOfField, ThePlaneInFocusStaysSharp) {
  auto scene = [](double aperture) {
    Scene s = sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 20,
      "aperture": )" + std::to_string(aperture) +
                            R"( },
      "image": { "width": 48, "height": 48, "ambient": [1, 1, 1] },
      "materials": { "white": { "color": [1, 1, 1], "ambient": 1, "diffuse": 0 } },
      "objects": [ { "type": "polygon", "material": "white",
                     "vertices": [[-0.3, -0.2, 0], [0.25, -0.3, 0], [0.35, 0.3, 0], [-0.2, 0.25, 0]] } ] })");
    s.render.spp = 16;
    return s;
  };
  Image pinhole = render(scene(0.0)).image;
  Image lens = render(scene(0.5)).image;
  int differing = 0, edge = 0;
  double worst = 0.0;
  for (std::uint32_t y = 0; y < pinhole.height; ++y) {
    for (std::uint32_t x = 0; x < pinhole.width; ++x) {
      double a = pinhole.at(x, y).r, b = lens.at(x, y).r;
      edge += a > 0.0 && a < 1.0;
      differing += a != b;
      worst = std::max(worst, std::abs(a - b));
    }
  }
  ASSERT_GT(edge, 40); // the square's edges cross pixels
  EXPECT_LE(worst, 1.0 / 16.0 + 1e-6) << "at most one sample of a pixel lands differently";
  EXPECT_LE(differing * 10, edge) << differing << " pixels differ, of " << edge << " edge pixels";
  // The same square 1 unit off the plane in focus is visibly blurred (the test can tell).
  Scene off = scene(0.5);
  off.camera.focusDistance = 4.0;
  Image blurred = render(off).image;
  double blurWorst = 0.0;
  for (std::uint32_t y = 0; y < pinhole.height; ++y) {
    for (std::uint32_t x = 0; x < pinhole.width; ++x) {
      blurWorst = std::max(blurWorst, static_cast<double>(std::abs(pinhole.at(x, y).r - blurred.at(x, y).r)));
    }
  }
  EXPECT_GT(blurWorst, 0.25);
}

// aperture 0 is the pinhole: the bundled scenes render to the same bytes with the two keys as
// without them (the lens is compiled out: kSpecThinLens).
TEST(RenderDepthOfField, ApertureZeroIsThePinholeBitForBit) {
  for (const char* name : {"showcase.json", "glass.json", "meshes.json"}) {
    Scene s = loadScene(scenePath(name));
    s.render.width = 64;
    s.render.height = 48;
    s.render.spp = 4;
    std::vector<std::uint8_t> pinhole = encodePfm(render(s).image);
    s.camera.aperture = 0.0;
    s.camera.focusDistance = 1.75;
    EXPECT_EQ(encodePfm(render(s).image), pinhole) << name;
  }
}

// focus_distance unset is the distance to look_at: the same bytes as giving it.
TEST(RenderDepthOfField, FocusDistanceDefaultsToTheLookAtDistance) {
  Scene s = brightSphere(2.5, 0.1, 0.4, 30.0, 32, 4);
  ASSERT_FALSE(s.camera.focusDistance.has_value());
  EXPECT_EQ(s.camera.focusDistanceOrDefault(), 5.0);
  std::vector<std::uint8_t> defaulted = encodePfm(render(s).image);
  s.camera.focusDistance = 5.0;
  EXPECT_EQ(encodePfm(render(s).image), defaulted);
  s.camera.focusDistance = 3.0;
  EXPECT_NE(encodePfm(render(s).image), defaulted);
}

std::string loadError(const std::string& json) {
  try {
    loadSceneFromString(json, "lens.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SceneDepthOfField, LoadsTheLensKeys) {
  Scene s = loadSceneFromString(
      R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 1], "aperture": 0.25, "focus_distance": 3.5 } })",
      "lens.json");
  EXPECT_EQ(s.camera.aperture, 0.25);
  EXPECT_EQ(s.camera.focusDistanceOrDefault(), 3.5);
  Scene d = loadSceneFromString(R"({ "camera": { "position": [0, 3, 4], "look_at": [0, 0, 0] } })", "lens.json");
  EXPECT_EQ(d.camera.aperture, 0.0);
  EXPECT_FALSE(d.camera.focusDistance.has_value());
  EXPECT_DOUBLE_EQ(d.camera.focusDistanceOrDefault(), 5.0);
}

TEST(SceneDepthOfField, RefusesABadLensWithItsPath) {
  std::string e = loadError(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "aperture": -1 } })");
  EXPECT_NE(e.find("camera.aperture"), std::string::npos) << e;
  EXPECT_NE(e.find("-1"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  e = loadError(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "focus_distance": 0 } })");
  EXPECT_NE(e.find("camera.focus_distance"), std::string::npos) << e;
  EXPECT_NE(e.find("> 0"), std::string::npos) << e;
  e = loadError(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "animation": { "frames": 2, "camera": [ { "frame": 0, "aperture": 0.1 } ] } })");
  EXPECT_NE(e.find("aperture"), std::string::npos) << e;
  EXPECT_NE(e.find("not animated"), std::string::npos) << e;
}

} // namespace
} // namespace vkray::test
