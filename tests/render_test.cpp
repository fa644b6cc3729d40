// Images checked against independent expectations: analytic silhouettes, the Phong formula
// evaluated on the host, shadow geometry, and the double-precision reference tracer.
//
// Pixels whose centre ray passes within a hair of an edge (silhouette, shadow boundary, polygon
// edge) can fall either way in float32 and are excluded from exact classification checks: a pixel
// is "stable" when the reference classifies its centre ray and four rays offset by 1e-3 pixel
// identically. Everything else must match exactly.
#include <cmath>
#include <cstring>
#include <functional>

#include <gtest/gtest.h>

#include "image/image_io.h"
#include "reference.h"
#include "test_support.h"

namespace vkray::test {
namespace {

using glm::dvec3;

const char* kCamera = R"("camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 40 },)";

// A path key folded into the non-negative ints stableKey() deals in (-1 means "unstable").
int positiveKey(std::uint64_t k) {
  return static_cast<int>(k % 0x7fffffffu);
}

// Classifies a pixel with `key` at its centre and at four nearby points; -1 when they disagree.
int stableKey(const ReferenceTracer& ref, std::uint32_t x, std::uint32_t y,
              const std::function<int(const dvec3&, const dvec3&)>& key) {
  const double e = 1e-3;
  const double offsets[5][2] = {{0, 0}, {e, 0}, {-e, 0}, {0, e}, {0, -e}};
  int k0 = 0;
  for (int i = 0; i < 5; ++i) {
    int k = key(ref.eyeOrigin(), ref.eyeDirection(x + 0.5 + offsets[i][0], y + 0.5 + offsets[i][1]));
    if (i == 0)
      k0 = k;
    else if (k != k0)
      return -1;
  }
  return k0;
}

TEST(RenderSilhouette, SphereMatchesAnalyticDisc) {
  Scene scene = sceneFromJson(std::string("{") + kCamera + R"(
    "image": { "width": 96, "height": 72 }, "ambient": [1, 1, 1],
    "materials": { "flat": { "color": [1, 1, 1], "ambient": 1, "diffuse": 0 } },
    "objects": [ { "type": "sphere", "center": [0.3, -0.2, 0], "radius": 1, "material": "flat" } ] })");
  RenderResult r = render(scene);
  ReferenceTracer ref(scene);
  const Sphere& s = scene.spheres[0];
  int inside = 0, outside = 0;
  for (std::uint32_t y = 0; y < 72; ++y) {
    for (std::uint32_t x = 0; x < 96; ++x) {
      dvec3 o = ref.eyeOrigin();
      dvec3 d = ref.eyeDirection(x + 0.5, y + 0.5);
      // Distance from the centre to the ray's line, in double.
      dvec3 f = s.center - o;
      double dist = glm::length(f - glm::dot(f, d) * d);
      if (std::abs(dist - s.radius) < 1e-5) continue; // within float precision of the rim
      bool hit = dist < s.radius;
      float v = r.image.at(x, y).x;
      EXPECT_EQ(v, hit ? 1.0f : 0.0f) << "pixel " << x << "," << y << " distance " << dist;
      (hit ? inside : outside)++;
    }
  }
  EXPECT_GT(inside, 500);
  EXPECT_GT(outside, 500);
}

