// The command line with model files and its rough edges: `vkray render MODEL -o OUT` renders a picture
// that is not only background; refused models are one line with no output; --version; did-you-mean
// for flags and subcommands; --explain with --stats prints its block once.
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "test_support.h"

#include "image/image_io.h"

namespace vkray::test {
namespace {

namespace fs = std::filesystem;

const fs::path kAssimp = "/usr/share/assimp/models";

using Outcome = CliRun;

class CliModel : public ::testing::Test {
protected:
  void SetUp() override { dir_ = test::freshScratchDir("cli-model"); }
  void TearDown() override { fs::remove_all(dir_); }

  // build/vkray with args (shell-quoted), on lavapipe.
  Outcome vkray(const std::string& args) const { return runVkray(args, dir_); }

  // Renders a model; the share of pixels that are not the background.
  double modelCoverage(const fs::path& model, const std::string& flags = "") {
    fs::path out = dir_ / "model.pfm";
    fs::remove(out);
    Outcome r = vkray("render '" + model.string() + "' -o '" + out.string() +
                      "' --width 96 --height 72 -q --validate --background 0.5,0,0.5 " + flags);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    if (r.exitCode != 0) return 0.0;
    Image image = readImage(out);
    std::size_t covered = std::count_if(image.pixels.begin(), image.pixels.end(), [](const glm::vec3& p) {
      return glm::length(p - glm::vec3(0.5f, 0.0f, 0.5f)) > 1e-3f;
    });
    return double(covered) / double(image.pixels.size());
  }

  fs::path dir_;
};

TEST_F(CliModel, GltfAndObjModelsRenderDirectly) {
  if (!fs::exists(kAssimp)) GTEST_SKIP() << kAssimp << " is absent (apt-get install assimp-testmodels)";
  // Framed with a margin: the model covers a good share of the image, never all of it.
  for (const char* model : {"glTF2/BoxTextured-glTF/BoxTextured.gltf", "OBJ/WusonOBJ.obj"}) {
    double coverage = modelCoverage(kAssimp / model);
    EXPECT_GT(coverage, 0.05) << model;
    EXPECT_LT(coverage, 0.95) << model;
  }
}

TEST_F(CliModel, BundledFixturesRenderDirectlyAndTheFloorFillsTheBottom) {
  fs::path box = fs::path(VKRAY_SOURCE_DIR) / "tests/data/meshes/box.obj";
  double bare = modelCoverage(box);
  double floored = modelCoverage(box, "--floor");
  EXPECT_GT(bare, 0.05);
  EXPECT_GT(floored, bare + 0.1);
}

// A model opened on its own has no scene file to give it a material: a usemtl its library lacks
// renders grey with one warning; the same file as a scene's mesh is refused, naming the fix.
TEST_F(CliModel, AMissingMaterialIsGreyForAModelAndAnErrorInAScene) {
  fs::path obj = dir_ / "quad.obj";
  std::ofstream(obj) << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl Missing\nf 1 2 3 4\n";
  fs::path out = dir_ / "out.png";
  Outcome r = vkray("render '" + obj.string() + "' -o '" + out.string() + "' --width 32 --height 24 -q");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("vkray: warning: " + obj.string() +
                       ": usemtl 'Missing' is not in the material library; those faces get the default grey"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(out));

  fs::path scene = dir_ / "scene.json";
  std::ofstream(scene) << R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
                              "objects": [ { "type": "mesh", "file": "quad.obj" } ] })";
  fs::path out2 = dir_ / "out2.png";
  r = vkray("render '" + scene.string() + "' -o '" + out2.string() + "' -q");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("usemtl 'Missing' is not in the material library (give the mesh a 'material'"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out2));
}

TEST_F(CliModel, RefusedModelIsOneLineAndWritesNothing) {
  fs::path bad = dir_ / "points.obj";
  std::ofstream(bad) << "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\n";
  fs::path out = dir_ / "out.png";
  Outcome r = vkray("render '" + bad.string() + "' -o '" + out.string() + "'");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("vkray: error: " + bad.string() + ": no triangles:"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliModel, FloorAndBackgroundAreForModelFilesOnly) {
  Outcome r =
      vkray("render '" VKRAY_SOURCE_DIR "/scenes/showcase.json' -o '" + (dir_ / "x.png").string() + "' --floor");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("--floor: only for model files"), std::string::npos) << r.err;
  r = vkray("render '" VKRAY_SOURCE_DIR "/tests/data/meshes/box.obj' -o '" + (dir_ / "x.png").string() +
            "' --background 1,2");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("--background: expected r,g,b"), std::string::npos) << r.err;
}

TEST_F(CliModel, StatsGiveEachMeshsBoundsAndTriangles) {
  Outcome r = vkray("render '" VKRAY_SOURCE_DIR "/tests/data/meshes/box.obj' -o '" + (dir_ / "x.png").string() +
                    "' --width 32 --height 24 -q --stats");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("box.obj: 12 triangles, 0 degenerate dropped, bounds ["), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("pipeline cache: "), std::string::npos);
  EXPECT_NE(r.out.find("bytes kept by the driver"), std::string::npos) << r.out;
}

TEST_F(CliModel, VersionIsOneLine) {
  Outcome r = vkray("--version");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.out.rfind("vkray 0.", 0), 0u) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
}

TEST_F(CliModel, MisspeltFlagAndSubcommandGetADidYouMean) {
  Outcome flag = vkray("render '" VKRAY_SOURCE_DIR "/scenes/showcase.json' -o x.png --stast");
  EXPECT_EQ(flag.exitCode, 1);
  EXPECT_NE(flag.err.find("--stast (did you mean --stats?)"), std::string::npos) << flag.err;
  Outcome sub = vkray("rendr '" VKRAY_SOURCE_DIR "/scenes/showcase.json' -o x.png");
  EXPECT_EQ(sub.exitCode, 1);
  EXPECT_NE(sub.err.find("(did you mean 'render'?)"), std::string::npos) << sub.err;
  Outcome nested = vkray("bench tme x.json");
  EXPECT_NE(nested.err.find("(did you mean 'time'?)"), std::string::npos) << nested.err;
  EXPECT_EQ(std::count(sub.err.begin(), sub.err.end(), '\n'), 1) << sub.err;
}

TEST_F(CliModel, ExplainWithStatsPrintsItsBlockOnce) {
  Outcome r = vkray("render '" VKRAY_SOURCE_DIR "/scenes/showcase.json' -o '" + (dir_ / "x.png").string() +
                    "' --width 32 --height 24 -q --stats --explain");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::size_t first = r.out.find("reflection: on");
  ASSERT_NE(first, std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("reflection: on", first + 1), std::string::npos) << r.out;
}

} // namespace
} // namespace vkray::test
