// "Simulate only the effects a scene calls for": scene analysis, exact ray counts, the bailout and
// its error bound, and proof that specialization never changes a pixel.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "reference.h"
#include "render/kernel_variants.h"
#include "scene/features.h"
#include "scene/scene_loader.h"
#include "test_support.h"
#include "vk/compute_pipeline.h"
#include "vk/fold_cache.h"
#include "vk/spirv_fold.h"

namespace vkray::test {
namespace {

// Two parallel mirrors (planes y = 0 and y = 2) seen from between them: every eye ray bounces
// forever, so the number of rays at each level is exactly the number of pixels.
std::string parallelMirrors(double reflection, int depth, double bailout) {
  return R"({ "camera": { "position": [0, 1, 0], "look_at": [1, 0.3, 0.2], "fov_y": 30 },
    "image": { "width": 24, "height": 16 }, "ambient": [0.5, 0.5, 0.5],
    "render": { "max_depth": )" +
         std::to_string(depth) + R"(, "bailout": )" + std::to_string(bailout) + R"( },
    "materials": { "m": { "color": [1, 1, 1], "ambient": 0.2, "diffuse": 0.5, "reflection": )" +
         std::to_string(reflection) + R"( } },
    "lights": [ { "position": [0, 1, 0] } ],
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "m" },
                 { "type": "plane", "normal": [0, -1, 0], "offset": 2, "material": "m" } ] })";
}

TEST(FeaturesAnalysis, SceneWithoutMirrorsNeedsDepthZero) {
  Scene s = sceneFromJson(R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] }, "render": { "max_depth": 10 },
    "objects": [ { "type": "sphere", "center": [0,0,0], "radius": 1 } ] })");
  Features f = analyzeScene(s, s.render);
  EXPECT_EQ(f.usableDepth, 0);
  EXPECT_FALSE(f.reflection);
  EXPECT_FALSE(f.refraction);
  EXPECT_FALSE(f.shadows);
  auto lines = f.explain();
  EXPECT_NE(std::find(lines.begin(), lines.end(), "reflection: off — no reflective or transmissive material"),
            lines.end());
}

TEST(FeaturesAnalysis, BailoutLimitsTheUsableDepth) {
  // Weight 0.5 per bounce, bailout 1/255: 0.5^7 = 1/128 is traced, 0.5^8 = 1/256 is not.
  Scene s = sceneFromJson(parallelMirrors(0.5, 20, 1.0 / 255.0));
  Features f = analyzeScene(s, s.render);
  EXPECT_TRUE(f.reflection);
  EXPECT_EQ(f.usableDepth, 7);
  s.render.bailout = 0.0;
  f.applySettings(s.render);
  EXPECT_EQ(f.usableDepth, 20);
}

TEST(FeaturesAnalysis, ShadowsNeedAnOccluder) {
  Scene one = sceneFromJson(R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] },
    "lights": [ { "position": [0, 5, 0] } ], "objects": [ { "type": "sphere", "center": [0,0,0], "radius": 1 } ] })");
  EXPECT_FALSE(analyzeScene(one, one.render).shadows); // one convex object cannot shadow itself
  Scene off =
      sceneFromJson(R"({ "base": "showcase.json", "lights": [ { "position": [0, 5, 0], "shadows": false } ] })");
  Features f = analyzeScene(off, off.render);
  EXPECT_FALSE(f.shadows);
  EXPECT_EQ(f.explain()[1], "shadows: off — every light has shadows: false");
}

TEST(FeaturesAnalysis, FloorBelowEverythingCannotCastShadows) {
  Scene s = sceneFromJson(R"({ "base": "showcase.json" })");
  EXPECT_EQ(planesThatCanOcclude(s), std::vector<bool>{false});
  // A sphere dipping below the floor makes the floor an occluder for that sphere's lower part.
  s.spheres[0].center.y = 0.5;
  EXPECT_EQ(planesThatCanOcclude(s), std::vector<bool>{true});
  // So does a light under the floor, and a second plane that crosses it.
  Scene walls = sceneFromJson(R"({ "base": "showcase.json", "objects": [
      { "type": "plane", "normal": [0, 1, 0], "offset": 0 }, { "type": "plane", "normal": [1, 0, 0], "offset": 3 } ] })");
  EXPECT_EQ(planesThatCanOcclude(walls), (std::vector<bool>{true, true}));
}

