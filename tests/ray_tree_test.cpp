// The ray-tree inspector (render/ray_tree.h, shaders/lib/tree_record.glsl): the tree the kernel
// records for a pixel is the host reference tracer's tree (same rays, same objects, the same
// contributions), its contributions add up to the pixel, and the recorder costs nothing when off.
#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "render/kernel_variants.h"
#include "render/ray_tree.h"
#include "render/renderer.h"
#include "scene/features.h"
#include "scene/scene_loader.h"
#include "vk/spirv_fold.h"

#include "reference.h"
#include "test_support.h"
#include "trace_norecorder_spv.h" // kTraceNoRecorderSpv: trace.comp without the recorder
#include "trace_spv.h"            // kTraceSpv

namespace vkray::test {
namespace {

namespace fs = std::filesystem;

// Everything the tree has: a dielectric with Fresnel both ways, a mirror, an opaque occluder, two
// shadowing lights, ambient light and a coloured background, on a diffuse floor. No checker: its
// cell boundaries would make the float and double colours differ by a whole cell on a few pixels.
const char* const kTreeScene = R"({
  "camera": { "position": [0, 1.6, 6], "look_at": [0, 0.8, 0], "fov_y": 45 },
  "image": { "width": 64, "height": 48 },
  "background": [0.3, 0.4, 0.6], "ambient": [0.2, 0.2, 0.2],
  "render": { "max_depth": 4, "bailout": 0.01 },
  "materials": {
    "floor": { "color": [0.8, 0.75, 0.6], "ambient": 0.3, "diffuse": 0.7, "specular": 0.2, "shininess": 20 },
    "glass": { "color": [1, 1, 1], "diffuse": 0, "specular": 0.5, "shininess": 200, "transmission": 0.95,
               "ior": 1.5, "absorption": [0.05, 0.2, 0.4] },
    "mirror": { "color": [0.9, 0.9, 0.9], "diffuse": 0.1, "specular": 0.4, "shininess": 100, "reflection": 0.8 },
    "red": { "color": [0.9, 0.2, 0.15], "ambient": 0.2, "diffuse": 0.8 }
  },
  "lights": [ { "position": [-3, 6, 4], "color": [0.8, 0.8, 0.8] },
              { "position": [4, 5, 3], "color": [0.4, 0.4, 0.45] } ],
  "objects": [
    { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
    { "type": "sphere", "center": [-1.0, 0.8, 0.3], "radius": 0.8, "material": "glass" },
    { "type": "sphere", "center": [1.1, 0.7, -0.4], "radius": 0.7, "material": "mirror" },
    { "type": "sphere", "center": [0.1, 0.35, 1.4], "radius": 0.35, "material": "red" }
  ] })";

int refKindOf(ObjectKind k) {
  switch (k) {
  case ObjectKind::Sphere:
    return 0;
  case ObjectKind::Plane:
    return 1;
  case ObjectKind::Polygon:
    return 2;
  default:
    return 3;
  }
}

// Each ray of a recorded tree by its path from the eye, as RefTreeRay names them.
std::map<std::string, const InspectedRay*> byPath(const RayTree& tree) {
  std::vector<std::string> paths(tree.rays.size());
  std::map<std::string, const InspectedRay*> out;
  for (std::size_t i = 0; i < tree.rays.size(); ++i) {
    const InspectedRay& r = tree.rays[i];
    std::string here;
    if (r.kind == TreeRayKind::Eye) {
      here = "eye";
    } else {
      const std::string up = r.parent ? paths[*r.parent] : "?";
      here = up + (r.kind == TreeRayKind::Reflection   ? "/R"
                   : r.kind == TreeRayKind::Refraction ? "/T"
                                                       : "/L" + std::to_string(r.light.value_or(99)));
    }
    paths[i] = here;
    out[here] = &r;
  }
  return out;
}

int outcomeCode(TreeOutcome o) {
  return static_cast<int>(o); // Background, Surface, Light, Blocked, Unshadowed: gpu::kTree* order
}

// The kernel's tree for a pixel against the reference's, ray by ray. Contributions: float32
// geometry and shading against double agree to ~1e-6 relative along a path; Fresnel factors and
// Beer-Lambert over a path of a few units amplify that ~10x, so 2e-4 absolute plus 1e-3 relative
// holds with a wide margin and still catches a missing or doubled term (the smallest terms here
// are ~1e-3).
void expectSameTree(const RayTree& gpuTree, const std::vector<RefTreeRay>& ref) {
  auto rays = byPath(gpuTree);
  ASSERT_EQ(rays.size(), gpuTree.rays.size()) << "two rays with one path";
  EXPECT_EQ(gpuTree.rays.size(), ref.size());
  for (const RefTreeRay& r : ref) {
    SCOPED_TRACE(r.path);
    auto it = rays.find(r.path);
    ASSERT_NE(it, rays.end()) << "the kernel did not trace this ray";
    const InspectedRay& g = *it->second;
    EXPECT_EQ(static_cast<int>(g.kind), r.kind);
    EXPECT_EQ(outcomeCode(g.outcome), r.outcome);
    if (r.objectKind >= 0) {
      ASSERT_TRUE(g.object.has_value());
      EXPECT_EQ(refKindOf(g.object->kind), r.objectKind);
      EXPECT_EQ(g.object->index, r.objectIndex);
    } else {
      EXPECT_FALSE(g.object.has_value());
    }
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(g.contribution[c], r.contribution[c], 2e-4 + 1e-3 * std::abs(r.contribution[c])) << "channel " << c;
    }
  }
}

