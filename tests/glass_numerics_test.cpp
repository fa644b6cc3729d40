// Thin and touching glass through the real kernel (trace.comp on lavapipe): a slab 1e-5 thick, two
// glass spheres touching at a point, a glass ball and a water ball whose surfaces coincide, and
// refraction within 1e-3 rad of the critical angle 1e4 from the origin. Properties, not pixels: no
// NaN, no light from nowhere (every pixel under an energy bound derived from the materials), no lost
// branch (thin and touching render as their thick and separated twins; total internal reflection
// decided by the angle alone). Each case prints one line of figures.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "numerics_support.h"
#include "reference.h"
#include "test_support.h"

namespace vkray::test::numerics {
namespace {

float brightest(const Image& image) {
  float worst = 0.0f;
  for (const auto& p : image.pixels) worst = std::max({worst, p.x, p.y, p.z});
  return worst;
}

bool allFinite(const Image& image) {
  for (const auto& p : image.pixels)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  return true;
}

// Glass that adds no light of its own (ambient, diffuse, specular 0) and splits each ray's weight
// into reflection + transmission = 1 with no absorption: a node of the ray tree passes on at most its
// own weight, so no pixel can exceed the brightest local colour or background its tree reaches.
const char* kMaterials = R"(
      "floor": { "color": [0.9, 0.9, 0.85], "ambient": 0.4, "diffuse": 0.6,
                 "checker": { "color2": [0.2, 0.1, 0.1], "scale": 0.25 } },
      "wall": { "color": [0.9, 0.5, 0.2], "ambient": 1, "diffuse": 0,
                "checker": { "color2": [0.1, 0.3, 0.8], "scale": 0.25 } },
      "glass": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "specular": 0, "reflection": 0.05,
                 "transmission": 0.95, "ior": 1.5 },
      "water": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "specular": 0, "transmission": 1, "ior": 1.33 })";

// The energy bound of scenes built from kMaterials with ambient light A = 0.5, one light of colour
// 0.8 and background 0.7: the floor's local colour is at most ambient * base * A + diffuse * base *
// light * (n.l <= 1) = 0.4 * 0.9 * 0.5 + 0.6 * 0.9 * 0.8 = 0.612, the wall's 1 * 0.9 * 0.5 = 0.45,
// glass and water add nothing and pass on at most their weight (attenuated shadows only remove
// light). So every pixel is <= max(background, 0.612, 0.45) = 0.7, plus float rounding of a sum of
// at most a few hundred leaves (1e-5).
constexpr float kEnergyBound = 0.7f + 1e-5f;

std::string sceneHead(const std::string& camera, const std::string& lookAt, double fov, int maxDepth) {
  return R"({ "camera": { "position": )" + camera + R"(, "look_at": )" + lookAt + R"(, "fov_y": )" +
         std::to_string(fov) + R"( },
    "image": { "width": 96, "height": 72 }, "background": [0.7, 0.7, 0.7], "ambient": [0.5, 0.5, 0.5],
    "render": { "max_depth": )" +
         std::to_string(maxDepth) + R"(, "bailout": 0, "transmissive_shadows": "attenuated" },
    "materials": {)" +
         kMaterials +
         R"( },
    "lights": [ { "position": [-3, 6, 4], "color": [0.8, 0.8, 0.8] } ],
    "objects": [
      { "type": "plane", "normal": [0, 1, 0], "point": [0, 0, 0], "material": "floor" },
      { "type": "polygon", "material": "wall", "vertices": [[-8, 0, -3], [8, 0, -3], [8, 6, -3], [-8, 6, -3]] })";
}

// ---- 1. Thin slab --------------------------------------------------------------------------------