TEST(FeaturesAnalysis, OnlySpecularOnlyMaterialsCompileInTheFaintHighlightTest) {
  // Glass has no diffuse term, so its kernel weighs each light's highlight before sampling it; the
  // showcase's materials all have one, and its kernel compiles the test out (kSpecSpecularOnly).
  for (const char* name : {"glass.json", "showcase.json"}) {
    SCOPED_TRACE(name);
    Scene scene = loadScene(std::filesystem::path(VKRAY_SOURCE_DIR) / "scenes" / name);
    Features f = analyzeScene(scene, scene.render);
    const bool glass = std::string(name) == "glass.json";
    EXPECT_EQ(f.specularOnlyMaterial, glass);
    vulkan::Specialization spec =
        specializationFor(f, scene.render, RenderOptions{}, SceneShape{}, SceneMemoryUse{}, false, false);
    EXPECT_EQ(spec.values().at(gpu::kSpecSpecularOnly), glass ? 1u : 0u);
    RenderOptions everything;
    everything.specialize = false; // --no-specialize: every feature compiled in
    vulkan::Specialization all =
        specializationFor(f, scene.render, everything, SceneShape{}, SceneMemoryUse{}, false, false);
    EXPECT_EQ(all.values().at(gpu::kSpecSpecularOnly), 1u);
  }
}

TEST(RenderStats, NoMirrorsAtDepthTenTracesNoSecondaryRaysAndMatchesDepthZero) {
  Scene s = sceneFromJson(R"({ "base": "showcase.json", "image": { "width": 64, "height": 48 },
    "materials": { "mirror": { "reflection": 0 }, "floor": { "reflection": 0 }, "glossy": { "reflection": 0 } } })");
  s.render.maxDepth = 10;
  RenderResult deep = render(s);
  EXPECT_EQ(deep.stats.reflection, 0u);
  EXPECT_EQ(deep.stats.refraction, 0u);
  EXPECT_EQ(deep.stats.maxDepth, 0u);
  s.render.maxDepth = 0;
  RenderResult flat = render(s);
  EXPECT_EQ(deep.image.pixels, flat.image.pixels); // bit-identical
  EXPECT_EQ(deep.stats.total(), flat.stats.total());
}

TEST(RenderStats, LightsWithoutShadowsTraceNoShadowRays) {
  Scene s = sceneFromJson(R"({ "base": "showcase.json", "image": { "width": 32, "height": 24 },
    "lights": [ { "position": [-4, 7, 5] , "shadows": false }, { "position": [5, 5, 3], "shadows": false } ] })");
  RenderResult r = render(s);
  EXPECT_EQ(r.stats.shadow, 0u);
  EXPECT_GT(r.stats.reflection, 0u);
}

TEST(RenderStats, CountsAreExactPerLevel) {
  // Every eye ray of the parallel mirrors reflects at every level, and every hit point sees the
  // light (half-way between the planes) by exactly one unblocked shadow ray.
  const std::uint64_t pixels = 24 * 16;
  for (int depth = 0; depth <= 4; ++depth) {
    Scene s = sceneFromJson(parallelMirrors(0.5, depth, 0.0));
    RenderResult r = render(s);
    EXPECT_EQ(r.stats.eye, pixels);
    EXPECT_EQ(r.stats.reflection, pixels * static_cast<std::uint64_t>(depth)) << "depth " << depth;
    EXPECT_EQ(r.stats.shadow, pixels * static_cast<std::uint64_t>(depth + 1)) << "depth " << depth;
    EXPECT_EQ(r.stats.maxDepth, static_cast<std::uint32_t>(depth));
  }
}

TEST(RenderStats, MirrorSphereReflectionRaysEqualItsPixels) {
  // One mirror sphere (bright red ambient) on black: a reflected ray can only escape, so there is
  // exactly one reflection ray per pixel that sees the sphere, and none at level 2.
  Scene s = sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 40 },
    "image": { "width": 64, "height": 48 }, "ambient": [1, 1, 1], "background": [0, 0, 0.25],
    "render": { "max_depth": 3, "bailout": 0 },
    "materials": { "m": { "color": [1, 0, 0], "ambient": 1, "diffuse": 0, "reflection": 0.5 } },
    "objects": [ { "type": "sphere", "center": [0.2, 0.1, 0], "radius": 1.1, "material": "m" } ] })");
  RenderResult r = render(s);
  std::uint64_t spherePixels = 0;
  for (const auto& p : r.image.pixels) spherePixels += p.x > 0.5f;
  EXPECT_GT(spherePixels, 500u);
  EXPECT_EQ(r.stats.reflection, spherePixels);
  EXPECT_EQ(r.stats.maxDepth, 1u);
}

