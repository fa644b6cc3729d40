// Progressive rendering (host/render/adaptive.h): the error estimate's arithmetic and the pass
// schedule on the host; on the kernel, that the estimate is calibrated against a many-sample
// reference, that a noise threshold reaches its target with fewer rays than uniform sampling, is
// deterministic and keeps its cap, and that a time limit holds.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <optional>

#include <gtest/gtest.h>

#include "render/adaptive.h"
#include "scene/scene_loader.h"
#include "test_support.h"
#include "util/error.h"
#include "util/host_memory.h"
#include "util/parallel.h"

namespace vkray::test {
namespace {

// ---- Host: the estimate and the schedule ----------------------------------------------------

// Adds one pass of a pixel's samples (the same in R, G and B) as the renderer does: the sum, and
// the sum of the pass's first half.
void pass(ProgressiveImage& img, std::uint32_t x, const std::vector<double>& samples) {
  glm::vec4 sums(0.0f), half(0.0f);
  const std::size_t halfCount = firstHalf(static_cast<std::uint32_t>(samples.size()));
  for (std::size_t i = 0; i < samples.size(); ++i) {
    sums += glm::vec4(glm::vec3(static_cast<float>(samples[i])), 1.0f);
    if (i < halfCount) half += glm::vec4(glm::vec3(static_cast<float>(samples[i])), 0.0f);
  }
  img.add(x, 0, sums, half);
}

TEST(Progressive, OnePassErrorIsTheDifferenceOfItsHalvesMeansOverTwo) {
  // A = 0.25, B = 0.75 (two samples each): (A - B)^2 n1 n2 / n^2 = 0.25 * 4 / 16, error 0.25.
  ProgressiveImage img(1, 1);
  pass(img, 0, {0, 0.5, 1, 0.5});
  EXPECT_DOUBLE_EQ(img.error(0, 0), 0.25);
  double dof = -1.0;
  EXPECT_DOUBLE_EQ(blockVariance(img.at(0, 0), &dof), 0.0625);
  EXPECT_EQ(dof, 1.0);
  // Unequal halves, n1 = 1, n2 = 2 (a pass of three): |A - B| sqrt(2) / 3.
  ProgressiveImage odd(1, 1);
  pass(odd, 0, {1, 0, 0});
  EXPECT_FLOAT_EQ(odd.error(0, 0), std::sqrt(2.0) / 3.0); // stored in float
}

TEST(Progressive, FourBlocksPooledWithThePreviousDecisionsEstimate) {
  // Passes of 2, 2 and 4 samples: 0 0 | 1 1 | 0 0 1 1. The last add sees four blocks of two, means
  // 0, 1, 0, 1 around 0.5: sum m (x - 0.5)^2 = 2, over J - 1 = 3 and n = 8: 1/12, three degrees of
  // freedom. The add before saw blocks {0, 0}, {1}, {1} around 0.5: 1 over 2 and 4, 1/8, two
  // degrees of freedom, of the mean of 4 samples: 1/16 for 8. Pooled: (3/12 + 2/16) / 5 = 0.075.
  // (That add itself pooled its 1/8 with the first pass's halves, {0} and {0}: 0 with one degree
  // of freedom, (2/8 + 0) / 3.)
  ProgressiveImage img(1, 1);
  pass(img, 0, {0, 0});
  EXPECT_EQ(img.error(0, 0), 0.0);
  pass(img, 0, {1, 1});
  EXPECT_FLOAT_EQ(img.error(0, 0), std::sqrt(1.0 / 12.0));
  pass(img, 0, {0, 0, 1, 1});
  double dof = 0.0;
  EXPECT_DOUBLE_EQ(blockVariance(img.at(0, 0), &dof), 1.0 / 12.0);
  EXPECT_EQ(dof, 3.0);
  // add() keeps the estimate it made, which the next pass pools as the previous decision's.
  EXPECT_EQ(img.at(0, 0).variance, static_cast<float>(1.0 / 12.0));
  EXPECT_EQ(img.at(0, 0).varianceDof, 3.0f);
  EXPECT_FLOAT_EQ(img.error(0, 0), std::sqrt(0.075));
  // The blocks move on by a pass: before the pass before the last, 4 samples of mean 0.5.
  pass(img, 0, {0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5});
  EXPECT_EQ(img.at(0, 0).previousSamples, 4.0);
  EXPECT_EQ(img.at(0, 0).earlierSamples, 8.0);
}

TEST(Progressive, NoEstimateFromOneBlockAndNoneBelowTwoSamples) {
  ProgressiveImage one(1, 1);
  pass(one, 0, {0.5}); // the pass's first half is empty: one block
  EXPECT_TRUE(std::isinf(one.error(0, 0)));
  pass(one, 0, {0.5}); // two blocks of one, equal
  EXPECT_EQ(one.error(0, 0), 0.0);
  ProgressiveImage flat(1, 1);
  pass(flat, 0, {0.5, 0.5});
  pass(flat, 0, {0.5, 0.5});
  EXPECT_EQ(flat.error(0, 0), 0.0);
}

TEST(Progressive, ErrorIsTheLargestChannels) {
  ProgressiveImage img(1, 1);
  // Green: halves of means 0 and 1 (two samples each), 0.5; red and blue exact.
  img.add(0, 0, glm::vec4(0.0f, 2.0f, 0.0f, 4.0f), glm::vec4(0.0f));
  EXPECT_DOUBLE_EQ(img.error(0, 0), 0.5);
}

TEST(Progressive, NeighbourhoodDecidesWhoStaysOpen) {
  ProgressiveImage img(5, 1);
  // Pixels 0..4 with one pass of four each; pixel 2 noisy (halves of means 0 and 2: error 1), the
  // others exact.
  for (std::uint32_t x = 0; x < 5; ++x)
    pass(img, x, x == 2 ? std::vector<double>{0, 0, 2, 2} : std::vector<double>{1, 1, 1, 1});
  EXPECT_DOUBLE_EQ(img.error(2, 0), 1.0);
  // kOwnShare of the pixel's own square, the rest of its neighbourhood's mean square: pixel 1,
  // exact itself next to the noisy one, 0.2 (0 + 0 + 1) / 3; pixel 2, 0.8 + 0.2 (0 + 1 + 0) / 3.
  ASSERT_EQ(ProgressiveImage::kOwnShare, 0.8);
  EXPECT_DOUBLE_EQ(img.neighbourhoodError(1, 0), std::sqrt(0.2 / 3.0));
  EXPECT_DOUBLE_EQ(img.neighbourhoodError(2, 0), std::sqrt(0.8 + 0.2 / 3.0));
  EXPECT_DOUBLE_EQ(img.neighbourhoodError(0, 0), 0.0);
  std::vector<std::uint32_t> all{0, 1, 2, 3, 4};
  // At 0.95 every pixel closes; at 0.5 the noisy pixel (0.93) stays open and no longer holds its
  // settled neighbours (0.26) with it; at 0.2 they stay open too.
  EXPECT_TRUE(img.stillOpen(all, 0.95).empty());
  EXPECT_EQ(img.stillOpen(all, 0.5), (std::vector<std::uint32_t>{2}));
  EXPECT_EQ(img.stillOpen(all, 0.2), (std::vector<std::uint32_t>{1, 2, 3}));
  // Only pixels open before can stay open.
  EXPECT_EQ(img.stillOpen({2}, 0.5), (std::vector<std::uint32_t>{2}));
}

// A row of pixels whose samples all agree (no estimate of error: 0) beside a row of another colour,
// as along a checker line that runs with the pixel rows: every block of the first rows' samples
// missed whatever lies between. At the first decision, and at any before a pixel has 16 samples,
// such a pixel stays open while the contrast of its 3 x 3 neighbourhood over its samples could hide
// more than a quarter of the threshold; a flat neighbourhood closes as before. From 16 samples on
// only a first decision asks.
TEST(Progressive, EarlyDecisionsKeepPixelsBesideContrastOpen) {
  ProgressiveImage img(3, 3);
  // Rows 0 and 1 at 0.2, row 2 at 0.6 (green 0.6 - 0.2 = 0.4 the largest channel's range); equal
  // samples in passes of 2, 2 and 4, then one of 8.
  auto passes = [&](std::initializer_list<std::uint32_t> ks) {
    for (std::uint32_t y = 0; y < 3; ++y)
      for (std::uint32_t x = 0; x < 3; ++x)
        for (std::uint32_t k : ks) {
          const glm::vec3 c = y < 2 ? glm::vec3(0.2f) : glm::vec3(0.3f, 0.6f, 0.1f);
          img.add(x, y, glm::vec4(c * float(k), float(k)), glm::vec4(c * float(firstHalf(k)), 1.0f));
        }
  };
  passes({2, 2, 4});
  ASSERT_EQ(ProgressiveImage::kContrastShare, 0.25);
  ASSERT_EQ(ProgressiveImage::kContrastGuardSamples, 16.0f);
  EXPECT_EQ(img.error(1, 0), 0.0);
  EXPECT_NEAR(img.neighbourhoodContrast(1, 0), 0.0, 1e-7); // rows 0 and 1: flat
  EXPECT_NEAR(img.neighbourhoodContrast(1, 1), 0.4, 1e-6); // beside row 2
  EXPECT_NEAR(img.neighbourhoodContrast(0, 2), 0.4, 1e-6); // clipped at the corner
  const std::vector<std::uint32_t> all{0, 1, 2, 3, 4, 5, 6, 7, 8};
  const std::vector<std::uint32_t> beside{3, 4, 5, 6, 7, 8};
  // 0.4 / 8 samples = 0.05: open below a threshold of 0.2, closed above it, at the first decision
  // and at a later one alike (8 samples are fewer than 16).
  for (bool first : {true, false}) {
    EXPECT_EQ(img.stillOpen(all, 0.19, first), beside) << first;
    EXPECT_TRUE(img.stillOpen(all, 0.21, first).empty()) << first;
  }
  // 16 samples: 0.4 / 16 = 0.025 holds them below a threshold of 0.1 at a first decision (min_spp
  // 16); a later decision does not ask, and every estimate is 0, so every pixel closes.
  passes({8});
  EXPECT_EQ(img.stillOpen(all, 0.09, true), beside);
  EXPECT_TRUE(img.stillOpen(all, 0.11, true).empty());
  EXPECT_TRUE(img.stillOpen(all, 0.09, false).empty());
}

// The host's per-pixel loops run on every hardware thread (util/parallel.h): the ranges cover each
// iteration exactly once, whatever the count and the threads, and a failure in any range reaches
// the caller.
TEST(ParallelFor, CoversEveryIterationOnce) {
  for (std::size_t n : {0u, 1u, 7u, 1000u, 100003u})
    for (unsigned threads : {1u, 2u, 3u, 8u})
      for (std::size_t minPerThread : {std::size_t{1}, std::size_t{16384}}) {
        std::vector<int> seen(n, 0);
        std::vector<std::pair<std::size_t, std::size_t>> ranges(threads + 1);
        std::atomic<std::size_t> calls{0};
        parallelFor(
            n, minPerThread,
            [&](std::size_t begin, std::size_t end) {
              ranges[calls++] = {begin, end};
              for (std::size_t i = begin; i < end; ++i) ++seen[i];
            },
            threads);
        EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; })) << n << " " << threads;
        // As many ranges as threads allow, each at least minPerThread long (one range below that).
        const std::size_t expected = n == 0 ? 0 : std::clamp<std::size_t>(n / minPerThread, 1, threads);
        EXPECT_EQ(calls.load(), expected) << n << " " << threads << " " << minPerThread;
        for (std::size_t r = 0; r < calls.load() && expected > 1; ++r)
          EXPECT_GE(ranges[r].second - ranges[r].first, minPerThread);
      }
}

