// Specular transmission: Snell's law at both interfaces of a glass sphere (on the shader's own
// functions, through the probe), total internal reflection, energy bounds, the Fresnel fraction a
// slab transmits, nested media, and the explicit ray-tree stack.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "reference.h"
#include "render/probe.h"
#include "scene/scene_loader.h"
#include "test_support.h"

namespace vkray::test {
namespace {

using glm::dvec3;
using glm::vec3;
using glm::vec4;

gpu::ProbeQuery sphereQuery(vec3 origin, vec3 dir, vec3 center, float radius) {
  gpu::ProbeQuery q{};
  q.origin = vec4(origin, 0.0f);
  q.dir = vec4(dir, 0.0f);
  q.a = vec4(center, radius);
  q.op = glm::uvec4(gpu::kProbeSphere, gpu::kNumericsRobust, 0, 0);
  return q;
}

gpu::ProbeQuery dielectricQuery(vec3 dir, vec3 facingNormal, float n1, float n2, bool schlick = false) {
  gpu::ProbeQuery q{};
  q.dir = vec4(dir, 0.0f);
  q.a = vec4(facingNormal, 0.0f);
  q.b = vec4(facingNormal, 0.0f);
  q.c = vec4(n1, n2, 0.0f, 0.0f);
  q.op = glm::uvec4(gpu::kProbeDielectric, gpu::kNumericsRobust, schlick ? 1u : 0u, 0);
  return q;
}

// Snell's law in vector form, in double.
dvec3 refractD(const dvec3& d, const dvec3& n, double eta) {
  double c = -glm::dot(d, n);
  double k = 1.0 - eta * eta * (1.0 - c * c);
  return eta * d + (eta * c - std::sqrt(k)) * n;
}

double angleBetween(const dvec3& a, const dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// A ray through a glass sphere (n = 1.5, r = 1) at offsets 0 .. 0.95: the shader's intersection,
// spawn and refraction functions, step by step, against the same path computed in double from the
// same float inputs. Tolerance 2e-6 rad: each float step (hit point, normal, refract) is good to a
// few 1e-7 relative, and four of them chain.
TEST(NumericsRefraction, GlassSphereObeysSnellAtBothInterfaces) {
  Probe probe(gpu());
  const vec3 center(0.0f);
  const float radius = 1.0f;
  const float n = 1.5f;
  for (float offset : {0.0f, 0.3f, 0.6f, 0.9f, 0.95f}) {
    SCOPED_TRACE(offset);
    vec3 o(offset, 0.0f, 5.0f);
    vec3 d(0.0f, 0.0f, -1.0f);
    auto hit1 = probe.run({sphereQuery(o, d, center, radius)})[0];
    ASSERT_GT(hit1.hit.x, 0.0f);
    vec3 n1 = vec3(hit1.normal);
    auto split1 = probe.run({dielectricQuery(d, n1, 1.0f, n)})[0];
    vec3 t1 = vec3(split1.point);
    auto hit2 = probe.run({sphereQuery(vec3(hit1.spawnIn), t1, center, radius)})[0];
    ASSERT_GT(hit2.hit.x, 0.0f) << "the refracted ray must meet the far side";
    vec3 n2 = vec3(hit2.normal); // outward; the ray arrives from inside
    auto split2 = probe.run({dielectricQuery(t1, -n2, n, 1.0f)})[0];
    vec3 t2 = vec3(split2.point);

    // Reference in double.
    dvec3 od(o), dd(d);
    double b = glm::dot(od, dd);
    double c = glm::dot(od, od) - 1.0;
    double tEnter = -b - std::sqrt(b * b - c);
    dvec3 p1 = od + tEnter * dd;
    dvec3 m1 = glm::normalize(p1);
    dvec3 r1 = glm::normalize(refractD(dd, m1, 1.0 / 1.5));
    double tExit = -2.0 * glm::dot(p1, r1); // chord from p1 along r1 in the unit sphere
    dvec3 p2 = p1 + tExit * r1;
    dvec3 m2 = glm::normalize(p2);
    dvec3 r2 = glm::normalize(refractD(r1, -m2, 1.5));

    EXPECT_LT(angleBetween(dvec3(t1), r1), 2e-6);
    EXPECT_LT(angleBetween(dvec3(t2), r2), 2e-6);
    // Snell at both interfaces: n1 sin(theta_i) = n2 sin(theta_t).
    auto sinAngle = [](const dvec3& a, const dvec3& nn) { return glm::length(glm::cross(glm::normalize(a), nn)); };
    EXPECT_NEAR(sinAngle(dd, m1), 1.5 * sinAngle(dvec3(t1), m1), 2e-6);
    EXPECT_NEAR(1.5 * sinAngle(dvec3(t1), m2), sinAngle(dvec3(t2), m2), 2e-6);
    // By symmetry the ray leaves at the angle it entered.
    EXPECT_NEAR(sinAngle(dvec3(t2), m2), sinAngle(dd, m1), 4e-6);
  }
}

TEST(NumericsRefraction, TotalInternalReflectionAndTheCriticalAngle) {
  Probe probe(gpu());
  const double critical = std::asin(1.0 / 1.5);
  std::vector<gpu::ProbeQuery> queries;
  std::vector<double> angles;
  // 45 degrees from inside glass: beyond the critical angle (41.8 degrees).
  angles.push_back(glm::radians(45.0));
  for (double delta : {-1e-3, -1e-4, 0.0, 1e-4, 1e-3}) angles.push_back(critical + glm::radians(delta));
  for (double a : angles) {
    for (bool schlick : {false, true}) {
      vec3 dir(static_cast<float>(std::sin(a)), static_cast<float>(-std::cos(a)), 0.0f);
      queries.push_back(dielectricQuery(dir, vec3(0, 1, 0), 1.5f, 1.0f, schlick));
    }
  }
  auto results = probe.run(queries);
  // 45 degrees: everything reflects, no refracted ray, for both Fresnel forms.
  for (int s = 0; s < 2; ++s) {
    EXPECT_EQ(results[static_cast<std::size_t>(s)].hit.x, 1.0f);
    EXPECT_EQ(vec3(results[static_cast<std::size_t>(s)].point), vec3(0.0f));
    vec3 mirror = vec3(results[static_cast<std::size_t>(s)].normal);
    EXPECT_NEAR(mirror.y, std::cos(glm::radians(45.0)), 1e-6);
  }
  // Around the critical angle: finite, F in [0, 1], and the refracted direction unit or zero.
  for (std::size_t i = 2; i < results.size(); ++i) {
    float F = results[i].hit.x;
    vec3 t = vec3(results[i].point);
    EXPECT_TRUE(std::isfinite(F) && F >= 0.0f && F <= 1.0f) << "F = " << F;
    EXPECT_TRUE(std::isfinite(t.x) && std::isfinite(t.y) && std::isfinite(t.z));
    float len = glm::length(t);
    EXPECT_TRUE(len == 0.0f || std::abs(len - 1.0f) < 1e-5f) << "|t| = " << len;
    if (len == 0.0f) {
      EXPECT_EQ(F, 1.0f) << "a missing refracted ray must send all weight to reflection";
    }
  }
}

const char* kGlass = R"("glass": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "specular": 0,
                                 "transmission": 1, "ior": 1.5 })";

// With reflection + transmission <= 1, no absorption and glass that adds no light of its own, the
// weights of a pixel's leaves sum to at most 1: no pixel can exceed the brightest thing it can
// see. Here that is the background (1) and the floor's local colour.
TEST(RenderRefraction, EnergyIsBounded) {
  Scene s = sceneFromJson(std::string(R"({
    "camera": { "position": [0, 1.5, 5], "look_at": [0, 0.6, 0], "fov_y": 45 },
    "image": { "width": 64, "height": 48 }, "background": [1, 1, 1], "ambient": [0.3, 0.3, 0.3],
    "render": { "max_depth": 12, "bailout": 0 },
    "materials": { "floor": { "color": [0.7, 0.7, 0.7], "ambient": 1, "diffuse": 0.5 }, )") +
                          kGlass + R"( },
    "lights": [ { "position": [2, 6, 3], "color": [0.5, 0.5, 0.5] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
                 { "type": "sphere", "center": [-0.6, 0.8, 0], "radius": 0.8, "material": "glass" },
                 { "type": "sphere", "center": [0.9, 0.5, 0.5], "radius": 0.5, "material": "glass" } ] })");
  RenderResult r = render(s);
  // Brightest local colour: floor ambient 0.7*0.3 + light 0.5*0.5*0.7 (n.l <= 1) = 0.385 < 1.
  float worst = 0.0f;
  for (const auto& p : r.image.pixels) worst = std::max({worst, p.x, p.y, p.z});
  EXPECT_LE(worst, 1.0f + 1e-5f);
  EXPECT_GT(r.stats.refraction, 0u);
  EXPECT_EQ(r.stats.stackOverflow, 0u);
}

// A slab (two parallel faces, outward normals) in front of a white card, seen at normal incidence:
// each face transmits 1 - R with R = ((n-1)/(n+1))^2, and light bounces between the faces. Paths
// reaching the card after k round trips arrive at depth 2 + 2k, so with max_depth 9 the pixel is
// (1-R)^2 (1 + R^2 + R^4 + R^6). Tolerance 1e-5: float Fresnel at cos = 1 is exact to ~1e-7.
TEST(RenderRefraction, SlabAtNormalIncidenceTransmitsTheFresnelFraction) {
  Scene s = sceneFromJson(std::string(R"({
    "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 10 },
    "image": { "width": 16, "height": 16 }, "ambient": [1, 1, 1],
    "render": { "max_depth": 9, "bailout": 0 },
    "materials": { "card": { "color": [1, 1, 1], "ambient": 1, "diffuse": 0 }, )") +
                          kGlass + R"( },
    "objects": [
      { "type": "polygon", "material": "glass", "vertices": [[-4,-4,0],[4,-4,0],[4,4,0],[-4,4,0]] },
      { "type": "polygon", "material": "glass", "vertices": [[-4,-4,-0.5],[-4,4,-0.5],[4,4,-0.5],[4,-4,-0.5]] },
      { "type": "polygon", "material": "card", "vertices": [[-6,-6,-3],[6,-6,-3],[6,6,-3],[-6,6,-3]] } ] })");
  RenderResult r = render(s);
  double R = std::pow((1.5 - 1.0) / (1.5 + 1.0), 2.0);
  double expected = (1 - R) * (1 - R) * (1 + R * R + std::pow(R, 4) + std::pow(R, 6));
  glm::vec3 centre = r.image.at(8, 8);
  EXPECT_NEAR(centre.x, expected, 1e-5);
  EXPECT_NEAR(centre.y, expected, 1e-5);
  // Schlick is exact at normal incidence.
  s.render.fresnel = FresnelMode::Schlick;
  EXPECT_NEAR(render(s).image.at(8, 8).x, expected, 1e-5);
}

// A glass ball inside a water tank with the water's own index is invisible: at the water|ball
// interface n1 = n2, so nothing reflects and nothing bends. Had the ball been entered "from air"
// (a wrong media stack), it would refract like a lens.
TEST(RenderRefraction, NestedMediaUseTheRatioOfTheirOwnInterface) {
  auto scene = [](bool ball) {
    std::string objects = R"(
      { "type": "polygon", "material": "water", "vertices": [[-1,-1,1],[1,-1,1],[1,1,1],[-1,1,1]] },
      { "type": "polygon", "material": "water", "vertices": [[1,-1,-1],[-1,-1,-1],[-1,1,-1],[1,1,-1]] },
      { "type": "polygon", "material": "water", "vertices": [[-1,-1,-1],[-1,-1,1],[-1,1,1],[-1,1,-1]] },
      { "type": "polygon", "material": "water", "vertices": [[1,-1,1],[1,-1,-1],[1,1,-1],[1,1,1]] },
      { "type": "polygon", "material": "water", "vertices": [[-1,1,1],[1,1,1],[1,1,-1],[-1,1,-1]] },
      { "type": "polygon", "material": "water", "vertices": [[-1,-1,-1],[1,-1,-1],[1,-1,1],[-1,-1,1]] },
      { "type": "plane", "normal": [0, 0, 1], "offset": 4, "material": "wall" })";
    if (ball) objects += R"(, { "type": "sphere", "center": [0.1, 0, 0], "radius": 0.6, "material": "ball" })";
    return sceneFromJson(R"({ "camera": { "position": [0.4, 0.3, 5], "look_at": [0, 0, 0], "fov_y": 35 },
      "image": { "width": 48, "height": 48 }, "ambient": [1, 1, 1], "render": { "max_depth": 16, "bailout": 0 },
      "materials": {
        "wall": { "color": [0.9, 0.5, 0.2], "ambient": 1, "diffuse": 0, "checker": { "color2": [0.1, 0.3, 0.8], "scale": 0.25 } },
        "water": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "transmission": 1, "ior": 1.33 },
        "ball": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "transmission": 1, "ior": 1.33 } },
      "objects": [ )" + objects +
                         "] }");
  };
  Image without = render(scene(false)).image;
  RenderResult with = render(scene(true));
  EXPECT_GT(with.stats.refraction, render(scene(false)).stats.refraction) << "the ball was not hit at all";
  double worst = 0.0;
  for (std::size_t i = 0; i < without.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, double(std::abs(without.pixels[i][c] - with.image.pixels[i][c])));
  }
  // Spawned origins move by ~1e-6 at each extra interface; a checker edge can still flip a pixel
  // or two, so the bound is on how many differ, not only by how much.
  std::size_t differing = 0;
  for (std::size_t i = 0; i < without.pixels.size(); ++i)
    differing += glm::any(glm::greaterThan(glm::abs(without.pixels[i] - with.image.pixels[i]), glm::vec3(1e-4f)));
  EXPECT_LE(differing, 4u) << "worst difference " << worst;

  // Control: the same ball as glass (1.5) inside the water is plainly visible.
  Scene glassBall = scene(true);
  for (Material& m : glassBall.materials) {
    if (m.name == "ball") m.ior = 1.5;
  }
  Image visible = render(glassBall).image;
  std::size_t changed = 0;
  for (std::size_t i = 0; i < without.pixels.size(); ++i) changed += visible.pixels[i] != without.pixels[i];
  EXPECT_GT(changed, 200u);
}