TEST(RenderStats, SpecularOnlySurfacesSampleALightOnlyWhereItsHighlightCounts) {
  // A sphere with no diffuse term (as glass) lit by one light: its only use for the light is the
  // Phong highlight, which at shininess 300 adds less than kNegligibleHighlight to the pixel a few
  // degrees from the mirror direction, so only those pixels trace a shadow ray; a light 10^6 times
  // as bright keeps a wider highlight and traces more. With the least diffuse term, every pixel
  // that faces the light does. Counted here in double precision, per pixel centre.
  auto sceneWith = [](const std::string& kd, const std::string& light) {
    return sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 40 },
      "image": { "width": 64, "height": 48 }, "ambient": [0.2, 0.2, 0.2], "render": { "max_depth": 0 },
      "materials": { "m": { "color": [1, 1, 1], "ambient": 0.5, "specular": 0.9, "shininess": 300, "diffuse": )" +
                         kd + R"( } },
      "lights": [ { "position": [3, 4, 5], "color": [)" +
                         light + "," + light + "," + light + R"(] } ],
      "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 1.2, "material": "m" },
                   { "type": "sphere", "center": [1.5, 2, 2.5], "radius": 0.2, "material": "m" } ] })");
  };
  Scene specularOnly = sceneWith("0", "1");
  ReferenceTracer ref(specularOnly);
  const glm::dvec3 light = specularOnly.lights[0].position;
  std::uint64_t facing = 0, highlight = 0, brightHighlight = 0;
  for (std::uint32_t y = 0; y < 48; ++y) {
    for (std::uint32_t x = 0; x < 64; ++x) {
      glm::dvec3 d = ref.eyeDirection(x + 0.5, y + 0.5);
      RefHit h = ref.closestHit(ref.eyeOrigin(), d);
      if (!h.hit()) continue; // the small sphere is out of view: every hit is the large one's
      glm::dvec3 n = glm::normalize(h.n), l = glm::normalize(light - h.p);
      double ndotl = glm::dot(n, l);
      if (ndotl <= 0) continue;
      ++facing;
      double rv = glm::dot(2.0 * ndotl * n - l, -d);
      double spec = rv > 0 ? 0.9 * std::pow(rv, 300.0) : 0.0;
      highlight += spec >= gpu::kNegligibleHighlight;
      brightHighlight += 1e6 * spec >= gpu::kNegligibleHighlight;
    }
  }
  ASSERT_GT(facing, 500u);
  ASSERT_GT(highlight, 10u);
  EXPECT_LT(highlight, facing / 4);
  EXPECT_GT(brightHighlight, highlight + 10);
  // float against double: a pixel whose highlight lies within rounding of the floor may go either way.
  // Each facing pixel either traces its shadow ray or counts a faint highlight (--stats): the two
  // add up to the pixels that face the light.
  RenderResult dim = render(specularOnly);
  EXPECT_NEAR(static_cast<double>(dim.stats.shadow), static_cast<double>(highlight), 2.0);
  EXPECT_NEAR(static_cast<double>(dim.stats.faintHighlights), static_cast<double>(facing - highlight), 2.0);
  EXPECT_NEAR(static_cast<double>(dim.stats.shadow + dim.stats.faintHighlights), static_cast<double>(facing), 2.0);
  RenderResult bright = render(sceneWith("0", "1e6"));
  EXPECT_NEAR(static_cast<double>(bright.stats.shadow), static_cast<double>(brightHighlight), 2.0);
  EXPECT_EQ(bright.stats.shadow + bright.stats.faintHighlights, dim.stats.shadow + dim.stats.faintHighlights);
  RenderResult diffuse = render(sceneWith("1e-6", "1"));
  EXPECT_NEAR(static_cast<double>(diffuse.stats.shadow), static_cast<double>(facing), 2.0);
  EXPECT_EQ(diffuse.stats.faintHighlights, 0u); // a diffuse term uses every light that faces it
  EXPECT_EQ(diffuse.stats.shadow, dim.stats.shadow + dim.stats.faintHighlights);
}