// A glass slab of two parallel square polygons (outward normals), tilted towards the camera,
// `thickness` thick; with `backFace` false only its front face (a slab whose back face is lost).
Scene slabScene(double thickness, bool backFace = true) {
  const dvec3 n = glm::normalize(dvec3(0.5, 0.3, 1.0)); // tilted: a ray that skips the back face bends
  const dvec3 u = glm::normalize(glm::cross(dvec3(0, 1, 0), n));
  const dvec3 v = glm::cross(n, u); // u x v = n: counter-clockwise seen from the front
  const dvec3 c(0.0, 1.0, 0.5);
  auto quad = [&](const dvec3& centre, bool front) {
    dvec3 p[4] = {centre - u - v, centre + u - v, centre + u + v, centre - u + v};
    std::string s = R"(, { "type": "polygon", "material": "glass", "vertices": [)";
    for (int i = 0; i < 4; ++i) s += (i ? ", " : "") + point(p[front ? i : 3 - i]);
    return s + "] }";
  };
  std::string objects = quad(c, true);
  if (backFace) objects += quad(c - thickness * n, false);
  return sceneFromJson(sceneHead("[0.3, 1.4, 5]", "[0, 0.9, 0]", 40, 8) + objects + "] }");
}

// A parallel slab without absorption transmits the same colour whatever its thickness (the two
// faces see the same angles), and moves the transmitted ray sideways by at most about 0.6 times the
// thickness: 6e-3 at 1e-2, a tenth of a pixel's footprint (0.07) on the wall behind. So the thick
// and thin slabs differ only in pixels whose ray passes within that of a checker edge, a silhouette
// or a shadow edge (internal reflections move by 2 t each): under 1 % of the pixels at 96 x 72
// (measured 0.3 %). The bound, 1 %, leaves no room for a lost back face (control: the front face
// alone changes > 20 % of the pixels; measured 23 %).
TEST(NumericsGlass, SlabTenMicronsThickRendersAsTheThickSlab) {
  for (dvec3 shift : {dvec3(0.0), dvec3(1e4, -1e4, 1e4)}) {
    Image thick = render(transformed(slabScene(1e-2), 1.0, shift)).image;
    RenderResult thin = render(transformed(slabScene(1e-5), 1.0, shift));
    Image frontOnly = render(transformed(slabScene(1e-5, false), 1.0, shift)).image;
    double share = shareOff(thick, thin.image);
    double lost = shareOff(thick, frontOnly);
    float worst = brightest(thin.image);
    std::printf("[ numerics ] slab 1e-5 vs 1e-2 thick, shift %-20s %5.2f %% of pixels off by > 6/255 (front face "
                "alone: %5.2f %%), brightest %.4f <= %.4f, %llu non-finite\n",
                str(shift).c_str(), 100.0 * share, 100.0 * lost, worst, kEnergyBound,
                static_cast<unsigned long long>(thin.stats.nonFinite));
    EXPECT_LE(share, 0.01) << "shift " << str(shift);
    EXPECT_GT(lost, 0.20) << "the comparison must see a slab whose back face is lost";
    EXPECT_EQ(thin.stats.nonFinite, 0u);
    EXPECT_TRUE(allFinite(thin.image));
    EXPECT_LE(worst, kEnergyBound);
    EXPECT_EQ(thin.stats.stackOverflow, 0u);
  }
}

// ---- 2. Touching spheres ---------------------------------------------------------------------------

Scene twoSpheres(double gap) {
  const double r = 0.7, x = r + 0.5 * gap;
  return sceneFromJson(sceneHead("[0, 1.2, 5]", "[0, 0.7, 0]", 40, 8) + R"(, { "type": "sphere", "center": )" +
                       point(dvec3(-x, r, 0)) + R"(, "radius": 0.7, "material": "glass" },
      { "type": "sphere", "center": )" +
                       point(dvec3(x, r, 0)) + R"(, "radius": 0.7, "material": "glass" } ] })");
}