TEST(ParallelFor, RethrowsAfterEveryRangeEnds) {
  std::atomic<int> finished{0};
  EXPECT_THROW(parallelFor(
                   4, 1,
                   [&](std::size_t begin, std::size_t) {
                     if (begin == 2) throw Error("range 2 failed");
                     ++finished;
                   },
                   4),
               Error);
  EXPECT_EQ(finished.load(), 3);
}

// On an image large enough for the decisions to be split over threads, stillOpen keeps exactly the
// pixels the rule keeps when asked pixel by pixel, in the list's order, at a first decision and a
// later one; and two images fed the same passes, one pixel at a time and on threads, hold the same
// moments and estimates.
TEST(Progressive, DecisionsOnThreadsAreThePixelsOwn) {
  const std::uint32_t w = 256, h = 160; // 40 960 pixels: more than two threads' worth
  ASSERT_GT(std::size_t{w} * h, 2 * ProgressiveImage::kPixelsPerThread);
  ProgressiveImage img(w, h), serial(w, h);
  std::vector<std::uint32_t> all(std::size_t{w} * h);
  std::iota(all.begin(), all.end(), 0u);
  // A deterministic, uneven pattern: smooth shading, a stripe of contrast, noise that varies.
  auto sample = [](std::uint32_t x, std::uint32_t y, std::uint32_t s) {
    const std::uint32_t hash = (x * 73856093u) ^ (y * 19349663u) ^ (s * 83492791u);
    const float noise = static_cast<float>(hash % 1000u) / 1000.0f * (x % 7 == 0 ? 0.5f : 0.02f);
    return glm::vec3(0.1f + 0.001f * x + noise, y % 23 == 0 ? 0.9f : 0.3f, 0.001f * y);
  };
  auto addPass = [&](std::uint32_t first, std::uint32_t k) {
    std::vector<std::pair<glm::vec4, glm::vec4>> sums(all.size());
    for (std::uint32_t i : all) {
      glm::vec4 sum(0.0f), half(0.0f);
      for (std::uint32_t s = first; s < first + k; ++s) {
        const glm::vec3 c = sample(i % w, i / w, s);
        sum += glm::vec4(c, 1.0f);
        if (s - first < firstHalf(k)) half += glm::vec4(c, 0.0f);
      }
      sums[i] = {sum, half + glm::vec4(0.0f, 0.0f, 0.0f, float(k))};
      serial.add(i % w, i / w, sums[i].first, sums[i].second);
    }
    parallelFor(all.size(), ProgressiveImage::kPixelsPerThread, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) img.add(i % w, i / w, sums[i].first, sums[i].second);
    });
  };
  auto byPixel = [&](const std::vector<std::uint32_t>& open, double threshold, bool first) {
    std::vector<std::uint32_t> kept;
    for (std::uint32_t i : open) {
      const std::uint32_t x = i % w, y = i / w;
      const double n = img.at(x, y).samples;
      const bool guarded = first || n < ProgressiveImage::kContrastGuardSamples;
      if (!(img.neighbourhoodError(x, y) <= threshold &&
            (!guarded || img.neighbourhoodContrast(x, y) / n <= ProgressiveImage::kContrastShare * threshold)))
        kept.push_back(i);
    }
    return kept;
  };
  addPass(0, 1);
  addPass(1, 1);
  addPass(2, 2);
  for (std::uint32_t y = 0; y < h; y += 7)
    for (std::uint32_t x = 0; x < w; x += 5) {
      ASSERT_EQ(std::memcmp(&img.at(x, y), &serial.at(x, y), sizeof(PixelMoments)), 0) << x << ", " << y;
      ASSERT_EQ(img.error(x, y), serial.error(x, y));
    }
  std::vector<std::uint32_t> open = img.stillOpen(all, 0.01, true);
  EXPECT_EQ(open, byPixel(all, 0.01, true));
  EXPECT_GT(open.size(), all.size() / 10); // the rule keeps some and closes others
  EXPECT_LT(open.size(), all.size() * 9 / 10);
  addPass(4, 4);
  std::vector<std::uint32_t> later = img.stillOpen(open, 0.01, false);
  EXPECT_EQ(later, byPixel(open, 0.01, false));
  EXPECT_LT(later.size(), open.size()) << open.size();
}

