// Tile files and merge: the bands of an image join back into it exactly; tiles that do not belong
// together (another fingerprint, size or frame), overlap or leave a gap are refused, naming the tile.
// The scene fingerprint tells renders apart by everything their pixels depend on.
#include <filesystem>
#include <functional>
#include <memory>

#include <gtest/gtest.h>

#include "test_support.h"

#include "image/image_io.h"
#include "image/tile_io.h"
#include "scene/scene_fingerprint.h"
#include "scene/texture.h"
#include "util/error.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;

class TileMerge : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::freshScratchDir("tiles");
    image_ = Image(7, 10);
    for (std::uint32_t y = 0; y < image_.height; ++y) {
      for (std::uint32_t x = 0; x < image_.width; ++x)
        image_.at(x, y) = glm::vec3(x * 0.1f, y * 0.37f, 1.0f / (1 + x + y));
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path tile(const std::string& name, std::uint32_t r0, std::uint32_t r1, const std::string& fp = "abc",
                int frame = 3) {
    TileInfo info{image_.width, image_.height, r0, r1, frame, fp, "s.json"};
    fs::path p = dir_ / name;
    writeTile(p, image_, info);
    return p;
  }
  std::string refusal(const std::vector<fs::path>& tiles) {
    try {
      mergeTiles(tiles);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(accepted)";
  }

  fs::path dir_;
  Image image_;
};

TEST_F(TileMerge, BandsJoinIntoTheImageInAnyOrder) {
  std::vector<fs::path> tiles;
  for (std::uint32_t i = 1; i <= 3; ++i) {
    std::uint32_t r0, r1;
    tileRows(image_.height, i, 3, r0, r1);
    // The name built by appending: GCC 12's -Wstringop-overflow misreads "t" + std::to_string(i).
    std::string name = std::to_string(i);
    name.append(".pfm");
    tiles.insert(tiles.begin(), tile("t" + name, r0, r1));
  }
  Image merged = mergeTiles(tiles);
  EXPECT_EQ(encodePfm(merged), encodePfm(image_));
  // Each tile is a plain PFM of its rows.
  EXPECT_EQ(readImage(tiles.back()).height, 3u);
}

TEST_F(TileMerge, BandsCoverEveryRowOnce) {
  for (std::uint32_t n : {1u, 3u, 7u, 10u}) {
    std::uint32_t next = 0;
    for (std::uint32_t i = 1; i <= n; ++i) {
      std::uint32_t r0, r1;
      tileRows(10, i, n, r0, r1);
      EXPECT_EQ(r0, next);
      EXPECT_GT(r1, r0);
      next = r1;
    }
    EXPECT_EQ(next, 10u);
  }
}

TEST_F(TileMerge, RefusesMismatchedFingerprints) {
  auto a = tile("a.pfm", 0, 5);
  auto b = tile("b.pfm", 5, 10, "def");
  EXPECT_NE(refusal({a, b}).find("b.pfm: has fingerprint def"), std::string::npos) << refusal({a, b});
}

TEST_F(TileMerge, RefusesOtherFrames) {
  auto a = tile("a.pfm", 0, 5);
  auto b = tile("b.pfm", 5, 10, "abc", 4);
  EXPECT_NE(refusal({a, b}).find("b.pfm: is of frame 4"), std::string::npos) << refusal({a, b});
}

TEST_F(TileMerge, RefusesOverlaps) {
  auto a = tile("a.pfm", 0, 6);
  auto b = tile("b.pfm", 5, 10);
  EXPECT_NE(refusal({a, b}).find("b.pfm: rows 5-9 overlap"), std::string::npos) << refusal({a, b});
}

// A tile listed twice (a shell glob and a name, say) is named as such, not as overlapping itself;
// so is the same file under another name.
TEST_F(TileMerge, RefusesATileGivenTwice) {
  auto a = tile("a.pfm", 0, 5);
  auto b = tile("b.pfm", 5, 10);
  EXPECT_EQ(refusal({a, a, b}), a.string() + ": is given twice");
  fs::path other = dir_ / "sub" / ".." / "a.pfm";
  fs::create_directories(dir_ / "sub");
  EXPECT_EQ(refusal({a, b, other}), other.string() + ": is the same file as " + a.string() + ", given before");
}

TEST_F(TileMerge, RefusesGaps) {
  auto a = tile("a.pfm", 0, 4);
  auto b = tile("b.pfm", 5, 10);
  EXPECT_NE(refusal({a, b}).find("no tile has rows 4-4"), std::string::npos) << refusal({a, b});
  auto c = tile("c.pfm", 4, 5);
  EXPECT_NE(refusal({a, c}).find("no tile has rows 5-9"), std::string::npos) << refusal({a, c});
  auto late = tile("late.pfm", 2, 10);
  EXPECT_NE(refusal({late}).find("no tile has rows 0-1"), std::string::npos) << refusal({late});
}

TEST_F(TileMerge, RefusesATileWithoutItsDescription) {
  auto a = tile("a.pfm", 0, 10);
  fs::remove(tileSidecarPath(a));
  EXPECT_NE(refusal({a}).find("no tile description"), std::string::npos) << refusal({a});
}

// One triangle with uvs and vertex colours; its material textured by a 2 x 2 image and cut out by alpha.
Scene texturedTriangle() {
  Scene s;
  TextureLevel image;
  image.width = 2;
  image.height = 2;
  image.texels = {glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1), glm::vec4(0, 0, 1, 0.5f), glm::vec4(1, 1, 1, 0)};
  auto texture = std::make_shared<Texture>();
  texture->levels = buildMipChain(image);
  s.textures.push_back(texture);
  Material m;
  m.baseColorTexture = MaterialTexture{};
  m.alphaCutoff = 0.5;
  s.materials.push_back(m);
  Triangle t;
  t.v[0] = glm::dvec3(0, 0, 0);
  t.v[1] = glm::dvec3(1, 0, 0);
  t.v[2] = glm::dvec3(0, 1, 0);
  t.uvs = std::array<glm::dvec4, 3>{glm::dvec4(0, 0, 0, 0), glm::dvec4(1, 0, 0, 0), glm::dvec4(0, 1, 0, 0)};
  t.colors = std::array<glm::dvec4, 3>{glm::dvec4(1), glm::dvec4(1), glm::dvec4(1)};
  s.triangles.push_back(t);
  return s;
}