TEST(NumericsGlass, TouchingSpheresRenderAsSpheresApartAwayFromTheContact) {
  Scene touchingScene = twoSpheres(0.0);
  RenderResult touching = render(touchingScene);
  Image apart = render(twoSpheres(1e-3)).image;
  // Excused: pixels whose eye ray passes within 0.1 of the contact point (0, 0.7, 0), two pixels'
  // footprint there (12 pixels); what the contact itself looks like depends on the gap.
  ReferenceTracer ref(touchingScene);
  const dvec3 contact(0.0, 0.7, 0.0);
  std::size_t compared = 0, off = 0;
  for (std::uint32_t y = 0; y < touching.image.height; ++y) {
    for (std::uint32_t x = 0; x < touching.image.width; ++x) {
      dvec3 o = ref.eyeOrigin(), d = glm::normalize(ref.eyeDirection(x + 0.5, y + 0.5));
      if (glm::length(glm::cross(contact - o, d)) < 0.1) continue;
      ++compared;
      off += pixelOff(touching.image.at(x, y), apart.at(x, y));
    }
  }
  double share = static_cast<double>(off) / static_cast<double>(compared);
  float worst = brightest(touching.image);
  std::printf("[ numerics ] touching glass spheres vs 1e-3 apart: %5.2f %% of %zu pixels off by > 6/255, brightest "
              "%.4f <= %.4f, %llu non-finite, %llu refracted rays\n",
              100.0 * share, compared, worst, kEnergyBound, static_cast<unsigned long long>(touching.stats.nonFinite),
              static_cast<unsigned long long>(touching.stats.refraction));
  // Moving each sphere by 5e-4 moves what is seen through it by about that times the sphere's
  // magnification (< 10 away from the rims), still a tenth of a pixel: only pixels near checker
  // and shadow edges may change. Bound 2 % (measured 1.0 %).
  EXPECT_LE(share, 0.02);
  EXPECT_EQ(touching.stats.nonFinite, 0u);
  EXPECT_TRUE(allFinite(touching.image));
  EXPECT_LE(worst, kEnergyBound);
  EXPECT_EQ(touching.stats.stackOverflow, 0u);
  EXPECT_EQ(touching.stats.truncated, 0u);
  EXPECT_GT(touching.stats.refraction, 0u);
}

// ---- 3. Coincident surfaces ------------------------------------------------------------------------

Scene coincidentBalls(const std::string& first, const std::string& second) {
  std::string objects;
  for (const std::string& m : {first, second})
    if (!m.empty())
      objects += R"(, { "type": "sphere", "center": [0, 0.8, 0.3], "radius": 0.8, "material": ")" + m + R"(" })";
  return sceneFromJson(sceneHead("[0.2, 1.3, 5]", "[0, 0.8, 0]", 35, 8) + objects + "] }");
}

// Coincident surfaces: water (1.33) and glass (1.5) spheres of the same centre and radius, the
// water listed first. They share every float value, so each ray meets both at the same t bit for
// bit, and the kernel keeps the first primitive it tests at a tie (traceScene tests spheres in
// order, replacing a hit only when strictly nearer). Entry and exit are then both the first
// sphere's, so the pair renders exactly as that sphere alone: one interface, air|water, entered and
// left through the same medium's stack entry. What must not happen is a mix: entering the water and
// leaving through the glass (n1 = 1.5 for a ray in water, and the water left on the media stack), or
// entering twice. Checked both ways round: the image equals the first-listed ball alone to 1e-6
// (float noise only; measured 0), and the two single balls differ in > 10 % of the pixels, so the
// comparison can tell which interface was used.
TEST(NumericsGlass, CoincidentGlassAndWaterBallsAreOneInterface) {
  RenderResult both = render(coincidentBalls("water", "glass"));
  RenderResult again = render(coincidentBalls("water", "glass"));
  RenderResult swapped = render(coincidentBalls("glass", "water"));
  Image glass = render(coincidentBalls("glass", "")).image;
  Image water = render(coincidentBalls("water", "")).image;
  auto maxDiff = [](const Image& a, const Image& b) {
    float worst = 0.0f;
    for (std::size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(a.pixels[i][c] - b.pixels[i][c]));
    return worst;
  };
  float vsWater = maxDiff(both.image, water), swappedVsGlass = maxDiff(swapped.image, glass);
  double glassVsWater = shareOff(glass, water);
  float worst = std::max(brightest(both.image), brightest(swapped.image));
  std::printf("[ numerics ] coincident water+glass balls: largest difference from water alone %.1e, glass+water "
              "from glass alone %.1e (the two alone differ in %5.2f %% of pixels); brightest %.4f <= %.4f, %llu "
              "non-finite\n",
              vsWater, swappedVsGlass, 100.0 * glassVsWater, worst, kEnergyBound,
              static_cast<unsigned long long>(both.stats.nonFinite + swapped.stats.nonFinite));
  EXPECT_LE(vsWater, 1e-6f) << "water+glass must render as the water ball alone";
  EXPECT_LE(swappedVsGlass, 1e-6f) << "glass+water must render as the glass ball alone";
  EXPECT_GT(glassVsWater, 0.10);
  EXPECT_EQ(both.stats.nonFinite + swapped.stats.nonFinite, 0u);
  EXPECT_TRUE(allFinite(both.image) && allFinite(swapped.image));
  EXPECT_LE(worst, kEnergyBound);
  EXPECT_EQ(both.image.pixels, again.image.pixels) << "two renders of one scene must be bit-identical";
  EXPECT_EQ(both.stats.stackOverflow + swapped.stats.stackOverflow, 0u);
}