// The full image against the double-precision reference, where the reference is continuous (the
// radiance at the pixel centre and at four points 1e-3 pixel away agree within 1e-3).
TEST(RenderRefraction, GlassSceneMatchesTheReference) {
  Scene s = sceneFromJson(R"({ "base": "glass.json", "image": { "width": 64, "height": 48 } })");
  RenderResult r = render(s);
  EXPECT_EQ(r.stats.stackOverflow, 0u);
  ReferenceTracer ref(s);
  int checked = 0, mismatched = 0;
  for (std::uint32_t y = 0; y < 48; ++y) {
    for (std::uint32_t x = 0; x < 64; ++x) {
      dvec3 c = ref.radiance(ref.eyeOrigin(), ref.eyeDirection(x + 0.5, y + 0.5));
      bool stable = true;
      for (auto [dx, dy] : {std::pair{1e-3, 0.0}, {-1e-3, 0.0}, {0.0, 1e-3}, {0.0, -1e-3}}) {
        dvec3 v = ref.radiance(ref.eyeOrigin(), ref.eyeDirection(x + 0.5 + dx, y + 0.5 + dy));
        stable = stable && glm::all(glm::lessThan(glm::abs(v - c), dvec3(1e-3)));
      }
      if (!stable) continue;
      ++checked;
      // 2e-3: float directions drift ~1e-5 through up to eight refractions, and the specular
      // highlights (shininess 300) amplify that.
      if (glm::any(glm::greaterThan(glm::abs(dvec3(r.image.at(x, y)) - c), dvec3(2e-3)))) {
        ++mismatched;
        ADD_FAILURE() << "pixel " << x << "," << y << ": gpu " << r.image.at(x, y).x << "," << r.image.at(x, y).y << ","
                      << r.image.at(x, y).z << " reference " << c.x << "," << c.y << "," << c.z;
        if (mismatched > 10) return;
      }
    }
  }
  EXPECT_GT(checked, 2000);
}