TEST(RenderBailout, RaisingItMonotonicallyReducesRaysAndZeroTracesEverything) {
  std::uint64_t previous = ~0ull;
  for (double b : {0.0, 1.0 / 1024, 1.0 / 255, 1.0 / 64, 1.0 / 16, 0.3}) {
    Scene s = sceneFromJson(parallelMirrors(0.7, 12, b));
    RenderResult r = render(s);
    EXPECT_LE(r.stats.total(), previous) << "bailout " << b;
    previous = r.stats.total();
    if (b == 0.0) {
      EXPECT_EQ(r.stats.reflection, 24u * 16u * 12u); // every branch to max_depth
      EXPECT_EQ(r.stats.bailoutSaved, 0u);
    } else {
      // Depth k carries weight 0.7^k: the first level below b is not traced.
      int k = static_cast<int>(std::floor(std::log(b) / std::log(0.7)));
      std::uint32_t expectedDepth = static_cast<std::uint32_t>(std::clamp(k, 0, 12));
      EXPECT_EQ(r.stats.maxDepth, expectedDepth) << "bailout " << b;
    }
  }
}

// The error a bailout b introduces: every branch not traced has weight w < b and would have
// returned at most R, the largest radiance any ray can carry, so each pixel is off by less than
// (skipped branches) * b * R. With one child per hit (mirrors) at most one branch per eye ray is
// skipped, and R <= Lmax / (1 - m), where Lmax bounds one hit's local colour (or the background)
// and m < 1 is the largest weight per bounce: error < b * Lmax / (1 - m).
TEST(RenderBailout, ErrorIsBoundedByTheThreshold) {
  // Parallel mirrors, 24 bounces at weight 0.7: every bailout below cuts the tree somewhere.
  Scene s = sceneFromJson(parallelMirrors(0.7, 24, 0.0));
  double lmax = 0.0;
  for (const Material& m : s.materials) {
    double local = 0.0;
    for (int c = 0; c < 3; ++c) {
      double v = m.ambient * m.color[c] * s.ambientLight[c];
      for (const PointLight& l : s.lights) v += l.color[c] * (m.diffuse * m.color[c] + m.specular);
      local = std::max(local, v);
    }
    lmax = std::max(lmax, local);
  }
  for (int c = 0; c < 3; ++c) lmax = std::max(lmax, s.background[c]);
  double m = 0.7; // the mirrors' reflection, the largest weight per bounce
  s.render.bailout = 0.0;
  Image exact = render(s).image;
  for (double b : {1.0 / 255, 1.0 / 64, 1.0 / 16}) {
    s.render.bailout = b;
    Image approx = render(s).image;
    double bound = b * lmax / (1.0 - m);
    double worst = 0.0;
    for (std::size_t i = 0; i < exact.pixels.size(); ++i) {
      for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::abs(exact.pixels[i][c] - approx.pixels[i][c])));
    }
    EXPECT_LT(worst, bound) << "bailout " << b;
    EXPECT_GT(worst, 0.0) << "bailout " << b << " changed nothing: the test scene is too easy";
  }
}

// A bundled scene at comparison size: 24 rows, its aspect kept, at most 4 spp.
Scene smallBundledScene(const std::filesystem::path& path) {
  Scene s = loadScene(path);
  double aspect = double(s.render.width) / s.render.height;
  s.render.height = 24;
  s.render.width = static_cast<std::uint32_t>(std::max(1.0, std::round(24 * aspect)));
  s.render.spp = std::min(s.render.spp, 4);
  return s;
}

// For every bundled scene: the specialized pipeline and the all-features one give identical images
// (bit for bit on the reference CPU driver; see variantsExact for other devices).
TEST(RenderSpecialization, ChangesNoPixelInAnyBundledScene) {
  int scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(VKRAY_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().filename().string());
    Scene s = smallBundledScene(entry.path());
    RenderOptions general;
    general.specialize = false;
    RenderResult specialized = render(s);
    RenderResult everything = render(s, general);
    expectSameImageAcrossVariants(specialized.image, everything.image);
    EXPECT_EQ(specialized.stats.total(), everything.stats.total());
    ++scenes;
  }
  EXPECT_GE(scenes, 4);
}