// A tile's render stores only its rows (and margin): the same passes give the same estimates and
// decisions as in the whole image, rows outside are black with no samples and no estimate.
TEST(Progressive, RowsOfATileDecideAsInTheWholeImage) {
  ProgressiveImage whole(3, 8), rows(3, 8, 3, 5);
  auto addBoth = [&](std::uint32_t x, std::uint32_t y, const std::vector<double>& samples) {
    glm::vec4 sums(0.0f), half(0.0f);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      sums += glm::vec4(glm::vec3(static_cast<float>(samples[i]), 0.25f, 0.0f), 1.0f);
      if (i < firstHalf(static_cast<std::uint32_t>(samples.size())))
        half += glm::vec4(glm::vec3(static_cast<float>(samples[i]), 0.25f, 0.0f), 0.0f);
    }
    whole.add(x, y, sums, half + glm::vec4(0.0f, 0.0f, 0.0f, 3.0f));
    rows.add(x, y, sums, half + glm::vec4(0.0f, 0.0f, 0.0f, 3.0f));
  };
  for (std::uint32_t y = 3; y < 5; ++y)
    for (std::uint32_t x = 0; x < 3; ++x) addBoth(x, y, {0.1 * x, 0.2 * y, 0.3, 0.1 * (x + y)});
  for (std::uint32_t y = 3; y < 5; ++y)
    for (std::uint32_t x = 0; x < 3; ++x) {
      EXPECT_EQ(rows.error(x, y), whole.error(x, y));
      EXPECT_EQ(rows.neighbourhoodError(x, y), whole.neighbourhoodError(x, y));
    }
  const std::vector<std::uint32_t> open{9, 10, 11, 12, 13, 14};
  EXPECT_EQ(rows.stillOpen(open, 0.05), whole.stillOpen(open, 0.05));
  Image a = whole.image(), b = rows.image();
  ASSERT_EQ(b.pixels.size(), 24u);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_EQ(b.pixels[0], glm::vec3(0.0f));
  PixelStats s = rows.stats();
  ASSERT_EQ(s.samples.size(), 24u);
  EXPECT_EQ(s.samples[0], 0.0f);
  EXPECT_TRUE(std::isinf(s.error[23]));
  EXPECT_EQ(s.samples[9], 4.0f);
  EXPECT_EQ(s.rays[14], 3.0f);
}