// Two facing glass spheres need a deep tree: at depth 8 nothing overflows the stack, and going from
// depth 2 to 8 changes only pixels whose eye ray meets glass.
TEST(RenderRefraction, DeepTreeNeverOverflowsAndDepthOnlyChangesGlassPixels) {
  Scene s = sceneFromJson(std::string(R"({
    "camera": { "position": [0, 1, 6], "look_at": [0, 0.8, 0], "fov_y": 40 },
    "image": { "width": 64, "height": 48 }, "background": [0.4, 0.5, 0.7], "ambient": [0.3, 0.3, 0.3],
    "render": { "max_depth": 8, "bailout": 0 },
    "materials": { "floor": { "color": [0.9, 0.9, 0.9], "ambient": 0.5, "diffuse": 0.6,
                              "checker": { "color2": [0.2, 0.2, 0.2], "scale": 0.5 } }, )") +
                          kGlass + R"( },
    "lights": [ { "position": [0, 6, 4] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
                 { "type": "sphere", "center": [-0.9, 0.9, 0], "radius": 0.8, "material": "glass" },
                 { "type": "sphere", "center": [0.9, 0.9, 0], "radius": 0.8, "material": "glass" } ] })");
  RenderResult deep = render(s);
  EXPECT_EQ(deep.stats.stackOverflow, 0u);
  EXPECT_EQ(deep.stats.maxDepth, 8u);
  s.render.maxDepth = 2;
  RenderResult shallow = render(s);
  ReferenceTracer ref(s);
  int changed = 0;
  for (std::uint32_t y = 0; y < 48; ++y) {
    for (std::uint32_t x = 0; x < 64; ++x) {
      if (deep.image.at(x, y) == shallow.image.at(x, y)) continue;
      ++changed;
      // Every changed pixel's eye ray hits glass (checked in double, allowing the rim).
      bool glass = false;
      for (auto [dx, dy] : {std::pair{0.0, 0.0}, {0.5, 0.0}, {-0.5, 0.0}, {0.0, 0.5}, {0.0, -0.5}}) {
        RefHit h = ref.closestHit(ref.eyeOrigin(), ref.eyeDirection(x + 0.5 + dx, y + 0.5 + dy));
        glass = glass || (h.hit() && s.materials[h.material].transmission > 0);
      }
      EXPECT_TRUE(glass) << "pixel " << x << "," << y << " changed but sees no glass";
    }
  }
  EXPECT_GT(changed, 200);
}

// Glass panes facing each other at normal incidence split every ray in two at every interface:
// without bailout the tree has up to 2^(depth+1) rays. The kernel stops a tree at kMaxTreeRays
// rays and counts the sample as truncated (even without statistics), on every driver alike: no
// driver's loop limit is needed to end it (Mesa 22's llvmpipe has one, Mesa 25's and GPUs' have
// none), and a driver that does cut the loop first is counted the same way. The glass scene's
// accuracy reference (depth 16, bailout 1e-6, 4 spp) stays within the budget.
std::string paneRow(int panes) {
  std::string objects;
  for (int i = 0; i < panes; ++i) {
    double z0 = -0.3 * i, z1 = z0 - 0.15;
    auto quad = [](double z, bool facingCamera) {
      std::string a = "[-3,-3," + std::to_string(z) + "]", b = "[3,-3," + std::to_string(z) + "]",
                  c = "[3,3," + std::to_string(z) + "]", d = "[-3,3," + std::to_string(z) + "]";
      return R"({ "type": "polygon", "material": "glass", "vertices": [)" +
             (facingCamera ? a + "," + b + "," + c + "," + d : a + "," + d + "," + c + "," + b) + "] }";
    };
    if (i) objects += ","; // appended piece by piece: GCC 12 warns falsely on `const char* + string&&`
    objects += quad(z0, true) + "," + quad(z1, false);
  }
  return std::string(R"({ "camera": { "position": [0, 0, 4], "look_at": [0, 0, 0], "fov_y": 10 },
    "image": { "width": 8, "height": 8 }, "background": [1, 1, 1],
    "render": { "max_depth": 40, "bailout": 0 }, "materials": { )") +
         kGlass + R"( }, "objects": [ )" + objects + "] }";
}

TEST(RenderRefraction, TreesBeyondTheRayBudgetAreCounted) {
  Scene s = sceneFromJson(paneRow(4));
  RenderOptions quiet;
  quiet.countStats = false;
  RenderResult cut = render(s, quiet);
  EXPECT_EQ(cut.stats.truncated, 64u) << "every pixel's tree is cut short";
  RenderResult counted = render(s);
  // A tree stops at the budget: no pixel traces more reflection and refraction rays than that.
  EXPECT_LE(counted.stats.reflection + counted.stats.refraction + counted.stats.eye, 64u * gpu::kMaxTreeRays);
  for (const auto& p : cut.image.pixels) EXPECT_TRUE(std::isfinite(p.x) && p.x <= 1.0f + 1e-5f);
  // Each reflected branch weighs at most R = 0.04 at normal incidence: a bailout of 0.05 leaves a
  // tree of one ray per interface, well within the budget.
  s.render.bailout = 0.05;
  EXPECT_EQ(render(s, quiet).stats.truncated, 0u);

  Scene glass = loadScene(scenePath("glass.json"));
  glass.render.width = 80;
  glass.render.height = 60;
  glass.render.maxDepth = 16;
  glass.render.bailout = 1e-6;
  glass.render.spp = 4;
  EXPECT_EQ(render(glass, quiet).stats.truncated, 0u);
}

// A stack too small for the tree drops branches and counts them instead of corrupting anything.
// Depth first, the refracted child is followed and the reflected one waits, so a ray crossing a
// row of 12 glass slabs (24 interfaces) at normal incidence leaves one waiting branch per
// interface: more than kMaxStackSize = 16.
TEST(RenderRefraction, BranchesBeyondTheStackAreCounted) {
  Scene s = sceneFromJson(paneRow(12));
  RenderResult r = render(s);
  EXPECT_GT(r.stats.stackOverflow, 0u);
  EXPECT_EQ(r.stats.nonFinite, 0u);
  for (const auto& p : r.image.pixels) EXPECT_TRUE(std::isfinite(p.x) && p.x <= 1.0f + 1e-5f);
  // Each reflected branch weighs at most R = 0.04 (normal incidence, n = 1.5): a bailout of 0.05
  // leaves nothing waiting, so nothing is dropped.
  s.render.bailout = 0.05;
  EXPECT_EQ(render(s).stats.stackOverflow, 0u);
}

TEST(RenderRefraction, OpaqueAndAttenuatedShadowsOfGlass) {
  // The camera looks under the pane from the side; the light is straight above it.
  Scene s = sceneFromJson(R"({
    "camera": { "position": [4, 1.5, 0], "look_at": [0, 0, 0], "fov_y": 40 },
    "image": { "width": 32, "height": 32 }, "ambient": [0.1, 0.1, 0.1],
    "materials": { "floor": { "color": [1, 1, 1], "ambient": 1, "diffuse": 1 },
                   "half": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "transmission": 0.5, "ior": 1.0 } },
    "lights": [ { "position": [0, 10, 0] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
                 { "type": "polygon", "material": "half", "vertices": [[-0.5,1,-0.5],[-0.5,1,0.5],[0.5,1,0.5],[0.5,1,-0.5]] } ] })");
  // The pane is one face with transmission 0.5: attenuated shadows let half the light through.
  s.render.transmissiveShadows = TransmissiveShadows::Attenuated;
  s.render.maxDepth = 0;
  RenderResult att = render(s);
  s.render.transmissiveShadows = TransmissiveShadows::Opaque;
  RenderResult opq = render(s);
  ReferenceTracer refA(s);
  // Floor pixels the camera sees directly, inside the pane's shadow (with a margin at its rim).
  int checked = 0;
  for (std::uint32_t y = 0; y < 32; ++y) {
    for (std::uint32_t x = 0; x < 32; ++x) {
      RefHit h = refA.closestHit(refA.eyeOrigin(), refA.eyeDirection(x + 0.5, y + 0.5));
      if (!h.hit() || h.kind != 1) continue;
      double px = h.p.x * (10.0 - 1.0) / 10.0, pz = h.p.z * 9.0 / 10.0; // where the light ray crosses y = 1
      if (std::abs(px) > 0.45 || std::abs(pz) > 0.45) continue;
      double ndotl = glm::normalize(s.lights[0].position - h.p).y;
      EXPECT_NEAR(att.image.at(x, y).x, 0.1 + 0.5 * ndotl, 1e-4) << x << "," << y;
      EXPECT_NEAR(opq.image.at(x, y).x, 0.1, 1e-5) << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0) << "no floor pixel is in the pane's shadow and visible";
}

} // namespace
} // namespace vkray::test