TEST(RenderShading, LitPlaneMatchesThePhongFormula) {
  Scene scene = sceneFromJson(R"({
    "camera": { "position": [0, 3, 4], "look_at": [0, 0, 0], "fov_y": 50 },
    "image": { "width": 64, "height": 48 }, "ambient": [0.2, 0.25, 0.3], "background": [0, 0, 0],
    "materials": { "m": { "color": [0.8, 0.6, 0.4], "ambient": 0.3, "diffuse": 0.7, "specular": 0.5,
                          "shininess": 12 } },
    "lights": [ { "position": [1, 2, 1], "color": [1, 0.9, 0.8] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "m" } ] })");
  RenderResult r = render(scene);
  const Material& m = scene.materials[0];
  const PointLight& light = scene.lights[0];
  ReferenceTracer ref(scene);
  int checked = 0;
  for (std::uint32_t y = 0; y < 48; ++y) {
    for (std::uint32_t x = 0; x < 64; ++x) {
      dvec3 o = ref.eyeOrigin();
      dvec3 d = ref.eyeDirection(x + 0.5, y + 0.5);
      if (d.y >= 0) continue;
      // The formula of docs/scene-format.md, written out here: n = +y, l to the light,
      // v = -d, r = mirror of l about n.
      dvec3 p = o + (-o.y / d.y) * d;
      dvec3 n(0, 1, 0);
      dvec3 l = glm::normalize(light.position - p);
      dvec3 v = -d;
      dvec3 rr = 2.0 * glm::dot(n, l) * n - l;
      double ndotl = std::max(0.0, glm::dot(n, l));
      double spec = m.specular * std::pow(std::max(0.0, glm::dot(rr, v)), m.shininess);
      dvec3 expected = m.ambient * m.color * scene.ambientLight + light.color * (m.diffuse * m.color * ndotl + spec);
      glm::vec3 got = r.image.at(x, y);
      for (int c = 0; c < 3; ++c) {
        // float32 position and normal errors of ~1e-6 relative; 1e-4 is a hundredfold margin.
        EXPECT_NEAR(got[c], expected[c], 1e-4 * (1 + expected[c])) << "pixel " << x << "," << y << " channel " << c;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(RenderShadow, FallsWhereTheGeometrySays) {
  Scene scene = sceneFromJson(R"({
    "camera": { "position": [0, 4, 5], "look_at": [0, 0, 0], "fov_y": 50 },
    "image": { "width": 80, "height": 60 }, "ambient": [0.2, 0.2, 0.2],
    "materials": { "floor": { "color": [1, 1, 1], "ambient": 1, "diffuse": 1 },
                   "ball": { "color": [1, 0, 0], "ambient": 1, "diffuse": 0 } },
    "lights": [ { "position": [2, 5, 1] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
                 { "type": "sphere", "center": [0, 1, 0], "radius": 0.7, "material": "ball" } ] })");
  RenderResult r = render(scene);
  ReferenceTracer ref(scene);
  const Sphere& ball = scene.spheres[0];
  const dvec3 light = scene.lights[0].position;
  // 1: floor in shadow, 2: lit floor, 0: anything else; from the segment-to-light geometry.
  auto key = [&](const dvec3& o, const dvec3& d) {
    RefHit h = ref.closestHit(o, d);
    if (!h.hit() || h.kind != 1) return 0;
    dvec3 seg = light - h.p;
    double len = glm::length(seg);
    dvec3 u = seg / len;
    dvec3 f = ball.center - h.p;
    double along = std::clamp(glm::dot(f, u), 0.0, len);
    double dist = glm::length(f - along * u);
    if (std::abs(dist - ball.radius) < 1e-3) return 3; // on the penumbra line: not stable
    return dist < ball.radius ? 1 : 2;
  };
  int shadowed = 0, lit = 0;
  for (std::uint32_t y = 0; y < 60; ++y) {
    for (std::uint32_t x = 0; x < 80; ++x) {
      int k = stableKey(ref, x, y, key);
      if (k != 1 && k != 2) continue;
      float v = r.image.at(x, y).x;
      if (k == 1) {
        EXPECT_NEAR(v, 0.2f, 1e-6f) << "pixel " << x << "," << y << " should be in shadow";
        ++shadowed;
      } else {
        EXPECT_GT(v, 0.25f) << "pixel " << x << "," << y << " should be lit";
        ++lit;
      }
    }
  }
  EXPECT_GT(shadowed, 40);
  EXPECT_GT(lit, 1000);
}

TEST(RenderPrimitives, EachKindIsHitWhereTheHostSays) {
  Scene scene = sceneFromJson(std::string("{") + kCamera + R"(
    "image": { "width": 96, "height": 72 }, "ambient": [1, 1, 1],
    "materials": { "s": { "color": [1, 0, 0], "ambient": 1, "diffuse": 0 },
                   "p": { "color": [0, 1, 0], "ambient": 1, "diffuse": 0 },
                   "g": { "color": [0, 0, 1], "ambient": 1, "diffuse": 0 },
                   "t": { "color": [1, 1, 0], "ambient": 1, "diffuse": 0 } },
    "objects": [
      { "type": "sphere", "center": [-0.9, 0.6, 0], "radius": 0.5, "material": "s" },
      { "type": "plane", "normal": [0, 1, 0.2], "offset": 1.2, "material": "p" },
      { "type": "polygon", "vertices": [[0.2,0.2,0],[1.4,0.3,0],[1.5,1.1,0],[0.8,1.4,0],[0.1,0.9,0]], "material": "g" },
      { "type": "triangle", "vertices": [[-1.2,-0.8,0.5],[0.3,-0.6,0.2],[-0.5,0.1,0.4]], "material": "t" } ] })");
  RenderResult r = render(scene);
  ReferenceTracer ref(scene);
  const glm::vec3 colors[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}};
  int counts[5] = {0, 0, 0, 0, 0};
  auto key = [&](const dvec3& o, const dvec3& d) { return ref.closestHit(o, d).kind + 1; };
  for (std::uint32_t y = 0; y < 72; ++y) {
    for (std::uint32_t x = 0; x < 96; ++x) {
      int k = stableKey(ref, x, y, key);
      if (k < 0) continue;
      glm::vec3 expected = k == 0 ? glm::vec3(0) : colors[k - 1];
      EXPECT_EQ(r.image.at(x, y), expected) << "pixel " << x << "," << y << " kind " << k - 1;
      ++counts[k];
    }
  }
  for (int k = 0; k < 5; ++k) EXPECT_GT(counts[k], 30) << "kind " << k - 1 << " barely visible";
}

// Depth 0 -> 1 changes exactly the pixels whose eye ray hits a mirror; 1 -> 2 exactly those whose
// eye ray hits a mirror and whose reflected ray hits a mirror again.
TEST(RenderDepth, ChangesExactlyThePixelsThatSeeMirrors) {
  Scene scene = sceneFromJson(R"({ "base": "seed.json", "image": { "width": 96, "height": 72 } })");
  ReferenceTracer ref(scene);
  auto mirror = [&](const RefHit& h) { return h.hit() && scene.materials[h.material].reflection > 0; };
  // 0: no mirror; 1: mirror first; 2: mirror, then mirror again.
  auto key = [&](const dvec3& o, const dvec3& d) {
    RefHit h = ref.closestHit(o, d);
    if (!mirror(h)) return 0;
    dvec3 n = glm::dot(h.n, d) < 0 ? h.n : -h.n;
    dvec3 rd = d - 2.0 * glm::dot(d, n) * n;
    RefHit h2 = ref.closestHit(h.p, rd, 1e-7);
    return mirror(h2) ? 2 : 1;
  };
  Image img[3];
  for (int depth = 0; depth < 3; ++depth) {
    scene.render.maxDepth = depth;
    img[depth] = render(scene).image;
  }
  int changed01 = 0, changed12 = 0;
  for (std::uint32_t y = 0; y < 72; ++y) {
    for (std::uint32_t x = 0; x < 96; ++x) {
      int k = stableKey(ref, x, y, key);
      if (k < 0) continue;
      bool d01 = img[0].at(x, y) != img[1].at(x, y);
      bool d12 = img[1].at(x, y) != img[2].at(x, y);
      EXPECT_EQ(d01, k >= 1) << "pixel " << x << "," << y;
      EXPECT_EQ(d12, k == 2) << "pixel " << x << "," << y;
      changed01 += d01;
      changed12 += d12;
    }
  }
  EXPECT_GT(changed01, 300);
  EXPECT_GT(changed12, 20);
}

// The whole showcase against the double-precision reference, on stable pixels.
TEST(RenderReference, ShowcaseMatchesTheDoublePrecisionTracer) {
  Scene scene = sceneFromJson(R"({ "base": "showcase.json", "image": { "width": 80, "height": 60 } })");
  RenderResult r = render(scene);
  ReferenceTracer ref(scene);
  // Stability key: the sequence of materials along the mirror path and the shadow state of the
  // first hit, so pixels on any discontinuity are excluded.
  auto key = [&](const dvec3& o0, const dvec3& d0) {
    // Unsigned: a deep mirror path shifts it past 32 bits (it wraps, which only hashes it).
    std::uint64_t k = 0;
    dvec3 o = o0, d = d0;
    for (int depth = 0; depth <= scene.render.maxDepth; ++depth) {
      RefHit h = ref.closestHit(o, d, 1e-7);
      if (!h.hit()) return positiveKey(k * 8 + 7);
      dvec3 q = (h.p - h.n * 1e-7) / 1.0;
      int cell = static_cast<int>(std::floor(q.x) + std::floor(q.y) + std::floor(q.z)) & 1;
      int shadow = 0;
      for (std::size_t li = 0; li < scene.lights.size(); ++li) {
        dvec3 toL = scene.lights[li].position - h.p;
        RefHit s = ref.closestHit(h.p, glm::normalize(toL), 1e-7, glm::length(toL));
        shadow = shadow * 2 + s.hit();
      }
      k = (k * 8 + h.material) * 16 + static_cast<std::uint64_t>(cell * 4 + shadow);
      if (scene.materials[h.material].reflection <= 0) break;
      dvec3 n = glm::dot(h.n, d) < 0 ? h.n : -h.n;
      d = d - 2.0 * glm::dot(d, n) * n;
      o = h.p;
    }
    return positiveKey(k);
  };
  int checked = 0;
  for (std::uint32_t y = 0; y < 60; ++y) {
    for (std::uint32_t x = 0; x < 80; ++x) {
      if (stableKey(ref, x, y, key) < 0) continue;
      dvec3 expected = ref.radiance(ref.eyeOrigin(), ref.eyeDirection(x + 0.5, y + 0.5));
      glm::vec3 got = r.image.at(x, y);
      for (int c = 0; c < 3; ++c) {
        // Float32 directions after five mirror bounces drift ~1e-5 relative; highlights with
        // shininess 200 amplify that ~200x, so 2e-3 absolute is the stated bound.
        EXPECT_NEAR(got[c], expected[c], 2e-3) << "pixel " << x << "," << y << " channel " << c;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 3500);
}

TEST(RenderDeterminism, SameSceneSameBytes) {
  Scene scene = sceneFromJson(R"({ "base": "showcase.json", "image": { "width": 64, "height": 48 } })");
  auto a = encodePng(render(scene).image);
  auto b = encodePng(render(scene).image);
  EXPECT_EQ(a, b);
}

TEST(RenderDeterminism, AllSamplesInOneDispatchGiveTheBytesOfOnePerDispatch) {
  // Where the driver lets loops run to their end (Context::loopLimit), one dispatch traces all of a
  // band's samples; where it cuts them, each sample gets a dispatch. The sums are added in the same
  // order either way: the same image bit for bit and the same rays, with glass's stack and adaptive
  // antialiasing's refine pass too.
  for (const char* extra :
       {R"("base": "showcase.json", "render": { "spp": 8 })", R"("base": "glass.json", "render": { "spp": 6 })",
        R"("base": "showcase.json", "render": { "spp": 4, "antialiasing": "adaptive" })"}) {
    Scene scene = sceneFromJson(std::string("{") + extra + R"(, "image": { "width": 48, "height": 36 } })");
    RenderResult together = render(scene);
    RenderOptions apart;
    apart.oneSamplePerDispatch = true;
    RenderResult split = render(scene, apart);
    ASSERT_EQ(together.image.pixels.size(), split.image.pixels.size());
    EXPECT_EQ(0, std::memcmp(together.image.pixels.data(), split.image.pixels.data(),
                             together.image.pixels.size() * sizeof(glm::vec3)))
        << extra;
    EXPECT_EQ(together.stats.total(), split.stats.total()) << extra;
    EXPECT_EQ(together.stats.truncated, split.stats.truncated) << extra;
  }
}

TEST(RenderNonSquare, OddSizesCoverEveryPixel) {
  // 37 x 23 is no multiple of the 8 x 8 workgroup: the last partial groups must still be traced.
  Scene scene = sceneFromJson(std::string("{") + kCamera + R"(
    "image": { "width": 37, "height": 23 }, "background": [0.5, 0.25, 1] })");
  RenderResult r = render(scene);
  for (const auto& p : r.image.pixels) EXPECT_EQ(p, glm::vec3(0.5f, 0.25f, 1.0f));
  EXPECT_EQ(r.stats.eye, 37u * 23u);
}

} // namespace
} // namespace vkray::test