// The moments are kept in float: 72 bytes a pixel, 76 with its estimate (the 4K image's statistics
// take 0.6 GiB; in double they took 1.2).
TEST(Progressive, HostMemoryIsCountedAndTooMuchIsRefused) {
  EXPECT_EQ(ProgressiveImage::kBytesPerPixel, 76u);
  // Traced pixels: 76 + two list entries; every pixel: the means (12) and three statistics (12).
  EXPECT_EQ(progressiveHostBytes(100, 50, 50), 5000u * (84 + 24));
  EXPECT_EQ(progressiveHostBytes(100, 50, 10), 1000u * 84 + 5000u * 24);
  const std::uint64_t gib = std::uint64_t{1} << 30;
  EXPECT_NO_THROW(checkProgressiveMemory(16384, 16384, 16384, 64 * gib)); // 27 GiB
  try {
    checkProgressiveMemory(16384, 16384, 16384, 8 * gib);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "sampling progressively (a noise threshold, a time limit, or the spp, error or rays AOVs) "
                           "at 16384x16384 keeps 27.0 GiB of per-pixel sums in host memory, and 8.0 GiB is "
                           "available: render fewer pixels, or in tiles (--tile I/N, then vkray merge)");
  }
  // A tile of 1024 rows and its margin: the moments of those rows, the means of the whole.
  EXPECT_NO_THROW(checkProgressiveMemory(16384, 16384, 1040, 8 * gib));
}

// A container's memory limit is not in MemAvailable: the room under the control group's limit counts
// too, from cgroup v2's or v1's files, in the group's own directory or (namespaced) the root's.
TEST(Progressive, RoomUnderAControlGroupsMemoryLimit) {
  namespace fs = std::filesystem;
  const fs::path root = test::freshScratchDir("cgroup");
  auto put = [&](const fs::path& file, const std::string& text) {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text << "\n";
  };
  put(root / "memory.max", "max");
  put(root / "memory.current", "100");
  put(root / "a/b/memory.max", "1000");
  put(root / "a/b/memory.current", "400");
  EXPECT_EQ(cgroupMemoryRoom(root, "0::/a/b\n"), std::optional<std::uint64_t>(600));
  EXPECT_EQ(cgroupMemoryRoom(root, "0::/\n"), std::nullopt) << "\"max\" is no limit";
  put(root / "memory/x/memory.limit_in_bytes", "5000");
  put(root / "memory/x/memory.usage_in_bytes", "1000");
  put(root / "memory/memory.limit_in_bytes", "9223372036854771712"); // v1's "no limit"
  put(root / "memory/memory.usage_in_bytes", "1000");
  EXPECT_EQ(cgroupMemoryRoom(root, "5:cpu:/x\n4:memory:/x\n0::/\n"), std::optional<std::uint64_t>(4000));
  EXPECT_EQ(cgroupMemoryRoom(root, "3:cpu,memory:/x\n"), std::optional<std::uint64_t>(4000));
  EXPECT_EQ(cgroupMemoryRoom(root, "4:memory:/not-here\n"), std::nullopt) << "the root's, unlimited";
  put(root / "memory/memory.limit_in_bytes", "800");
  EXPECT_EQ(cgroupMemoryRoom(root, "4:memory:/not-here\n"), std::optional<std::uint64_t>(0)) << "over the limit";
  EXPECT_EQ(cgroupMemoryRoom(root, ""), std::nullopt);
  EXPECT_EQ(formatBytes(3ull << 29), "1.5 GiB");
  EXPECT_EQ(formatBytes(312ull << 20), "312 MiB");
  fs::remove_all(root);
}

TEST(Progressive, ThresholdScheduleDoublesUpToTheCap) {
  RenderSettings s;
  s.noiseThreshold = 0.01;
  s.minSpp = 16;
  s.maxSpp = 100;
  std::vector<std::uint32_t> passes;
  std::uint32_t n = 0;
  while (std::uint32_t k = nextPassSamples(s, n, 10, 0.0, 0.0)) passes.push_back(k), n += k;
  EXPECT_EQ(passes, (std::vector<std::uint32_t>{4, 4, 8, 16, 32, 36}));
  EXPECT_EQ(nextPassSamples(s, 16, 0, 0.0, 0.0), 0u); // nothing open
}