// Folding the specialization into the SPIR-V (vk/spirv_fold.h) hands the driver the code it would
// have kept itself: for every bundled scene the image and the ray counts equal those of the
// module handed over whole with its constants (--no-spirv-folding), and the folded module is
// smaller than the whole one.
TEST(RenderSpecialization, FoldingIntoTheSpirvChangesNoPixel) {
  int scenes = 0;
  // A renderer of its own: the suite's shares pipelines across tests, and the folded ones of these
  // scenes would come built already, with no creation time or size to compare.
  Renderer own(gpu(), nullptr);
  auto renderOwn = [&](const Scene& s, const RenderOptions& options) {
    own.setScene(s);
    RenderResult r = own.render(s.camera, s.render, options);
    expectNoValidationMessages();
    return r;
  };
  auto traceBuild = [](const RenderResult& r) {
    for (const PipelineBuild& p : r.timings.pipelinesBuilt) {
      if (p.name == "trace") return p;
    }
    ADD_FAILURE() << "the render built no trace pipeline";
    return PipelineBuild{};
  };
  // Spheres, planes and mirrors; glass; textures; a BVH over meshes; a polygon and a far ground.
  for (const char* name :
       {"showcase.json", "glass.json", "textured.json", "meshes.json", "numerics-huge-ground.json"}) {
    SCOPED_TRACE(name);
    Scene s = smallBundledScene(std::filesystem::path(VKRAY_SOURCE_DIR "/scenes") / name);
    RenderOptions whole;
    whole.foldSpirv = false;
    RenderResult folded = renderOwn(s, RenderOptions{});
    RenderResult unfolded = renderOwn(s, whole);
    EXPECT_EQ(folded.image.pixels, unfolded.image.pixels);
    EXPECT_EQ(folded.stats.total(), unfolded.stats.total());
    PipelineBuild f = traceBuild(folded), u = traceBuild(unfolded);
    EXPECT_GT(f.foldMs, 0.0);
    EXPECT_EQ(u.foldMs, 0.0);
    EXPECT_GT(f.spirvBytes, 0u);
    EXPECT_LT(f.spirvBytes, u.spirvBytes);
    ++scenes;
  }
  EXPECT_EQ(scenes, 5);
}

// What SPIRV-Tools cannot read is refused, not folded: the caller then hands the original over.
TEST(SpirvFolding, ABrokenModuleIsReportedNotFolded) {
  std::vector<std::uint32_t> junk{0x07230203u, 0x00010300u, 0u, 5u, 0u, 0xdeadbeefu};
  vulkan::Specialization spec;
  spec.set(0u, 1u);
  vulkan::FoldedSpirv folded = vulkan::foldSpecialization(junk, spec);
  EXPECT_TRUE(folded.code.empty());
  EXPECT_FALSE(folded.error.empty());
}