namespace vkray::test {
namespace {

// No NaN or Inf ever reaches the image: the cases the renderer must survive by construction.
TEST(RenderNoNaN, DegenerateInputsGiveFiniteImages) {
  // An up vector parallel to the view, shininess 0 (pow(0, 0) is undefined in GLSL), and smooth
  // normals that cancel in the middle of a triangle (a zero-length interpolated normal).
  Scene s = sceneFromJson(R"({
    "camera": { "position": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 60 },
    "image": { "width": 32, "height": 32 }, "ambient": [0.2, 0.2, 0.2], "background": [0.1, 0.1, 0.1],
    "render": { "max_depth": 4 },
    "materials": { "dull": { "color": [0.8, 0.8, 0.8], "specular": 1, "shininess": 0, "reflection": 0.3 } },
    "lights": [ { "position": [1, 4, 1] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "dull" },
                 { "type": "sphere", "center": [0.5, 0.5, 0], "radius": 0.5, "material": "dull" },
                 { "type": "triangle", "vertices": [[-2, 0.1, -1], [0, 0.1, 1], [-1, 0.1, -2]],
                   "normals": [[0, 1, 0], [0, -1, 0], [0, 1, 0]], "material": "dull" } ] })");
  RenderResult r = render(s);
  EXPECT_EQ(r.stats.nonFinite, 0u);
  for (const auto& p : r.image.pixels) EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  // The degenerate camera still looks down: the floor fills the view.
  std::size_t floor = 0;
  for (const auto& p : r.image.pixels) floor += p != glm::vec3(0.1f);
  EXPECT_GT(floor, 900u);
}

} // namespace
} // namespace vkray::test