TEST(Progressive, PassesBeforeTheFirstDecisionRunAsOne) {
  RenderSettings s;
  s.noiseThreshold = 0.01;
  s.minSpp = 16;
  s.maxSpp = 100;
  using Passes = std::vector<std::uint32_t>;
  EXPECT_EQ(nextPasses(s, 0, 10, 0.0, 0.0, true), (Passes{4, 4, 8})); // then the first decision
  EXPECT_EQ(nextPasses(s, 16, 10, 0.0, 0.0, true), (Passes{16}));     // one pass per decision after it
  EXPECT_EQ(nextPasses(s, 64, 10, 0.0, 0.0, true), (Passes{36}));     // the cap
  EXPECT_EQ(nextPasses(s, 0, 10, 0.0, 0.0, false), (Passes{4}));      // apart, as the schedule lists them
  EXPECT_TRUE(nextPasses(s, 100, 10, 0.0, 0.0, true).empty());
  s.minSpp = 6; // 1, 1, 2 and 4 before the first decision: the first three run as one
  EXPECT_EQ(nextPasses(s, 0, 10, 0.0, 0.0, true), (Passes{1, 1, 2}));
  EXPECT_EQ(nextPasses(s, 4, 10, 0.0, 0.0, true), (Passes{4}));
  s.minSpp = 1; // a decision after every pass
  EXPECT_EQ(nextPasses(s, 0, 10, 0.0, 0.0, true), (Passes{1}));
  s.minSpp = 16;
  s.maxSpp = 8; // the cap comes first (refused at load; the schedule still holds)
  EXPECT_EQ(nextPasses(s, 0, 10, 0.0, 0.0, true), (Passes{4, 4}));
  s.maxSpp = 100;
  s.timeLimit = 1.0; // a time limit may stop between them: apart
  EXPECT_EQ(nextPasses(s, 0, 10, 0.0, 0.0, true), (Passes{4}));
}

TEST(Progressive, DecisionsFollowTheSchedule) {
  RenderSettings s;
  EXPECT_EQ(decisionCount(s), 0u); // no threshold, no decisions
  s.noiseThreshold = 0.01;
  s.minSpp = 16;
  s.maxSpp = 1024;
  EXPECT_EQ(decisionCount(s), 7u); // after 16, 32, 64, 128, 256, 512, 1024 samples
  s.maxSpp = 16;
  EXPECT_EQ(decisionCount(s), 1u);
}

TEST(Progressive, TimeLimitShortensThePassToWhatIsLeft) {
  RenderSettings s;
  s.timeLimit = 1.0;                                    // 1000 ms
  EXPECT_EQ(nextPassSamples(s, 0, 1000, 0.0, 0.0), 1u); // the first pass measures
  // 0.01 ms per pixel-sample, 1000 pixels: 10 ms per sample of each; 100 ms spent, 900 ms left.
  EXPECT_EQ(nextPassSamples(s, 1, 1000, 0.01, 100.0), 1u);   // doubling asks for 1
  EXPECT_EQ(nextPassSamples(s, 64, 1000, 0.01, 100.0), 64u); // 90 fit
  EXPECT_EQ(nextPassSamples(s, 128, 1000, 0.01, 100.0), 90u);
  EXPECT_EQ(nextPassSamples(s, 128, 1000, 0.01, 995.0), 0u); // not one sample fits
}

TEST(Progressive, PixelStatisticsAloneTraceSppInTwoHalves) {
  RenderSettings s;
  s.spp = 9;
  EXPECT_EQ(nextPassSamples(s, 0, 10, 0.0, 0.0), 4u);
  EXPECT_EQ(nextPassSamples(s, 4, 10, 0.0, 0.0), 5u);
  EXPECT_EQ(nextPassSamples(s, 9, 10, 0.0, 0.0), 0u);
}

TEST(Progressive, BadCombinationsAreRefused) {
  RenderSettings s;
  s.noiseThreshold = 0.01;
  s.minSpp = 64;
  s.maxSpp = 32;
  EXPECT_THROW(checkProgressiveSettings(s), InputError);
  s.minSpp = 16;
  EXPECT_NO_THROW(checkProgressiveSettings(s));
  s.antialiasing = Antialiasing::Adaptive;
  s.spp = 4;
  EXPECT_THROW(checkProgressiveSettings(s), InputError);
}

// ---- The kernel ----------------------------------------------------------------------------

// Noise of three kinds: a sphere's silhouette against the sky (edges), a tight Phong highlight
// (glossy), and a glass sphere in front of a checkered floor (refraction). Small, so a many-sample
// reference stays cheap on lavapipe.
Scene noisyScene() {
  Scene s = sceneFromJson(R"({
    "camera": { "position": [0, 1.2, 5], "look_at": [0, 0.6, 0], "fov_y": 40 },
    "image": { "width": 96, "height": 72 }, "background": [0.3, 0.4, 0.6], "ambient": [0.2, 0.2, 0.2],
    "render": { "max_depth": 4 },
    "lights": [ { "position": [3, 5, 4], "color": [1, 1, 1] } ],
    "materials": {
      "floor": { "color": [0.8, 0.8, 0.8], "diffuse": 0.8, "checker": { "color2": [0.1, 0.1, 0.1], "scale": 0.5 } },
      "shiny": { "color": [0.8, 0.2, 0.2], "diffuse": 0.6, "specular": 0.9, "shininess": 400 },
      "glass": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "transmission": 0.9, "ior": 1.5 } },
    "objects": [
      { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
      { "type": "sphere", "center": [-1.1, 0.7, 0], "radius": 0.7, "material": "shiny" },
      { "type": "sphere", "center": [0.9, 0.7, 0.5], "radius": 0.7, "material": "glass" } ] })");
  return s;
}

