// Image-level numerical robustness: whole renders through the real kernel (trace.comp). A scene
// moved far from the world origin renders the same image (camera-relative packing, gpu_scene.h),
// and closed meshes seen from inside never show the background (watertight intersection, and no
// fixed epsilon that a small room falls under).
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "numerics_support.h"
#include "reference.h"
#include "test_support.h"

namespace vkray::test::numerics {
namespace {

// A small scene with every primitive kind, a checkered floor, mirror reflection and shadows from
// two lights, its every coordinate shifted by `shift`.
std::string shiftedScene(const dvec3& shift) {
  auto at = [&](double x, double y, double z) { return point(shift + dvec3(x, y, z)); };
  return R"({
    "camera": { "position": )" +
         at(0.3, 1.6, 6) + R"(, "look_at": )" + at(0, 0.7, 0) + R"(, "fov_y": 45 },
    "image": { "width": 64, "height": 48 }, "background": [0.2, 0.3, 0.5], "ambient": [0.2, 0.2, 0.2],
    "render": { "max_depth": 3 },
    "materials": {
      "floor": { "color": [0.9, 0.9, 0.85], "diffuse": 0.8, "ambient": 0.3,
                 "checker": { "color2": [0.2, 0.1, 0.1], "scale": 0.5 } },
      "mirror": { "color": [0.9, 0.9, 0.9], "diffuse": 0.1, "specular": 0.6, "shininess": 80, "reflection": 0.7 },
      "matte": { "color": [0.9, 0.6, 0.2], "diffuse": 0.8, "specular": 0.3, "shininess": 20 },
      "blue": { "color": [0.2, 0.4, 0.9], "diffuse": 0.8 } },
    "lights": [ { "position": )" +
         at(-4, 6, 5) + R"(, "color": [0.8, 0.8, 0.8] },
                { "position": )" +
         at(5, 4, 2) + R"(, "color": [0.4, 0.4, 0.5] } ],
    "objects": [
      { "type": "plane", "normal": [0, 1, 0], "point": )" +
         at(0, 0, 0) + R"(, "material": "floor" },
      { "type": "sphere", "center": )" +
         at(-1.1, 0.8, 0) + R"(, "radius": 0.8, "material": "mirror" },
      { "type": "sphere", "center": )" +
         at(1.2, 0.5, 0.6) + R"(, "radius": 0.5, "material": "matte" },
      { "type": "triangle", "vertices": [)" +
         at(0.2, 0, -1.5) + ", " + at(1.8, 0, -1.2) + ", " + at(1, 1.6, -1.4) +
         R"(], "material": "blue" },
      { "type": "polygon", "vertices": [)" +
         at(-2.6, 0, -2) + ", " + at(-1.2, 0, -2.2) + ", " + at(-1.2, 1.2, -2.2) + ", " + at(-2.6, 1.4, -2) +
         R"(], "material": "matte" } ] })";
}

// Whether the double-precision path of the ray (through mirrors, as the kernel follows it) meets a
// checkered surface within `margin` of a checker cell boundary.
bool nearCheckerBoundary(const Scene& scene, const ReferenceTracer& ref, dvec3 o, dvec3 d, double margin) {
  for (int depth = 0; depth <= scene.render.maxDepth; ++depth) {
    RefHit h = ref.closestHit(o, d, 1e-7);
    if (!h.hit()) return false;
    const Material& m = scene.materials[h.material];
    if (m.checker) {
      for (int axis : {0, 2}) {
        double q = h.p[axis] / m.checker->scale;
        if (std::abs(q - std::round(q)) * m.checker->scale < margin) return true;
      }
    }
    if (m.reflection <= 0.0) return false;
    dvec3 n = glm::dot(h.n, d) < 0.0 ? h.n : -h.n;
    d = d - 2.0 * glm::dot(d, n) * n;
    o = h.p;
  }
  return false;
}

TEST(NumericsImage, SceneMovedTo1e5RendersTheSameImage) {
  Scene base = sceneFromJson(shiftedScene(dvec3(0.0)));
  Image reference = render(base).image;
  for (dvec3 shift : {dvec3(1e4, -2e4, 3e4), dvec3(1e5, 1e5, -1e5), dvec3(-7.3e4, 2.9e4, 1.1e5)}) {
    Scene moved = sceneFromJson(shiftedScene(shift));
    Image image = render(moved).image;
    ReferenceTracer ref(moved);
    // Geometry is packed relative to the camera in double (gpu_scene.h), so every intersection sees
    // the same float values as at the origin and the images agree to 1e-4 (float noise in shading).
    // The checker is the one world-space quantity: frame.worldOffset + p rounds to ulp(|shift|), so
    // pixels whose path meets a cell boundary within 2 ulp(|shift|) of their hit may change cell.
    double margin = 2.0 * ulpOf(maxAbs(shift)) + 1e-4;
    int compared = 0, excused = 0, differing = 0;
    for (std::uint32_t y = 0; y < image.height; ++y) {
      for (std::uint32_t x = 0; x < image.width; ++x) {
        dvec3 d = ref.eyeDirection(x + 0.5, y + 0.5);
        if (nearCheckerBoundary(moved, ref, ref.eyeOrigin(), glm::normalize(d), margin)) {
          ++excused;
          continue;
        }
        ++compared;
        glm::vec3 a = reference.at(x, y), b = image.at(x, y);
        differing += a != b ? 1 : 0;
        for (int c = 0; c < 3; ++c) {
          EXPECT_NEAR(a[c], b[c], 1e-4) << "pixel " << x << "," << y << " channel " << c << " moved by " << str(shift);
        }
      }
    }
    // At |shift| = 1e5 the band is 0.016 either side of lines 0.5 apart: about 6% of the floor.
    EXPECT_GT(compared, 80 * (compared + excused) / 100) << "too many pixels excused near checker edges";
    std::printf("[ numerics ] scene moved by %-30s %d pixels compared (%d not bit-identical), %d near checker edges\n",
                str(shift).c_str(), compared, differing, excused);
  }
}

// A colour no surface in these scenes has.
const glm::vec3 kBackground(1.0f, 0.0f, 1.0f);

std::string insideScene(const Mesh& mesh, const dvec3& eye, const dvec3& lookAt, double fov, int size,
                        const std::string& bvh, const std::string& numerics) {
  return R"({
    "camera": { "position": )" +
         point(eye) + R"(, "look_at": )" + point(lookAt) + R"(, "fov_y": )" + std::to_string(fov) + R"( },
    "image": { "width": )" +
         std::to_string(size) + R"(, "height": )" + std::to_string(size) + R"( },
    "background": [1, 0, 1], "ambient": [1, 1, 1],
    "render": { "max_depth": 0, "bvh": ")" +
         bvh + R"(", "numerics": ")" + numerics + R"(" },
    "materials": { "wall": { "color": [0.5, 0.5, 0.5], "ambient": 1, "diffuse": 0 } },
    "objects": [ )" +
         meshJson(mesh, "wall") + " ] }";
}

int backgroundPixels(const Image& image) {
  int count = 0;
  for (const auto& p : image.pixels) count += p == kBackground ? 1 : 0;
  return count;
}

TEST(NumericsImage, ClosedMeshesSeenFromInsideShowNoBackground) {
  // Odd square images: the centre pixel looks straight down the view axis and the diagonal pixels
  // along the image diagonals, so views aimed at a vertex put rays exactly on vertices and edges.
  const dvec3 far(1.2e5, -3.0e4, 7.0e4);
  Mesh ball = icosphere(far, 2.0, 2);
  Mesh cube = mixedCube(far, 1.0);
  struct View {
    const Mesh* mesh;
    dvec3 eye, lookAt;
    double fov;
    const char* what;
  };
  const View views[] = {
      {&ball, far + dvec3(0.3, -0.2, 0.4), far + dvec3(1, 0.5, -2), 110, "icosphere, off-centre eye"},
      {&ball, far, dvec3(ball.vertices[0]), 90, "icosphere, aimed at a vertex"},
      {&cube, far, far + dvec3(1, 1, 1), 100, "mixed cube, aimed at a corner"},
      {&cube, far, far + dvec3(0, 0, -1), 100, "mixed cube, aimed at a fan centre"},
      {&cube, far + dvec3(0.5, -0.3, 0.2), far + dvec3(-1, 0.2, 1), 120, "mixed cube, off-centre eye"},
  };
  for (const View& v : views) {
    for (const char* bvh : {"off", "on"}) {
      Scene scene = sceneFromJson(insideScene(*v.mesh, v.eye, v.lookAt, v.fov, 49, bvh, "robust"));
      EXPECT_EQ(backgroundPixels(render(scene).image), 0) << v.what << ", bvh " << bvh;
    }
  }
}

// The sheet of scenes/numerics-cracks.json, 200 triangles 1e5 away: every pixel whose eye ray meets
// the sheet in double, and so do rays 0.3 pixel to each side (silhouette pixels are left out: the
// float eye ray and the float vertices differ from the double ones by far less than that), must
// show the sheet. Naive numerics let the background through cracks along shared edges.
TEST(NumericsImage, MeshAt1e5HasNoCracks) {
  auto sceneFor = [](const char* numerics) {
    return sceneFromJson(std::string(R"({ "base": "numerics-cracks.json", "image": { "width": 160, "height": 120 },
                                          "render": { "numerics": ")") +
                         numerics + R"(" } })");
  };
  Scene robust = sceneFor("robust");
  ReferenceTracer ref(robust);
  std::vector<bool> inside(160 * 120, false);
  int insideCount = 0;
  for (std::uint32_t y = 0; y < 120; ++y) {
    for (std::uint32_t x = 0; x < 160; ++x) {
      bool all = true;
      const double offsets[5][2] = {{0, 0}, {0.3, 0}, {-0.3, 0}, {0, 0.3}, {0, -0.3}};
      for (const auto& o : offsets) {
        dvec3 d = glm::normalize(ref.eyeDirection(x + 0.5 + o[0], y + 0.5 + o[1]));
        all = all && ref.closestHit(ref.eyeOrigin(), d).hit();
      }
      inside[y * 160 + x] = all;
      insideCount += all ? 1 : 0;
    }
  }
  int cracks[2] = {0, 0};
  for (int mode = 0; mode < 2; ++mode) {
    Scene scene = mode == 0 ? robust : sceneFor("naive");
    Image image = render(scene).image;
    const glm::vec3 background(scene.background);
    for (std::uint32_t i = 0; i < inside.size(); ++i)
      cracks[mode] += inside[i] && image.pixels[i] == background ? 1 : 0;
  }
  std::printf("[ numerics ] mesh at 1e5, background pixels inside the sheet: robust %d, naive %d of %d\n", cracks[0],
              cracks[1], insideCount);
  EXPECT_GT(insideCount, 5000);
  EXPECT_EQ(cracks[0], 0);
  EXPECT_GT(cracks[1], 0) << "naive numerics were expected to show cracks";
}

TEST(NumericsImage, TinyRoomSeenFromInsideShowsNoBackground) {
  // A closed room 1e-4 across: every wall is nearer than the naive mode's fixed epsilon (1e-4), so
  // naive rays pass through all of them; robust numerics have no epsilon on t.
  const dvec3 at(3.0, 1.0, -2.0);
  Mesh room = mixedCube(at, 5e-5);
  int background[2] = {0, 0};
  for (int mode = 0; mode < 2; ++mode) {
    Scene scene =
        sceneFromJson(insideScene(room, at, at + dvec3(1, 0.5, -0.7), 100, 33, "off", mode == 0 ? "robust" : "naive"));
    background[mode] = backgroundPixels(render(scene).image);
  }
  std::printf("[ numerics ] tiny closed room (1e-4), background pixels:     robust %d, naive %d of %d\n", background[0],
              background[1], 33 * 33);
  EXPECT_EQ(background[0], 0);
  EXPECT_GT(background[1], 0) << "naive numerics were expected to see through the tiny room";
}

// ---- Triangles at the edge of float32 --------------------------------------------------------------

// A closed icosphere (320 flat triangles) lit by one light, in a scene whose other objects (a floor
// and a unit sphere) make it about one unit across, seen from `distance` away from its centre.
std::string edgeMeshScene(const Mesh& mesh, const dvec3& center, double distance, const std::string& numerics) {
  const dvec3 view = glm::normalize(dvec3(0.3, 0.4, 0.87));
  return R"({
    "camera": { "position": )" +
         point(center + distance * view) + R"(, "look_at": )" + point(center) + R"(, "fov_y": 45 },
    "image": { "width": 64, "height": 64 }, "background": [1, 0, 1], "ambient": [0.5, 0.5, 0.5],
    "render": { "max_depth": 0, "numerics": ")" +
         numerics + R"(" },
    "materials": { "grey": { "color": [0.9, 0.9, 0.9], "ambient": 0.2, "diffuse": 0.8 } },
    "lights": [ { "position": )" +
         point(center + dvec3(2.0, 3.0, 1.0)) + R"(, "color": [1, 1, 1] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "point": )" +
         point(center - dvec3(0.0, 1.0, 0.0)) + R"(, "material": "grey" },
      { "type": "sphere", "center": )" +
         point(center + dvec3(3.0, 0.0, -2.0)) + R"(, "radius": 1, "material": "grey" }, )" + meshJson(mesh, "grey") +
         " ] }";
}

// Triangles 1e-6 of the scene's size (a few dozen ulps of their coordinates across), and a mesh at
// 1e5 from the origin seen from one unit away. No cracks: every pixel whose eye ray, and rays 0.3
// pixel to each side (which leaves out the silhouette), meets the mesh in double shows it. No
// self-shadowing: a face turned towards the light by n.l > 0.1 (flat triangles, convex mesh: nothing
// can shadow it) is lit, i.e. brighter than its ambient term by at least half its diffuse term.
TEST(NumericsImage, TrianglesAtTheEdgeOfFloatHaveNoCracksAndNoSelfShadow) {
  struct Case {
    const char* name;
    dvec3 center;
    double radius, distance;
  };
  for (const Case& c : {Case{"triangles 1e-6 across", dvec3(0.3, 0.2, 0.1), 4e-6, 1.2e-5},
                        Case{"mesh at 1e5, from 1 away", dvec3(1e5, 1e5, -1e5), 0.4, 1.3}}) {
    Mesh mesh = icosphere(c.center, c.radius, 2);
    int cracks[2] = {0, 0}, shadowed[2] = {0, 0}, covered = 0, lit = 0;
    for (int mode = 0; mode < 2; ++mode) {
      Scene scene = sceneFromJson(edgeMeshScene(mesh, c.center, c.distance, mode == 0 ? "robust" : "naive"));
      Image image = render(scene).image;
      ReferenceTracer ref(scene);
      const dvec3 light = scene.lights[0].position;
      covered = lit = 0;
      for (std::uint32_t y = 0; y < image.height; ++y) {
        for (std::uint32_t x = 0; x < image.width; ++x) {
          auto meshHit = [&](double dx, double dy) {
            RefHit h = ref.closestHit(ref.eyeOrigin(), glm::normalize(ref.eyeDirection(x + 0.5 + dx, y + 0.5 + dy)));
            return h.kind == 3 ? h : RefHit{};
          };
          RefHit h = meshHit(0, 0);
          if (!h.hit() || !meshHit(-0.3, 0).hit() || !meshHit(0.3, 0).hit() || !meshHit(0, -0.3).hit() ||
              !meshHit(0, 0.3).hit())
            continue;
          ++covered;
          glm::vec3 got = image.at(x, y);
          cracks[mode] += got == kBackground ? 1 : 0;
          dvec3 d = glm::normalize(ref.eyeDirection(x + 0.5, y + 0.5));
          dvec3 n = glm::dot(h.n, d) < 0.0 ? h.n : -h.n;
          double nl = glm::dot(n, glm::normalize(light - h.p));
          if (nl < 0.1) continue;
          ++lit;
          double ambient = 0.2 * 0.9 * 0.5, diffuse = 0.8 * 0.9 * nl;
          shadowed[mode] += got.g < ambient + 0.5 * diffuse ? 1 : 0;
        }
      }
    }
    std::printf("[ numerics ] %-26s cracks robust %d, naive %d; self-shadowed robust %d, naive %d (of %d, %d lit)\n",
                c.name, cracks[0], cracks[1], shadowed[0], shadowed[1], covered, lit);
    EXPECT_GT(covered, 1000) << c.name;
    EXPECT_GT(lit, 200) << c.name;
    EXPECT_EQ(cracks[0], 0) << c.name;
    EXPECT_EQ(shadowed[0], 0) << c.name;
    // The check can fail: the textbook hit point o + t d of a triangle 1e-6 across shadows its own face.
    if (c.radius < 1e-3) {
      EXPECT_GT(shadowed[1], 0) << "naive numerics were expected to self-shadow " << c.name;
    }
  }
}

} // namespace
} // namespace vkray::test::numerics
