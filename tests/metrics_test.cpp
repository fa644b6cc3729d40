// Error metrics on synthetic images with known answers, and image file round trips.
#include <bit>
#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "image/decode.h"
#include "image/image_io.h"
#include "image/metrics.h"
#include "util/error.h"

namespace vkray {
namespace {

TEST(Metrics, IdenticalImagesHaveZeroError) {
  Image a(8, 6, glm::vec3(0.25f, 0.5f, 0.75f));
  ImageError e = compareImages(a, a);
  EXPECT_EQ(e.rmse, 0.0);
  EXPECT_EQ(e.maxAbs, 0.0);
  EXPECT_EQ(e.pixelsOff, 0u);
  EXPECT_EQ(e.fractionOff, 0.0);
  EXPECT_TRUE(std::isinf(e.psnr));
}

TEST(Metrics, KnownOffsetGivesKnownRmseAndPsnr) {
  Image a(10, 10, glm::vec3(0.5f));
  Image b(10, 10, glm::vec3(0.5f + 0.01f));
  ImageError e = compareImages(b, a);
  EXPECT_NEAR(e.rmse, 0.01, 1e-7);
  EXPECT_NEAR(e.psnr, 40.0, 1e-4); // 20 log10(1 / 0.01)
  EXPECT_NEAR(e.maxAbs, 0.01, 1e-7);
  // 0.5 -> 0.51 linear moves sRGB 0.7354 -> 0.7406: 1.3/255, so every pixel is "off".
  EXPECT_EQ(e.pixelsOff, 100u);
}

TEST(Metrics, OffsetInOneChannelOfOnePixel) {
  Image a(4, 4, glm::vec3(0.2f));
  Image b = a;
  b.at(1, 2).y = 0.6f;
  ImageError e = compareImages(b, a);
  EXPECT_NEAR(e.rmse, std::sqrt(0.16 / 48.0), 1e-7); // one squared error of 0.4^2 over 48 channels
  EXPECT_NEAR(e.maxAbs, 0.4, 1e-7);
  EXPECT_EQ(e.pixelsOff, 1u);
  EXPECT_DOUBLE_EQ(e.fractionOff, 1.0 / 16.0);
  Image map = errorMap(b, a);
  EXPECT_NEAR(map.at(1, 2).x, 0.4f, 1e-7f);
  EXPECT_EQ(map.at(0, 0).x, 0.0f);
}

TEST(Metrics, TinyDifferencesBelowOneLevelAreNotOff) {
  Image a(2, 2, glm::vec3(0.5f));
  Image b(2, 2, glm::vec3(0.5f + 1e-4f));
  EXPECT_EQ(compareImages(b, a).pixelsOff, 0u);
}

TEST(Metrics, SizeMismatchIsAnError) {
  EXPECT_THROW(compareImages(Image(2, 2), Image(3, 2)), Error);
}

TEST(ImageIo, SrgbEncodingIsTheStandardCurve) {
  EXPECT_EQ(encodeSrgb8(0.0f), 0);
  EXPECT_EQ(encodeSrgb8(1.0f), 255);
  EXPECT_EQ(encodeSrgb8(2.0f), 255);
  EXPECT_EQ(encodeSrgb8(-1.0f), 0);
  EXPECT_EQ(encodeSrgb8(0.5f), 188); // 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354
  EXPECT_EQ(encodeSrgb8(0.002f), 7); // linear segment: 12.92 * 0.002 * 255 = 6.6
  EXPECT_EQ(encodeSrgb8(std::numeric_limits<float>::quiet_NaN()), 0);
}

// encodeSrgb8 reads its bytes off a table of the formula's thresholds: it must give the formula's
// bytes for every float, which holds if the formula is monotone. Checked where it could break,
// 2048 floats on either side of every threshold, the first and last float of each of the lookup's
// buckets (2^15 bit patterns each), and across [0, 1] in steps of 61 floats (17 million values),
// plus infinities and values above 1.
TEST(ImageIo, SrgbTableGivesTheFormulasBytes) {
  const std::uint32_t one = std::bit_cast<std::uint32_t>(1.0f);
  std::uint32_t mismatches = 0;
  auto check = [&](std::uint32_t bits) {
    float x = std::bit_cast<float>(bits);
    if (encodeSrgb8(x) != encodeSrgb8Formula(x) && ++mismatches < 5) {
      ADD_FAILURE() << "x = " << x << ": table " << int(encodeSrgb8(x)) << ", formula " << int(encodeSrgb8Formula(x));
    }
  };
  for (std::uint32_t b = 0; b <= one; b += 61) check(b);
  for (std::uint32_t b = 0; b < one; b += 1u << 15) {
    check(b);
    check(b + (1u << 15) - 1);
  }
  std::uint32_t lo = 0;
  for (int k = 1; k < 256; ++k) {
    // The first float of byte k: where the formula steps from k - 1.
    std::uint32_t a = lo, z = one;
    while (z - a > 1) {
      std::uint32_t mid = a + (z - a) / 2;
      (encodeSrgb8Formula(std::bit_cast<float>(mid)) >= k ? z : a) = mid;
    }
    for (std::uint32_t b = z > 2048 ? z - 2048 : 0; b <= std::min(one, z + 2048); ++b) check(b);
    lo = z;
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_EQ(encodeSrgb8(std::numeric_limits<float>::infinity()), 255);
  EXPECT_EQ(encodeSrgb8(-std::numeric_limits<float>::infinity()), 0);
  EXPECT_EQ(encodeSrgb8(std::nextafter(1.0f, 2.0f)), 255);
}

TEST(ImageIo, PfmAndPngRoundTrip) {
  auto dir = std::filesystem::temp_directory_path() / ("vkray-io-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  Image img(5, 3);
  for (std::uint32_t y = 0; y < 3; ++y) {
    for (std::uint32_t x = 0; x < 5; ++x) img.at(x, y) = glm::vec3(x * 0.2f, y * 0.4f, 1.5f);
  }
  writeImage(dir / "a.pfm", img);
  Image back = readImage(dir / "a.pfm");
  EXPECT_EQ(back.pixels, img.pixels); // PFM is exact, rows in the right order
  writeImage(dir / "a.png", img);
  Image png = readImage(dir / "a.png");
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      float expected = std::min(img.pixels[i][c], 1.0f);
      EXPECT_NEAR(png.pixels[i][c], expected, 0.01f); // 8-bit sRGB quantisation
    }
  }
  std::filesystem::remove_all(dir);
}

// encodePng deflates the rows in pieces of about 128 KiB of filtered bytes side by side and joins
// them into one zlib stream. libpng must decode every pixel's sRGB byte exactly: one piece (small
// images), several with a short last one (300 x 1000: 145 rows a piece, 7 pieces), and rows longer
// than a piece (one row a piece), over noise, where Sub and deflate gain nothing, and a gradient.
TEST(ImageIo, PngPiecesDecodeToEveryPixelsSrgbByte) {
  std::uint32_t state = 12345;
  auto noise = [&state]() {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / 16777216.0f * 1.2f; // a fifth above 1: clamped
  };
  for (auto [w, h] : {std::pair{1u, 1u}, {5u, 3u}, {300u, 1000u}, {50000u, 3u}}) {
    Image img(w, h);
    for (std::uint32_t y = 0; y < h; ++y) {
      for (std::uint32_t x = 0; x < w; ++x) {
        img.at(x, y) = (y & 1u) ? glm::vec3(noise(), noise(), noise()) : glm::vec3(x / float(w), y / float(h), 0.5f);
      }
    }
    const std::vector<std::uint8_t> png = encodePng(img);
    EXPECT_EQ(png, encodePng(img)) << w << "x" << h; // the same bytes every time
    DecodeLimits limits;
    limits.maxSide = 50000; // a texture's limit, not an output's
    Rgba8Image back = decodePngOrJpeg(png.data(), png.size(), "pieces.png", limits);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < img.pixels.size(); ++i) {
      for (int c = 0; c < 3; ++c) wrong += back.rgba[i * 4 + c] != encodeSrgb8(img.pixels[i][c]);
      wrong += back.rgba[i * 4 + 3] != 255;
    }
    EXPECT_EQ(wrong, 0u) << w << "x" << h;
  }
  EXPECT_THROW(encodePng(Image(0, 3)), Error); // PNG has no empty image
}

TEST(ImageIo, AtomicWriteReplacesOnlyWhenComplete) {
  auto dir = std::filesystem::temp_directory_path() / ("vkray-atomic-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  writeFileAtomic(dir / "f", {1, 2, 3});
  writeFileAtomic(dir / "f", {4, 5});
  EXPECT_EQ(std::filesystem::file_size(dir / "f"), 2u);
  EXPECT_THROW(writeFileAtomic(dir / "missing-dir" / "f", {1}), InputError);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1u) << "a temporary file was left behind";
  std::filesystem::remove_all(dir);
}

} // namespace
} // namespace vkray