// noisyScene under a noise threshold, with the min_spp and max_spp a test is written for.
Scene thresholdScene(double threshold, int minSpp, int maxSpp) {
  Scene s = noisyScene();
  s.render.noiseThreshold = threshold;
  s.render.minSpp = minSpp;
  s.render.maxSpp = maxSpp;
  return s;
}

Image uniform(Scene s, int spp) {
  s.render.spp = spp;
  return render(s).image;
}

double maxChannelDiff(const glm::vec3& a, const glm::vec3& b) {
  glm::vec3 d = glm::abs(a - b);
  return std::max({d.x, d.y, d.z});
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

// Two renders of the same samples: the same image bit for bit, the same samples, rays and error
// estimates per pixel, and the same rays in all.
void expectTheSameRender(const RenderResult& a, const RenderResult& b) {
  ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
  EXPECT_EQ(0, std::memcmp(a.image.pixels.data(), b.image.pixels.data(), a.image.pixels.size() * sizeof(glm::vec3)));
  EXPECT_EQ(a.pixels.samples, b.pixels.samples);
  EXPECT_EQ(a.pixels.rays, b.pixels.rays);
  EXPECT_EQ(a.pixels.error, b.pixels.error);
  EXPECT_EQ(a.stats.total(), b.stats.total());
}

// Squared error estimates against squared deviations, summed over the pixels that have noise at all.
struct Calibration {
  double est2 = 0.0, dev2 = 0.0;
  int noisy = 0;
  void add(double estimateSquared, double deviationSquared) {
    if (estimateSquared < 1e-12 && deviationSquared < 1e-12) return; // no noise: nothing to calibrate
    est2 += estimateSquared;
    dev2 += deviationSquared;
    ++noisy;
  }
  double ratio() const { return std::sqrt(est2 / dev2); } // RMS estimate over RMS deviation
};

// The 1024-sample reference, once per process.
const Image& reference() {
  static const Image ref = uniform(noisyScene(), 1024);
  return ref;
}

TEST(RenderProgressive, ErrorEstimateIsCalibratedAgainstAReference) {
  // Per-pixel statistics at 64 spp (two halves of 32): over the pixels that have noise at all,
  // the RMS of the estimated standard error against the RMS of the actual deviation from the
  // 1024-sample reference (whose own error is a quarter of the 64-sample one's and shares its first
  // 64 samples, so the deviation is if anything understated).
  Scene s = noisyScene();
  s.render.spp = 64;
  RenderOptions o;
  o.pixelStats = true;
  RenderResult r = render(s, o);
  ASSERT_EQ(r.pixels.error.size(), r.image.pixels.size());
  const Image& ref = reference();
  Calibration c;
  for (std::size_t i = 0; i < ref.pixels.size(); ++i) {
    const double dev = maxChannelDiff(r.image.pixels[i], ref.pixels[i]);
    c.add(r.pixels.error[i] * r.pixels.error[i], dev * dev);
  }
  ASSERT_GT(c.noisy, 100);
  // A split-half estimate has one degree of freedom per channel and pixel; over hundreds of pixels
  // the RMS agrees within a factor 2 either way (measured: see the log line).
  std::printf("calibration: %d noisy pixels, RMS estimate / RMS deviation = %.3f\n", c.noisy, c.ratio());
  EXPECT_GT(c.ratio(), 0.5);
  EXPECT_LT(c.ratio(), 2.0);
  for (float spp : r.pixels.samples) EXPECT_EQ(spp, 64.0f);
}

TEST(RenderProgressive, ErrorEstimateIsCalibratedAgainstAnIndependentRender) {
  // The same at 64 spp, against no reference: two renders with other seeds (render.seed) are
  // independent, so the difference of their means has twice one mean's variance, and |a - b| / sqrt 2
  // measures one render's error without sharing its samples (the reference above shares its first
  // 64 with the render it checks).
  Scene s = noisyScene();
  s.render.spp = 64;
  RenderOptions o;
  o.pixelStats = true;
  s.render.seed = 1;
  RenderResult a = render(s, o);
  s.render.seed = 2;
  RenderResult b = render(s, o);
  ASSERT_EQ(a.pixels.error.size(), a.image.pixels.size());
  ASSERT_EQ(b.pixels.error.size(), b.image.pixels.size());
  Calibration c;
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
    const double dev = maxChannelDiff(a.image.pixels[i], b.image.pixels[i]);
    c.add(0.5 * (a.pixels.error[i] * a.pixels.error[i] + b.pixels.error[i] * b.pixels.error[i]), 0.5 * dev * dev);
  }
  ASSERT_GT(c.noisy, 100);
  std::printf("calibration against another seed: %d noisy pixels, RMS estimate / RMS deviation = %.3f\n", c.noisy,
              c.ratio());
  // The same factor 2 either way as against the reference (see the log line for both).
  EXPECT_GT(c.ratio(), 0.5);
  EXPECT_LT(c.ratio(), 2.0);
}

TEST(RenderProgressive, PixelStatisticsDoNotChangeTheImage) {
  // The progressive path at a fixed spp traces the same samples as a uniform render: the same
  // image up to the order of float additions (the host adds two halves in double).
  Scene s = noisyScene();
  s.render.spp = 8;
  Image plain = render(s).image;
  RenderOptions o;
  o.pixelStats = true;
  RenderResult r = render(s, o);
  double worst = 0.0;
  for (std::size_t i = 0; i < plain.pixels.size(); ++i)
    worst = std::max(worst, maxChannelDiff(plain.pixels[i], r.image.pixels[i]));
  EXPECT_LT(worst, 1e-5);
  double rays = std::accumulate(r.pixels.rays.begin(), r.pixels.rays.end(), 0.0);
  EXPECT_EQ(rays, static_cast<double>(r.stats.total())); // the per-pixel counts add up
}