// Folded modules kept on disk (vk/fold_cache.h): what is stored comes back word for word under its
// key and under no other; a file that does not check out (a byte changed, cut short, a stray
// extra byte) is a miss, never a module handed to the driver; the key covers every constant; and
// only the most recently used files are kept.
TEST(SpirvFolding, KeptModulesComeBackAsStoredAndDamagedOnesAreMissed) {
  namespace fs = std::filesystem;
  const fs::path dir = freshScratchDir("fold-cache") / "folded";
  vulkan::FoldCache cache(dir, 2);
  std::vector<std::uint32_t> module{0x07230203u, 0x00010300u, 7u, 42u, 0u, 0x00020011u, 1u};
  vulkan::Specialization spec;
  spec.set(3u, 1u);
  const std::uint64_t key = vulkan::FoldCache::key(module, spec);
  EXPECT_TRUE(cache.load(key).empty()) << "nothing stored yet";
  cache.store(key, module);
  EXPECT_EQ(cache.load(key), module);
  EXPECT_TRUE(cache.load(key + 1).empty());

  vulkan::Specialization other = spec;
  other.set(3u, 0u);
  EXPECT_NE(vulkan::FoldCache::key(module, other), key);
  other = spec;
  other.set(4u, 0u);
  EXPECT_NE(vulkan::FoldCache::key(module, other), key);
  std::vector<std::uint32_t> changed = module;
  changed[3] = 43u;
  EXPECT_NE(vulkan::FoldCache::key(changed, spec), key);

  const fs::path file = cache.fileFor(key);
  const std::string good = slurp(file);
  auto rewrite = [&](const std::string& bytes) {
    std::ofstream(file, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  };
  std::string flipped = good;
  flipped[flipped.size() - 2] ^= 0x10;
  rewrite(flipped);
  EXPECT_TRUE(cache.load(key).empty()) << "a changed byte";
  rewrite(good.substr(0, good.size() - 4));
  EXPECT_TRUE(cache.load(key).empty()) << "cut short";
  rewrite(good + "x");
  EXPECT_TRUE(cache.load(key).empty()) << "a stray byte";
  rewrite("");
  EXPECT_TRUE(cache.load(key).empty()) << "empty";
  rewrite(good);
  EXPECT_EQ(cache.load(key), module);

  // Two more modules with room for two: the least recently used (the first) goes.
  // (Pauses: distinct modification times, as the file system's clock may be coarser than the
  // one the load above marked its file with.)
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  cache.store(key + 1, module);
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  cache.store(key + 2, module);
  EXPECT_FALSE(fs::exists(cache.fileFor(key)));
  EXPECT_EQ(cache.load(key + 1), module);
  EXPECT_EQ(cache.load(key + 2), module);

  // Without a directory nothing is kept or found.
  vulkan::FoldCache off{fs::path()};
  off.store(key, module);
  EXPECT_TRUE(off.load(key).empty());
  fs::remove_all(dir.parent_path());
}

// A render whose folded module comes from an earlier run's cache builds the same kernel: the second
// renderer, given a pipeline cache in the same directory, reads the module back instead of folding
// it, and its image and ray counts are those of the first.
TEST(RenderSpecialization, AFoldedModuleKeptOnDiskGivesTheSamePixels) {
  const std::filesystem::path dir = freshScratchDir("fold-kept");
  Scene s = smallBundledScene(std::filesystem::path(VKRAY_SOURCE_DIR "/scenes") / "glass.json");
  auto renderWithCache = [&](PipelineBuild& trace) {
    vulkan::PipelineCache cache(gpu(), dir / "pipelines.bin");
    Renderer own(gpu(), &cache);
    own.setScene(s);
    RenderResult r = own.render(s.camera, s.render, RenderOptions{});
    expectNoValidationMessages();
    for (const PipelineBuild& p : r.timings.pipelinesBuilt) {
      if (p.name == "trace") trace = p;
    }
    return r;
  };
  PipelineBuild first, second;
  RenderResult a = renderWithCache(first);
  RenderResult b = renderWithCache(second);
  ASSERT_EQ(first.name, "trace");
  ASSERT_EQ(second.name, "trace");
  EXPECT_FALSE(first.foldKept);
  EXPECT_TRUE(second.foldKept);
  EXPECT_EQ(first.spirvBytes, second.spirvBytes);
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_EQ(a.stats.total(), b.stats.total());
  std::filesystem::remove_all(dir);
}

// Storage-buffer and uniform-buffer scene layouts read the same values.
TEST(RenderSpecialization, SceneMemoryLayoutsAgree) {
  Scene s = sceneFromJson(R"({ "base": "showcase.json", "image": { "width": 40, "height": 30 } })");
  RenderOptions storage;
  storage.sceneMemory = SceneMemory::Storage;
  RenderOptions uniform;
  uniform.sceneMemory = SceneMemory::Uniform;
  EXPECT_EQ(render(s, storage).image.pixels, render(s, uniform).image.pixels);
}

// A small scene of every kind (baked counts, read into registers before the first branch:
// loadSceneRegisters in shaders/lib/scene.glsl) gives the image of the all-features pipeline, which
// reads every array from memory at run-time counts, and of the storage-buffer layout. Several of
// each kind, so that a hit's material, sphere, plane, triangle or polygon is picked per lane.
TEST(RenderSpecialization, SceneInRegistersAgreesWithMemory) {
  Scene s = sceneFromJson(R"({
    "camera": { "position": [0, 2, 7], "look_at": [0, 0.6, 0], "fov_y": 50 },
    "image": { "width": 48, "height": 36 },
    "render": { "max_depth": 3 },
    "materials": {
      "a": { "color": [0.8, 0.3, 0.2], "diffuse": 0.8, "ambient": 0.1, "specular": 0.4, "shininess": 30 },
      "b": { "color": [0.2, 0.6, 0.8], "diffuse": 0.6, "reflection": 0.4 },
      "c": { "color": [0.9, 0.9, 0.8], "diffuse": 0.7, "checker": { "color2": [0.1, 0.1, 0.1], "scale": 0.5 } },
      "d": { "color": [0.3, 0.8, 0.3], "diffuse": 0.5, "specular": 0.6, "shininess": 80, "reflection": 0.2 }
    },
    "lights": [ { "position": [-3, 6, 4], "color": [0.8, 0.8, 0.8] },
                { "position": [4, 3, 2], "color": [0.4, 0.4, 0.5] },
                { "position": [0, 5, -4], "color": [0.2, 0.3, 0.2], "shadows": false } ],
    "objects": [
      { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "c" },
      { "type": "plane", "normal": [0, 0, 1], "offset": 6, "material": "b" },
      { "type": "sphere", "center": [-1.5, 0.7, 0], "radius": 0.7, "material": "a" },
      { "type": "sphere", "center": [1.4, 0.6, 0.5], "radius": 0.6, "material": "b" },
      { "type": "sphere", "center": [0, 0.4, 1.5], "radius": 0.4, "material": "d" },
      { "type": "triangle", "vertices": [[-2.5, 0, -1.5], [-0.5, 0, -1.5], [-1.5, 1.8, -1.5]], "material": "d" },
      { "type": "triangle", "vertices": [[0.5, 0, -1.5], [2.5, 0, -1.5], [1.5, 1.5, -1.2]], "material": "a" },
      { "type": "polygon", "vertices": [[-0.6, 0.01, -0.4], [0.6, 0.01, -0.4], [0.6, 1.0, -0.4], [-0.6, 1.0, -0.4]], "material": "a" },
      { "type": "polygon", "vertices": [[2.0, 0.01, 1.8], [2.8, 0.01, 1.2], [2.8, 1.2, 1.2], [2.0, 1.2, 1.8]], "material": "d" }
    ] })");
  s.render.bvh = BvhMode::Off; // brute force: the counts stay baked
  RenderResult registers = render(s);
  RenderOptions general;
  general.specialize = false;
  RenderOptions storage;
  storage.sceneMemory = SceneMemory::Storage;
  EXPECT_EQ(registers.image.pixels, render(s, general).image.pixels);
  EXPECT_EQ(registers.image.pixels, render(s, storage).image.pixels);
  EXPECT_GT(registers.stats.shadow, 0u);
  EXPECT_GT(registers.stats.reflection, 0u);
}

