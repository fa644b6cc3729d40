// Eye-ray culling by rows (host/render/row_culling.h): the host's test is conservative (rows it
// calls empty are missed by every ray through them, checked by brute force in double precision), it
// does cull what it should (the sky above the showcase), and a culled render equals a traced one bit
// for bit, ray counts included.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "render/gpu_scene.h"
#include "render/row_culling.h"
#include "scene/scene_loader.h"
#include "test_support.h"

namespace vkray::test {
namespace {

// Whether the ray o + t d (t > 0) meets a sphere or a plane of the scene, in double.
bool meetsAnything(const Scene& scene, const glm::dvec3& o, const glm::dvec3& d) {
  for (const Sphere& s : scene.spheres) {
    glm::dvec3 f = o - s.center;
    double a = glm::dot(d, d);
    double b = glm::dot(f, d);
    double c = glm::dot(f, f) - s.radius * s.radius;
    double disc = b * b - a * c;
    if (disc >= 0.0 && (-b + std::sqrt(disc)) / a > 0.0) return true;
  }
  for (const Plane& p : scene.planes) {
    double denom = glm::dot(p.normal, d);
    if (denom != 0.0 && -(glm::dot(p.normal, o) + p.offset) / denom > 0.0) return true;
  }
  return false;
}

Scene randomScene(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Scene scene;
  scene.materials.push_back(Material{});
  const int spheres = static_cast<int>(rng() % 4);
  for (int i = 0; i < spheres; ++i) {
    scene.spheres.push_back(Sphere{glm::dvec3(4 * u(rng), 2 * u(rng), 4 * u(rng)), 0.2 + 0.8 * (u(rng) + 1.0), 0});
  }
  if (rng() % 2) scene.planes.push_back(Plane{glm::normalize(glm::dvec3(0.2 * u(rng), 1.0, 0.2 * u(rng))), 1.5, 0});
  scene.camera.position = glm::dvec3(6 * u(rng), 3 * u(rng), 8 + 4 * u(rng));
  scene.camera.lookAt = glm::dvec3(u(rng), u(rng), u(rng));
  scene.camera.fovY = 30.0 + 40.0 * (u(rng) + 1.0);
  return scene;
}

TEST(RowCulling, RowsCalledEmptyAreMissedByEveryRayThroughThem) {
  std::mt19937 rng(7);
  const std::uint32_t width = 96;
  const std::uint32_t height = 64;
  int emptyRows = 0;
  int tracedRows = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Scene scene = randomScene(rng);
    GpuScene g = packScene(scene, scene.camera.position, false);
    CameraFrame cam = makeCameraFrame(scene.camera, width, height);
    CullScene cull = makeCullScene(g, cam);
    for (const RowRun& run : splitRows(cull, width, height, 0, height, 8)) {
      (run.empty ? emptyRows : tracedRows) += static_cast<int>(run.rows);
      if (!run.empty) continue;
      // Every sample position a pixel of these rows can have: a grid over the rows' area, edges
      // included.
      for (int iy = 0; iy <= 16; ++iy) {
        for (int ix = 0; ix <= 96; ++ix) {
          double px = width * ix / 96.0;
          double py = run.row0 + run.rows * iy / 16.0;
          glm::dvec3 d = cam.rayDirection(px, py, width, height);
          ASSERT_FALSE(meetsAnything(scene, scene.camera.position, d))
              << "trial " << trial << ": rows " << run.row0 << "+" << run.rows << " called empty, but the ray at ("
              << px << ", " << py << ") meets the scene";
        }
      }
    }
  }
  // Not vacuous: both verdicts occur.
  EXPECT_GT(emptyRows, 200);
  EXPECT_GT(tracedRows, 200);
}

TEST(RowCulling, TheShowcasesSkyIsCulledAndItsSpheresAndFloorAreNot) {
  Scene scene = loadScene(scenePath("showcase.json"));
  const std::uint32_t width = 640;
  const std::uint32_t height = 480;
  GpuScene g = packScene(scene, scene.camera.position, false);
  CullScene cull = makeCullScene(g, makeCameraFrame(scene.camera, width, height));
  std::vector<RowRun> runs = splitRows(cull, width, height, 0, height, 8);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_TRUE(runs[0].empty);
  EXPECT_FALSE(runs[1].empty);
  // The horizon (n.d = 0) is at row 140; the mirror sphere's top, above the eye, a little higher.
  EXPECT_GE(runs[0].rows, 96u);
  EXPECT_LE(runs[0].rows, 136u);
}

TEST(RowCulling, AnEyeOnAPlaneOrInsideTheBoxCullsNothing) {
  Scene scene;
  scene.materials.push_back(Material{});
  scene.planes.push_back(Plane{glm::dvec3(0, 1, 0), 0.0, 0});
  scene.camera.position = glm::dvec3(0, 0, 5); // on the plane
  scene.camera.lookAt = glm::dvec3(0, 10, 0);
  GpuScene g = packScene(scene, scene.camera.position, false);
  EXPECT_FALSE(rowsSeeNothing(makeCullScene(g, makeCameraFrame(scene.camera, 64, 64)), 64, 64, 0, 8));

  Scene inside;
  inside.materials.push_back(Material{});
  inside.spheres.push_back(Sphere{glm::dvec3(0), 10.0, 0});
  inside.camera.position = glm::dvec3(0, 0, 5);
  inside.camera.lookAt = glm::dvec3(0, 0, 0);
  GpuScene gi = packScene(inside, inside.camera.position, false);
  for (std::uint32_t y = 0; y < 64; y += 8) {
    EXPECT_FALSE(rowsSeeNothing(makeCullScene(gi, makeCameraFrame(inside.camera, 64, 64)), 64, 64, y, 8));
  }
}

// The filled rows are written with the traced miss's arithmetic and counters: images and ray counts
// equal, on scenes with sky above them, for pixel-centre, stratified and adaptive sampling.
TEST(RenderRowCulling, CulledRendersEqualTracedOnesBitForBit) {
  const char* scenes[] = {"showcase.json", "seed.json", "glass.json", "numerics-far-sphere.json"};
  // The last: progressive passes, where the host adds the sums of the rows that see nothing.
  const char* settings[] = {R"("render": { "spp": 1 })", R"("render": { "spp": 3 })",
                            R"("render": { "spp": 4, "antialiasing": "adaptive" })",
                            R"("render": { "noise_threshold": 0.01, "min_spp": 8, "max_spp": 64 })"};
  std::uint32_t culledProgressive = 0;
  for (const char* name : scenes) {
    for (const char* s : settings) {
      SCOPED_TRACE(std::string(name) + " " + s);
      Scene scene = sceneFromJson(std::string(R"({ "base": ")") + name +
                                  R"(", "image": { "width": 80, "height": 60 }, )" + s + "}");
      RenderOptions culled;
      RenderOptions traced;
      traced.cullRows = false;
      RenderResult a = render(scene, culled);
      RenderResult b = render(scene, traced);
      ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
      std::size_t different = 0;
      for (std::size_t i = 0; i < a.image.pixels.size(); ++i) different += a.image.pixels[i] != b.image.pixels[i];
      EXPECT_EQ(different, 0u);
      EXPECT_EQ(a.stats.eye, b.stats.eye);
      EXPECT_EQ(a.stats.shadow, b.stats.shadow);
      EXPECT_EQ(a.stats.reflection, b.stats.reflection);
      EXPECT_EQ(a.stats.refraction, b.stats.refraction);
      EXPECT_EQ(a.stats.refinedPixels, b.stats.refinedPixels);
      // Per pixel (progressive renders keep them): the same samples, error estimates and rays.
      EXPECT_EQ(a.pixels.samples, b.pixels.samples);
      EXPECT_EQ(a.pixels.error, b.pixels.error);
      EXPECT_EQ(a.pixels.rays, b.pixels.rays);
      if (scene.render.noiseThreshold > 0.0) culledProgressive += a.timings.culledRows;
      // The culled rows' eye rays, answered without a trace, are counted apart as well: a sample
      // each for every pixel of those rows (uniform sampling; adaptive's refine pass culls nothing),
      // or each pixel's own samples (progressive, whose rows split as the whole image's).
      EXPECT_EQ(b.timings.culledEyeRays, 0u);
      const std::uint32_t w = scene.render.width, h = scene.render.height;
      std::uint64_t expected = 0;
      if (scene.render.noiseThreshold > 0.0) {
        GpuScene g = packScene(scene, scene.camera.position, false);
        for (const RowRun& run :
             splitRows(makeCullScene(g, makeCameraFrame(scene.camera, w, h)), w, h, 0, h, gpu::kWorkgroupSizeY)) {
          if (!run.empty) continue;
          for (std::uint32_t y = run.row0; y < run.row0 + run.rows; ++y)
            for (std::uint32_t x = 0; x < w; ++x) expected += static_cast<std::uint64_t>(a.pixels.samples[y * w + x]);
        }
      } else {
        const bool adaptive = scene.render.antialiasing == Antialiasing::Adaptive;
        expected =
            std::uint64_t{a.timings.culledRows} * w * (adaptive ? 1u : static_cast<std::uint32_t>(scene.render.spp));
      }
      EXPECT_EQ(a.timings.culledEyeRays, expected);
      EXPECT_LE(a.timings.culledEyeRays, a.stats.eye);
    }
  }
  EXPECT_GT(culledProgressive, 0u) << "some progressive render had rows that see nothing";
  expectNoValidationMessages();
}

} // namespace
} // namespace vkray::test