TEST(RenderProgressive, ListPassesStartFromTheEntryPointsOfTheWholeImage) {
  // A scene with a BVH: the list pass's lanes read the entry points of their own pixels' tiles,
  // found once for the whole image, and find the same hits as the banded sample pass.
  Scene s = loadScene(scenePath("meshes.json"));
  s.render.width = 64;
  s.render.height = 48;
  s.render.spp = 4;
  RenderResult plain = render(s);
  ASSERT_TRUE(plain.features.useBvh);
  RenderOptions o;
  o.pixelStats = true;
  RenderResult r = render(s, o);
  double worst = 0.0;
  for (std::size_t i = 0; i < plain.image.pixels.size(); ++i)
    worst = std::max(worst, maxChannelDiff(plain.image.pixels[i], r.image.pixels[i]));
  EXPECT_LT(worst, 1e-5);
  EXPECT_EQ(r.stats.total(), plain.stats.total()); // the same rays, from the same hits
}

TEST(RenderProgressive, LanesSharingAPixelChangeNothing) {
  // Passes of 16 samples or more are traced by lanes that share a pixel, side by side (trace.comp,
  // listPass), and where the driver lets loops run to their end one dispatch takes a whole pass.
  // The simplest schedule, one sample of each listed pixel per dispatch and one invocation per
  // pixel, adds the same samples in the same order: the same image bit for bit, and the same
  // samples, rays and error estimates per pixel.
  Scene s = thresholdScene(0.003, 16, 128);
  RenderOptions o;
  o.pixelStats = true;
  RenderResult shared = render(s, o);
  o.oneSamplePerDispatch = true;
  RenderResult simple = render(s, o);
  ASSERT_GE(shared.progressive.sppMax, 64.0) << "passes of 32 samples and more, traced by 4 lanes or more";
  expectTheSameRender(shared, simple);
  // Each pixel's rays, summed over its lanes, add up to the render's.
  EXPECT_EQ(std::accumulate(shared.pixels.rays.begin(), shared.pixels.rays.end(), 0.0),
            static_cast<double>(shared.stats.total()));
}

TEST(RenderProgressive, PassesRunAsOneChangeNothing) {
  // The passes before the first decision (4, 4 and 8 samples at min_spp 16; 1, 1 and 2 at min_spp
  // 4, whose one-sample passes have empty first halves that one dispatch neither writes nor reads)
  // run as one list pass that reports each on its own, in one dispatch or (as a driver that cuts
  // loops short needs) one sample per dispatch, with lanes sharing a pixel on this glass scene (16
  // samples: two lanes): the same sums in the same order as three passes, so the same image bit for
  // bit and the same samples, rays and error estimates per pixel.
  for (int minSpp : {16, 4}) {
    SCOPED_TRACE("min_spp " + std::to_string(minSpp));
    Scene s = thresholdScene(0.003, minSpp, 64);
    RenderOptions o;
    o.pixelStats = true;
    RenderResult together = render(s, o);
    o.oneSamplePerDispatch = true;
    RenderResult perSample = render(s, o);
    o.firstPassesTogether = false;
    RenderResult apart = render(s, o);
    for (const RenderResult* r : {&perSample, &apart}) {
      expectTheSameRender(together, *r);
      EXPECT_EQ(together.progressive.passes, r->progressive.passes); // the schedule's passes
    }
    ASSERT_GT(together.progressive.converged, 0.2) << "the first decision closed pixels";
    ASSERT_LT(together.progressive.converged, 1.0) << "and left some open";
  }
}

TEST(RenderProgressive, NoiseThresholdReachesItsTargetWithFewerRaysThanUniform) {
  const double threshold = 0.004;
  Scene s = thresholdScene(threshold, 8, 512);
  RenderResult a = render(s);
  const Image& ref = reference();
  std::vector<double> errors;
  for (std::size_t i = 0; i < ref.pixels.size(); ++i)
    errors.push_back(maxChannelDiff(a.image.pixels[i], ref.pixels[i]));
  const double p95 = percentile(errors, 0.95);
  // The threshold bounds the neighbourhood's mean estimated standard error; the 95th percentile of
  // the actual error (a max over three channels, about two standard errors) stays within 3 E.
  EXPECT_LT(p95, 3.0 * threshold);
  for (float n : a.pixels.samples) {
    EXPECT_GE(n, 8.0f);   // min_spp
    EXPECT_LE(n, 512.0f); // the cap
  }
  EXPECT_GT(a.progressive.passes, 2);
  EXPECT_GT(a.progressive.converged, 0.5);

  // Uniform sampling needs more rays for the same 95th percentile: between the two powers of two
  // whose 95th percentiles bracket it, interpolated in log-log (error ~ spp^-a).
  double uniformRays = 0.0;
  double previousP95 = 0.0, previousRays = 0.0;
  for (int spp = 8; spp <= 512; spp *= 2) {
    Scene u = noisyScene();
    u.render.spp = spp;
    RenderResult ur = render(u);
    std::vector<double> ue;
    for (std::size_t i = 0; i < ref.pixels.size(); ++i) ue.push_back(maxChannelDiff(ur.image.pixels[i], ref.pixels[i]));
    const double up95 = percentile(ue, 0.95), rays = static_cast<double>(ur.stats.total());
    if (up95 <= p95) {
      const double t = previousP95 > 0.0 ? std::log(previousP95 / p95) / std::log(previousP95 / up95) : 1.0;
      uniformRays = previousP95 > 0.0 ? std::exp(std::log(previousRays) + t * std::log(rays / previousRays)) : rays;
      break;
    }
    previousP95 = up95;
    previousRays = rays;
  }
  std::printf("threshold %g: p95 error %.4f, %llu rays; uniform at the same p95: %.0f rays (ratio %.2f)\n", threshold,
              p95, static_cast<unsigned long long>(a.stats.total()), uniformRays,
              static_cast<double>(a.stats.total()) / uniformRays);
  ASSERT_GT(uniformRays, 0.0);
  EXPECT_LT(static_cast<double>(a.stats.total()), uniformRays);

  // Deterministic: the same image and sample counts again.
  RenderResult again = render(s);
  EXPECT_EQ(again.image.pixels, a.image.pixels);
  EXPECT_EQ(again.pixels.samples, a.pixels.samples);
}