// A scene too large for the uniform block still reads its materials, lights and planes from it
// (on a CPU device): the same image as with everything in storage buffers.
TEST(RenderSpecialization, ShadingFromTheUniformBlockAgreesWithStorage) {
  Scene s = loadScene(VKRAY_SOURCE_DIR "/scenes/meshes.json");
  s.render.width = 48;
  s.render.height = 36;
  RenderOptions storage;
  storage.sceneMemory = SceneMemory::Storage;
  RenderOptions automatic;
  RenderResult a = render(s, storage);
  RenderResult b = render(s, automatic);
  EXPECT_EQ(a.image.pixels, b.image.pixels);
  EXPECT_GT(a.stats.shadow, 0u);
  EXPECT_GT(a.stats.reflection, 0u);
}

// The BVH walk takes two descent steps between its subgroup votes in trees from
// gpu::kBvhTwoStepDepth deep on (fewer votes where lanes rarely finish after one step), one in
// shallower trees (where the second is often wasted), and one wherever there is no BVH; an option
// forces either. (GpuBvh.EyeRayHitsEqualBruteForce checks that two give the same hits.)
TEST(KernelVariants, TwoDescentStepsPerVoteInDeepTrees) {
  Scene scene = loadScene(std::filesystem::path(VKRAY_SOURCE_DIR) / "scenes" / "meshes.json");
  Features f = analyzeScene(scene, scene.render);
  ASSERT_TRUE(f.useBvh);
  auto steps = [&](int depth, bool hasBvh, int forced) {
    SceneShape shape;
    shape.hasBvh = hasBvh;
    shape.bvhDepth = depth;
    RenderOptions options;
    options.bvhStepsPerVote = forced;
    return specializationFor(f, scene.render, options, shape, SceneMemoryUse{}, false, false)
        .values()
        .at(gpu::kSpecBvhStepsPerVote);
  };
  EXPECT_EQ(steps(gpu::kBvhTwoStepDepth - 1, true, 0), 1u);
  EXPECT_EQ(steps(gpu::kBvhTwoStepDepth, true, 0), 2u);
  EXPECT_EQ(steps(40, true, 0), 2u);
  EXPECT_EQ(steps(40, false, 0), 1u); // no BVH: no walk
  EXPECT_EQ(steps(40, true, 1), 1u);
  EXPECT_EQ(steps(3, true, 2), 2u);
}

} // namespace
} // namespace vkray::test