// Every 4th pixel of the scene: its recorded tree is the reference's, and its contributions add up
// to the pixel, which is the full render's pixel.
TEST(RenderRayTree, EveryRayMatchesTheHostReferenceTree) {
  Scene s = sceneFromJson(kTreeScene);
  RenderResult full = render(s);
  ReferenceTracer ref(s);
  int pixels = 0, glassTrees = 0, blocked = 0, mirrored = 0;
  for (std::uint32_t y = 1; y < s.render.height; y += 4) {
    for (std::uint32_t x = 2; x < s.render.width; x += 4) {
      SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
      renderer().setScene(s);
      RayTree tree = renderer().inspect(s.camera, s.render, RenderOptions{}, glm::uvec2(x, y));
      expectNoValidationMessages();
      std::vector<RefTreeRay> refTree;
      glm::dvec3 refValue = ref.radiance(ref.eyeOrigin(), ref.eyeDirection(x + 0.5, y + 0.5), refTree);
      expectSameTree(tree, refTree);
      const glm::dvec3 sum = tree.contributionSum();
      const glm::vec3 rendered = full.image.at(x, y);
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(sum[c], tree.value[c], 1e-6 + 1e-5 * tree.value[c]);
        EXPECT_EQ(static_cast<float>(tree.value[c]), rendered[c]) << "the inspected pixel is the render's";
        EXPECT_NEAR(tree.value[c], refValue[c], 5e-4 + 2e-3 * refValue[c]);
      }
      ++pixels;
      for (const InspectedRay& r : tree.rays) {
        glassTrees += r.kind == TreeRayKind::Refraction && r.depth == 2;
        blocked += r.outcome == TreeOutcome::Blocked;
        mirrored += r.kind == TreeRayKind::Reflection && r.object && r.object->kind == ObjectKind::Plane;
      }
    }
  }
  EXPECT_EQ(pixels, 16 * 12);
  // The grid reaches what the test is about: through the glass, into shadow, off the mirror.
  EXPECT_GT(glassTrees, 3);
  EXPECT_GT(blocked, 3);
  EXPECT_GT(mirrored, 3);
}

// Several samples: one eye ray each, numbered, their contributions averaged into the pixel.
TEST(RenderRayTree, EachSampleIsATreeAndTheyAverageToThePixel) {
  Scene s = sceneFromJson(kTreeScene);
  s.render.spp = 4;
  RenderResult full = render(s);
  const glm::uvec2 pixel(20, 27); // the glass sphere's edge: the samples' trees differ
  renderer().setScene(s);
  RayTree tree = renderer().inspect(s.camera, s.render, RenderOptions{}, pixel);
  expectNoValidationMessages();
  EXPECT_EQ(tree.samples, 4u);
  std::vector<std::uint32_t> eyeSamples;
  for (const InspectedRay& r : tree.rays) {
    if (r.kind == TreeRayKind::Eye) eyeSamples.push_back(r.sample);
    if (r.parent) {
      EXPECT_EQ(r.sample, tree.rays[*r.parent].sample);
    }
  }
  EXPECT_EQ(eyeSamples, (std::vector<std::uint32_t>{0, 1, 2, 3}));
  const glm::dvec3 sum = tree.contributionSum();
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(sum[c], tree.value[c], 1e-6 + 1e-5 * tree.value[c]);
    EXPECT_EQ(static_cast<float>(tree.value[c]), full.image.at(pixel.x, pixel.y)[c]);
  }
}