// The kernel's samples, through the renderer's passes: no pixel stops at a decision before 16
// samples where its 3 x 3 neighbourhood's contrast over its samples is above kContrastShare of the
// threshold, however noiseless its own samples look; flat pixels do stop there. The neighbourhood's
// means are those the decision saw, from uniform renders of the same first samples: 4 where a
// neighbour had stopped at min_spp 4, 8 where it had not. A loose threshold, so that the estimate
// alone would close most edge pixels at once. At min_spp 8 the first decision asks, at min_spp 4
// both the first and the second.
TEST(RenderProgressive, EarlyDecisionsWaitBesideContrast) {
  const double threshold = 0.03;
  const Image at4 = uniform(noisyScene(), 4), at8 = uniform(noisyScene(), 8); // every pixel's first samples
  for (const int minSpp : {8, 4}) {
    SCOPED_TRACE("min_spp " + std::to_string(minSpp));
    Scene s = thresholdScene(threshold, minSpp, 64);
    RenderResult a = render(s);
    const std::uint32_t w = s.render.width, h = s.render.height;
    auto samples = [&](std::uint32_t x, std::uint32_t y) { return a.pixels.samples[y * w + x]; };
    int flatStopped = 0, heldBesideContrast = 0, secondDecisions = 0;
    for (const float n : {4.0f, 8.0f}) {
      if (n < float(minSpp)) continue;
      for (std::uint32_t y = 0; y < h; ++y) {
        for (std::uint32_t x = 0; x < w; ++x) {
          if (samples(x, y) < n) continue; // closed at an earlier decision
          glm::vec3 lo(1e30f), hi(-1e30f);
          for (std::uint32_t v = y > 0 ? y - 1 : 0; v <= std::min(h - 1, y + 1); ++v)
            for (std::uint32_t u = x > 0 ? x - 1 : 0; u <= std::min(w - 1, x + 1); ++u) {
              // The decision at 4 saw 4 samples everywhere; the one at 8, 4 where a neighbour stopped.
              const Image& seen = n == 4.0f || samples(u, v) < n ? at4 : at8;
              const glm::vec3 mean = seen.pixels[v * w + u];
              lo = glm::min(lo, mean);
              hi = glm::max(hi, mean);
            }
          const double bound = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) / n;
          // The kernel sums a pass at a time where the uniform render sums every sample: a margin
          // of 1 % for the float rounding between them.
          if (bound > 0.2525 * threshold) {
            EXPECT_GT(samples(x, y), n) << x << ", " << y << ": contrast / " << n << " = " << bound;
            heldBesideContrast += samples(x, y) > n;
          }
          if (bound < 0.05 * threshold && samples(x, y) == n) ++flatStopped;
          secondDecisions += n > float(minSpp) && samples(x, y) == n;
        }
      }
    }
    EXPECT_GT(heldBesideContrast, 100);
    EXPECT_GT(flatStopped, 1000);
    if (minSpp == 4) {
      EXPECT_GT(secondDecisions, 50) << "pixels that stopped at the second decision";
    }
  }
}

TEST(RenderProgressive, TilesUnderAThresholdMergeIntoTheWholeRender) {
  // Each tile traces a margin of rows for its neighbours' decisions, so its rows are the whole
  // render's bit for bit, sample counts included.
  Scene s = thresholdScene(0.01, 4, 64);
  RenderResult whole = render(s);
  const std::uint32_t w = s.render.width, h = s.render.height;
  for (auto [begin, end] : {std::pair<std::uint32_t, std::uint32_t>{0, 25}, {25, 50}, {50, h}}) {
    RenderOptions o;
    o.rowBegin = begin;
    o.rowEnd = end;
    RenderResult tile = render(s, o);
    for (std::uint32_t y = 0; y < h; ++y) {
      for (std::uint32_t x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (y >= begin && y < end) {
          ASSERT_EQ(tile.image.pixels[i], whole.image.pixels[i]) << x << ", " << y;
          ASSERT_EQ(tile.pixels.samples[i], whole.pixels.samples[i]) << x << ", " << y;
        } else {
          ASSERT_EQ(tile.image.pixels[i], glm::vec3(0.0f)) << x << ", " << y;
          ASSERT_EQ(tile.pixels.samples[i], 0.0f);
        }
      }
    }
  }
}

TEST(RenderProgressive, TimeLimitHoldsWithinOnePass) {
  Scene s = noisyScene();
  s.render.timeLimit = 0.25; // seconds of GPU time
  s.render.maxSpp = 4096;
  RenderResult r = render(s);
  EXPECT_GE(r.progressive.passes, 2);
  // The passes stop before the budget would be exceeded at the measured speed: the whole trace
  // stays within the budget plus the last pass.
  EXPECT_LE(r.timings.traceMs, 250.0 + r.progressive.lastPassMs);
  EXPECT_GT(r.progressive.sppMean, 1.0);
}

} // namespace
} // namespace vkray::test
