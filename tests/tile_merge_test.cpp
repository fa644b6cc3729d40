// Tile files and merge: the bands of an image join back into it exactly; tiles that do not belong
// together (another fingerprint, size or frame), overlap or leave a gap are refused, naming the tile.
#include <filesystem>

#include <gtest/gtest.h>

#include "test_support.h"

#include "image/image_io.h"
#include "image/tile_io.h"
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
    tiles.insert(tiles.begin(), tile("t" + std::to_string(i) + ".pfm", r0, r1));
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

} // namespace
} // namespace vkray