// Two facing mirrors: the tree is a chain of reflections, cut by the depth cap; with a bailout the
// kernel stops where the weights are provably below it, and the JSON says which.
TEST(RenderRayTree, TheDepthCapAndTheBailoutAreReportedWhereTheyCut) {
  const std::string mirrors = R"({
    "camera": { "position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 30 },
    "image": { "width": 8, "height": 8 }, "background": [0.5, 0.5, 0.5],
    "render": { "max_depth": 3, "bailout": 0 },
    "materials": { "m": { "color": [1, 1, 1], "diffuse": 0.2, "reflection": 0.6 } },
    "lights": [ { "position": [0, 0, -0.5] } ],
    "objects": [ { "type": "plane", "normal": [0, 0, 1], "offset": 2, "material": "m" },
                 { "type": "plane", "normal": [0, 0, -1], "offset": 1, "material": "m" } ] })";
  Scene s = sceneFromJson(mirrors);
  renderer().setScene(s);
  RayTree capped = renderer().inspect(s.camera, s.render, RenderOptions{}, glm::uvec2(4, 4));
  expectNoValidationMessages();
  std::vector<const InspectedRay*> chain;
  for (const InspectedRay& r : capped.rays)
    if (r.kind != TreeRayKind::Shadow) chain.push_back(&r);
  ASSERT_EQ(chain.size(), 4u); // eye + 3 reflections
  for (std::size_t i = 0; i + 1 < chain.size(); ++i) EXPECT_EQ(chain[i]->cuts, 0u);
  EXPECT_EQ(chain.back()->cuts, gpu::kTreeCutDepth);
  EXPECT_EQ(chain.back()->depth, 3u);
  std::string json = rayTreeJson(capped, s);
  EXPECT_NE(json.find(R"("cut":[{"branch":"reflection and refraction","by":"depth"}])"), std::string::npos) << json;

  // Weights 1, 0.6, 0.36: with bailout 0.5 only the first reflection is worth tracing.
  s.render.bailout = 0.5;
  renderer().setScene(s);
  RayTree bailed = renderer().inspect(s.camera, s.render, RenderOptions{}, glm::uvec2(4, 4));
  std::size_t traced = std::count_if(bailed.rays.begin(), bailed.rays.end(),
                                     [](const InspectedRay& r) { return r.kind != TreeRayKind::Shadow; });
  EXPECT_EQ(traced, 2u);
  json = rayTreeJson(bailed, s);
  EXPECT_NE(json.find(R"("by":"bailout")"), std::string::npos) << json;
  EXPECT_EQ(json.find(R"("by":"depth")"), std::string::npos) << json;
}

// A record buffer too small for the tree keeps its first rays and counts the others.
TEST(RenderRayTree, RaysBeyondTheCapacityAreCountedNotWritten) {
  Scene s = sceneFromJson(kTreeScene);
  renderer().setScene(s);
  RayTree whole = renderer().inspect(s.camera, s.render, RenderOptions{}, glm::uvec2(14, 27));
  ASSERT_GT(whole.rays.size(), 4u);
  RayTree part = renderer().inspect(s.camera, s.render, RenderOptions{}, glm::uvec2(14, 27), 3);
  expectNoValidationMessages();
  EXPECT_EQ(part.rays.size(), 3u);
  EXPECT_EQ(part.notRecorded, whole.rays.size() - 3);
  EXPECT_EQ(part.value, whole.value);
}

// Function code of a module: instructions between OpFunction and OpFunctionEnd, by opcode.
std::map<std::uint32_t, int> functionOpcodes(const std::vector<std::uint32_t>& spirv) {
  std::map<std::uint32_t, int> count;
  bool inFunction = false;
  for (std::size_t i = 5; i < spirv.size();) {
    const std::uint32_t words = spirv[i] >> 16, opcode = spirv[i] & 0xFFFFu;
    if (opcode == 54) inFunction = true; // OpFunction
    if (inFunction) ++count[opcode];
    if (opcode == 56) inFunction = false; // OpFunctionEnd
    i += std::max<std::uint32_t>(words, 1);
  }
  return count;
}