// ---- 4. Grazing refraction at the critical angle, 1e4 from the origin ------------------------------

// The camera inside glass (below the interface y = 0, whose polygon faces up into the air) looks up
// at the critical angle asin(1/1.5) from the normal, through a lens of 2e-3 rad: every eye ray meets
// the interface within 1e-3 rad of the critical angle. Refracted rays leave grazing and meet a red
// wall; totally reflected ones go down to a floor with no red in it. So a pixel has red exactly
// when its ray was refracted.
// z = 0.125: the eye looks along the middle of a row of the wall's and the floor's checker cells.
const dvec3 kCriticalEye(0.0, -1.0, 0.125);

Scene criticalScene(const dvec3& shift) {
  const dvec3 eye = kCriticalEye;
  const double critical = std::asin(1.0 / 1.5);
  const dvec3 look = eye + dvec3(std::sin(critical), std::cos(critical), 0.0);
  auto at = [&](double x, double y, double z) { return point(shift + dvec3(x, y, z)); };
  return sceneFromJson(R"({ "camera": { "position": )" + point(shift + eye) + R"(, "look_at": )" + point(shift + look) +
                       R"(, "fov_y": )" + std::to_string(glm::degrees(2e-3)) + R"( },
    "image": { "width": 64, "height": 48 }, "background": [0, 0, 0.5], "ambient": [1, 1, 1],
    "render": { "max_depth": 4, "bailout": 0 },
    "materials": {
      "red": { "color": [1, 0.2, 0], "ambient": 1, "diffuse": 0, "checker": { "color2": [0.5, 0, 0.5], "scale": 0.05 } },
      "floor": { "color": [0, 0.8, 0.3], "ambient": 1, "diffuse": 0, "checker": { "color2": [0, 0.3, 0.8], "scale": 0.25 } },
      "glass": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "specular": 0, "transmission": 1, "ior": 1.5 } },
    "objects": [
      { "type": "polygon", "material": "glass", "vertices": [)" +
                       at(-50, 0, -50) + ", " + at(-50, 0, 50) + ", " + at(9, 0, 50) + ", " + at(9, 0, -50) + R"(] },
      { "type": "plane", "normal": [-1, 0, 0], "point": )" +
                       at(10, 0, 0) + R"(, "material": "red" },
      { "type": "plane", "normal": [0, 1, 0], "point": )" +
                       at(0, -3, 0) + R"(, "material": "floor" } ] })");
}

TEST(NumericsGlass, CriticalAngleAt1e4DecidedByTheAngleAlone) {
  const double critical = std::asin(1.0 / 1.5);
  // Rows are 4e-5 rad apart and centred on the critical angle; the float eye direction and the
  // float test 1 - eta^2 (1 - c^2) >= 0 decide within a few 1e-7 rad of it. Pixels closer than
  // 2e-6 rad are not classified (none are at this size: the nearest row is 2e-5 away).
  const double margin = 2e-6;
  Image atOrigin;
  for (dvec3 shift : {dvec3(0.0), dvec3(1e4, -1e4, 1e4)}) {
    Scene scene = criticalScene(shift);
    RenderResult r = render(scene);
    ReferenceTracer ref(scene);
    int refracted = 0, reflected = 0, wrong = 0, unclassified = 0;
    double nearest = 1.0;
    for (std::uint32_t y = 0; y < r.image.height; ++y) {
      for (std::uint32_t x = 0; x < r.image.width; ++x) {
        dvec3 d = glm::normalize(ref.eyeDirection(x + 0.5, y + 0.5));
        double incidence = std::acos(d.y); // the interface's normal is +y
        double from = incidence - critical;
        nearest = std::min(nearest, std::abs(from));
        ASSERT_LT(std::abs(from), 1.1e-3) << "the lens must keep every ray near the critical angle";
        if (std::abs(from) < margin) {
          ++unclassified;
          continue;
        }
        bool red = r.image.at(x, y).x > 0.0f;
        bool tir = from > 0.0;
        (tir ? reflected : refracted)++;
        if (red == tir) {
          if (++wrong <= 5)
            ADD_FAILURE() << "pixel " << x << "," << y << " at " << from << " rad from the critical angle: "
                          << (tir ? "refracted past it" : "totally reflected before it") << ", red "
                          << r.image.at(x, y).x;
        }
      }
    }
    // Geometry is packed relative to the camera, so the moved scene's rays are the origin's bit for
    // bit; only the world-space checker is evaluated at frame.worldOffset + p, rounded to ulp(1e4)
    // = 1e-3 in float, and moves its edges by that (2 % of the wall's 0.05 squares). Pixels whose
    // paths (the refracted one to the wall, the reflected one to the floor, traced here in double)
    // meet the pattern within 2 ulp + 1e-4 of a cell edge are excused; the rest agree to 1e-4.
    int compared = 0, excused = 0, differing = 0;
    if (shift != dvec3(0.0)) {
      const double band = 2.0 * ulpOf(maxAbs(shift)) + 1e-4;
      auto nearEdge = [&](double q, double cell) { return std::abs(q / cell - std::round(q / cell)) * cell < band; };
      for (std::uint32_t y = 0; y < r.image.height; ++y) {
        for (std::uint32_t x = 0; x < r.image.width; ++x) {
          dvec3 d = glm::normalize(ref.eyeDirection(x + 0.5, y + 0.5));
          dvec3 p1 = kCriticalEye - (kCriticalEye.y / d.y) * d; // on the interface y = 0, camera-relative
          dvec3 m(d.x, -d.y, d.z);                              // reflected, down to the floor y = -3
          dvec3 f = p1 + (-3.0 / m.y) * m;
          bool near = nearEdge(f.x, 0.25) || nearEdge(f.z, 0.25);
          double k = 1.0 - 2.25 * (1.0 - d.y * d.y);
          if (k > 0.0) { // refracted: 1.5 d + (sqrt(k) - 1.5 cos) n, to the wall x = 10
            dvec3 t = 1.5 * d + (std::sqrt(k) - 1.5 * d.y) * dvec3(0, 1, 0);
            dvec3 w = p1 + ((10.0 - p1.x) / t.x) * t;
            near = near || nearEdge(w.y, 0.05) || nearEdge(w.z, 0.05);
          }
          if (near) {
            ++excused;
            continue;
          }
          ++compared;
          differing += atOrigin.at(x, y) != r.image.at(x, y);
          for (int c = 0; c < 3; ++c)
            if (std::abs(atOrigin.at(x, y)[c] - r.image.at(x, y)[c]) > 1e-4f) {
              ADD_FAILURE() << "pixel " << x << "," << y
                            << " differs from the scene at the origin: " << r.image.at(x, y)[c] << " vs "
                            << atOrigin.at(x, y)[c];
              break;
            }
        }
      }
      EXPECT_GT(compared, 3 * (compared + excused) / 4) << "too many pixels excused near checker edges";
    } else {
      atOrigin = r.image;
    }
    std::printf(
        "[ numerics ] critical angle +-1e-3 rad, shift %-20s %d refracted, %d totally reflected, %d wrong "
        "side, nearest ray %.1e rad from it; against the origin's image %d compared (%d not bit-identical), %d near "
        "checker edges; %llu non-finite\n",
        str(shift).c_str(), refracted, reflected, wrong, nearest, compared, differing, excused,
        static_cast<unsigned long long>(r.stats.nonFinite));
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(refracted, 0);
    EXPECT_GT(reflected, 0);
    EXPECT_EQ(r.stats.nonFinite, 0u);
    EXPECT_TRUE(allFinite(r.image));
  }
}

} // namespace
} // namespace vkray::test::numerics