// The texture of `s`, copied so that it can be changed (scenes share their textures).
Texture& ownTexture(Scene& s) {
  auto copy = std::make_shared<Texture>(*s.textures[0]);
  s.textures[0] = copy;
  return *copy;
}

TEST(SceneFingerprint, EqualScenesAgree) {
  // Built twice: equal contents in other objects (the textures are not the same pointer).
  EXPECT_EQ(sceneFingerprint(texturedTriangle(), 0), sceneFingerprint(texturedTriangle(), 0));
}

TEST(SceneFingerprint, EveryProgressiveForwardAndSeedSettingTellsScenesApart) {
  // Tiles rendered to another threshold, budget, sample range, method, photon count or seed are
  // tiles of another image: merge must refuse them.
  const std::string base = sceneFingerprint(texturedTriangle(), 0);
  const std::vector<std::pair<const char*, std::function<void(Scene&)>>> changes = {
      {"noise threshold", [](Scene& s) { s.render.noiseThreshold = 0.01; }},
      {"time limit", [](Scene& s) { s.render.timeLimit = 2.0; }},
      {"min spp", [](Scene& s) { s.render.minSpp = 8; }},
      {"max spp", [](Scene& s) { s.render.maxSpp = 256; }},
      {"method", [](Scene& s) { s.render.method = Method::Forward; }},
      {"photons", [](Scene& s) { s.render.photons = 12345; }},
      {"seed", [](Scene& s) { s.render.seed = 1; }},
  };
  for (const auto& [what, change] : changes) {
    Scene s = texturedTriangle();
    change(s);
    EXPECT_NE(sceneFingerprint(s, 0), base) << what;
  }
  Scene two = texturedTriangle();
  two.render.seed = 2;
  Scene one = texturedTriangle();
  one.render.seed = 1;
  EXPECT_NE(sceneFingerprint(two, 0), sceneFingerprint(one, 0));
}

TEST(SceneFingerprint, EveryTextureInputTellsScenesApart) {
  const std::string base = sceneFingerprint(texturedTriangle(), 0);
  const std::vector<std::pair<const char*, std::function<void(Scene&)>>> changes = {
      {"texture filter", [](Scene& s) { s.render.textureFilter = TextureFilter::Nearest; }},
      {"a texel", [](Scene& s) { ownTexture(s).levels[0].texels[3].x = 0.5f; }},
      {"a texel's alpha", [](Scene& s) { ownTexture(s).levels[0].texels[0].w = 0.75f; }},
      {"wrap", [](Scene& s) { ownTexture(s).wrapS = TextureWrap::Clamp; }},
      {"magnification", [](Scene& s) { ownTexture(s).nearest = true; }},
      {"minification", [](Scene& s) { ownTexture(s).minFilter = TextureMinFilter::Nearest; }},
      {"no texture", [](Scene& s) { s.materials[0].baseColorTexture.reset(); }},
      {"uv set", [](Scene& s) { s.materials[0].baseColorTexture->texCoord = 1; }},
      {"texture offset", [](Scene& s) { s.materials[0].baseColorTexture->transform.offset.x = 0.5; }},
      {"texture rotation", [](Scene& s) { s.materials[0].baseColorTexture->transform.rotation = 0.5; }},
      {"texture scale", [](Scene& s) { s.materials[0].baseColorTexture->transform.scale.y = 2.0; }},
      {"alpha cutoff", [](Scene& s) { s.materials[0].alphaCutoff = 0.25; }},
      {"alpha", [](Scene& s) { s.materials[0].alpha = 0.5; }},
      {"a uv", [](Scene& s) { (*s.triangles[0].uvs)[2].y = 0.5; }},
      {"second uv set", [](Scene& s) { (*s.triangles[0].uvs)[1].z = 0.5; }},
      {"no uvs", [](Scene& s) { s.triangles[0].uvs.reset(); }},
      {"a vertex colour", [](Scene& s) { (*s.triangles[0].colors)[0].g = 0.5; }},
      {"no vertex colours", [](Scene& s) { s.triangles[0].colors.reset(); }},
  };
  for (const auto& [what, change] : changes) {
    Scene s = texturedTriangle();
    change(s);
    EXPECT_NE(sceneFingerprint(s, 0), base) << what;
  }
}

} // namespace
} // namespace vkray