// Off, the recorder costs nothing: for every bundled scene the trace kernel with its recorder,
// specialized as that scene renders, folds to the same instructions as the kernel built without
// the recorder at all. On, it adds code.
TEST(TreeRecorder, SpecializedOffItFoldsToTheKernelWithoutIt) {
  int scenes = 0;
  for (const auto& entry : fs::directory_iterator(VKRAY_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().filename().string());
    Scene s = loadScene(entry.path());
    Features f = analyzeScene(s, s.render);
    f.applySettings(s.render);
    GpuScene packed = packScene(s, s.camera.position, f.useBvh);
    for (bool record : {false, true}) {
      RenderOptions options;
      options.recordTree = record;
      vulkan::Specialization spec =
          specializationFor(f, s.render, options, shapeOf(packed), SceneMemoryUse{}, s.render.spp == 1, false);
      vulkan::FoldedSpirv with = vulkan::foldSpecialization(kTraceSpv, spec);
      vulkan::FoldedSpirv without = vulkan::foldSpecialization(kTraceNoRecorderSpv, spec);
      ASSERT_TRUE(with.error.empty()) << with.error;
      ASSERT_TRUE(without.error.empty()) << without.error;
      auto a = functionOpcodes(with.code), b = functionOpcodes(without.code);
      int sizeA = 0, sizeB = 0;
      for (auto& [op, n] : a) sizeA += n;
      for (auto& [op, n] : b) sizeB += n;
      if (record) {
        EXPECT_GT(sizeA, sizeB + 50) << "the recorder, on, adds its code";
      } else {
        EXPECT_EQ(a, b) << sizeA << " instructions against " << sizeB;
      }
    }
    ++scenes;
  }
  EXPECT_GE(scenes, 10);
}

// ---- The command line -------------------------------------------------------------------------

class CliInspect : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = freshScratchDir("cli-inspect");
    scene_ = dir_ / "tree.json";
    std::ofstream(scene_) << kTreeScene;
  }
  void TearDown() override { fs::remove_all(dir_); }
  CliRun vkray(const std::string& args) const { return runVkray(args, dir_); }
  fs::path dir_, scene_;
};

// `render --inspect X,Y` prints the documented JSON; with -o it writes the image too, whose pixel
// is the tree's value; --inspect-out writes the JSON to a file.
TEST_F(CliInspect, PrintsTheTreeAsJsonWhoseContributionsSumToThePixel) {
  fs::path pfm = dir_ / "out.pfm";
  CliRun r = vkray("render '" + scene_.string() + "' --inspect 14,27 -o '" + pfm.string() + "' -q --validate");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["pixel"], nlohmann::json::array({14, 27}));
  EXPECT_EQ(doc["samples"], 1);
  const auto& rays = doc["rays"];
  ASSERT_GT(rays.size(), 4u);
  EXPECT_EQ(rays[0]["kind"], "eye");
  EXPECT_TRUE(rays[0]["parent"].is_null());
  glm::dvec3 sum(0.0);
  std::set<std::string> kinds;
  for (const auto& ray : rays) {
    for (const char* key : {"index", "kind", "parent", "origin", "direction", "hit", "weight", "contribution"})
      EXPECT_TRUE(ray.contains(key)) << key << " in " << ray.dump();
    kinds.insert(ray["kind"].get<std::string>());
    for (int c = 0; c < 3; ++c) sum[c] += ray["contribution"][c].get<double>();
  }
  EXPECT_EQ(kinds, (std::set<std::string>{"eye", "shadow", "reflection", "refraction"}));
  Image image = readImage(pfm);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(doc["value"][c].get<double>(), image.at(14, 27)[c], 1e-7);
    EXPECT_NEAR(sum[c], image.at(14, 27)[c], 1e-5);
  }

  fs::path json = dir_ / "tree-out.json";
  r = vkray("render '" + scene_.string() + "' --inspect 14,27 --inspect-out '" + json.string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(nlohmann::json::parse(slurp(json)), doc);
}

TEST_F(CliInspect, BadPixelsAndCombinationsAreRefusedInOneLine) {
  struct Case {
    std::string flags, message;
  };
  const std::vector<Case> cases = {
      {"--inspect 14", "vkray: error: --inspect: expected a pixel as X,Y (two integers >= 0), got '14'\n"},
      {"--inspect -1,2", "vkray: error: --inspect: expected a pixel as X,Y (two integers >= 0), got '-1,2'\n"},
      {"--inspect 1.5,2", "vkray: error: --inspect: expected a pixel as X,Y (two integers >= 0), got '1.5,2'\n"},
      {"--inspect 64,0", "vkray: error: --inspect: pixel 64,0 is outside the 64 x 48 image\n"},
      {"--inspect-out x.json", "vkray: error: --inspect-out: needs --inspect X,Y\n"},
      {"--inspect 1,1 --stats", "vkray: error: --inspect: prints its JSON on standard output, where --stats prints "
                                "too: give --inspect-out FILE\n"},
      {"", "vkray: error: -o: an output image is required (.png, .pfm or .exr)\n"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.flags);
    CliRun r = vkray("render '" + scene_.string() + "' " + c.flags);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_EQ(r.err, c.message);
    EXPECT_EQ(r.out, "");
  }
}

} // namespace
} // namespace vkray::test
