// Forward ray tracing (render.method forward, shaders/forward.comp) against backward tracing of the
// same scene. Where the two models agree (direct diffuse lighting, mirrors; no ambient term, a black
// background), photons collected through the lens converge to the backward image; the tolerances
// below are stated from the number of photons that strike each pixel. Also: the fraction that
// strikes follows the lens area, a pinhole receives nothing (refused), the image is deterministic,
// a time limit holds, and the command line says what it traced.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "image/image_io.h"
#include "scene/scene_loader.h"
#include "test_support.h"
#include "util/error.h"

namespace vkray::test {
namespace {

// A diffuse floor seen from straight above through a lens of radius `aperture`, focused on it, lit by
// one point light off the axis: backward, each pixel is I kd base cos(theta) at its points (no
// highlight, no ambient, nothing else in view).
Scene litFloor(double aperture, int size) {
  Scene s = sceneFromJson(R"({
    "camera": { "position": [0, 3, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov_y": 60,
                "aperture": )" +
                          std::to_string(aperture) +
                          R"( },
    "image": { "width": )" +
                          std::to_string(size) + R"(, "height": )" + std::to_string(size) + R"( },
    "background": [0, 0, 0], "ambient": [0, 0, 0],
    "lights": [ { "type": "point", "position": [0.6, 2, 0.4], "color": [1, 0.9, 0.8] } ],
    "materials": { "floor": { "color": [0.8, 0.6, 0.4], "ambient": 0, "diffuse": 0.7 } },
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" } ] })");
  return s;
}

// The same light on a diffuse ceiling, seen in a mirror floor from between them: every photon that
// reaches the lens has bounced off the mirror once. Focused on the ceiling's mirror image, which the
// camera at height 2 sees 2 + 4 = 6 away.
Scene ceilingInAMirror(double aperture, int size) {
  Scene s = sceneFromJson(R"({
    "camera": { "position": [0, 2, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov_y": 60,
                "aperture": )" +
                          std::to_string(aperture) +
                          R"(, "focus_distance": 6 },
    "image": { "width": )" +
                          std::to_string(size) + R"(, "height": )" + std::to_string(size) + R"( },
    "background": [0, 0, 0], "ambient": [0, 0, 0],
    "render": { "max_depth": 2 },
    "lights": [ { "type": "point", "position": [0.5, 1, 0.3], "color": [1, 1, 1] } ],
    "materials": {
      "ceiling": { "color": [0.9, 0.8, 0.7], "ambient": 0, "diffuse": 0.8 },
      "mirror": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "reflection": 0.9 } },
    "objects": [
      { "type": "plane", "normal": [0, -1, 0], "point": [0, 4, 0], "material": "ceiling" },
      { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "mirror" } ] })");
  return s;
}

RenderResult renderForward(Scene s, std::uint64_t photons) {
  s.render.method = Method::Forward;
  s.render.photons = photons;
  return render(s);
}

struct Agreement {
  double meanRatio = 0.0;     // forward's image mean over backward's
  double worstRelative = 0.0; // largest |f - b| / b over pixels
  double rmsRelative = 0.0;
  double expectedRelative = 0.0; // one photon-count standard deviation per pixel, 1 / sqrt(struck / pixels)
};

Agreement compare(const Image& forward, const Image& backward, const ForwardSummary& f) {
  Agreement a;
  double sf = 0.0, sb = 0.0, sq = 0.0;
  for (std::size_t i = 0; i < forward.pixels.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      double fv = forward.pixels[i][c];
      double bv = backward.pixels[i][c];
      sf += fv;
      sb += bv;
      double rel = std::abs(fv - bv) / bv;
      a.worstRelative = std::max(a.worstRelative, rel);
      sq += rel * rel;
    }
  }
  a.meanRatio = sf / sb;
  a.rmsRelative = std::sqrt(sq / (3.0 * forward.pixels.size()));
  a.expectedRelative = 1.0 / std::sqrt(static_cast<double>(f.struck) / forward.pixels.size());
  return a;
}

// Renders `s` backward at 64 spp and forward at 2^24 photons per light and holds the forward image
// to the backward one. In the scenes below every contribution carries nearly the same weight (pi kd
// base over the lens and pixel areas, times 1 / cos^4 of a ray within 30 degrees of the axis), so a
// pixel's relative deviation is about one over the square root of the photons it caught: the RMS
// over pixels is within 1.5x of that, no pixel is beyond 5 of it, and the image mean (all photons
// together) is within 5 of its own, smaller deviation, plus 0.5 % for backward's 64 samples.
RenderResult expectForwardConvergesToBackward(Scene s) {
  s.render.spp = 64;
  Image backward = render(s).image;
  RenderResult fwd = renderForward(s, 1u << 24);
  EXPECT_GT(fwd.forward.struck, 0u);
  if (fwd.forward.struck == 0) return fwd;
  Agreement a = compare(fwd.image, backward, fwd.forward);
  ::testing::Test::RecordProperty("struck", std::to_string(fwd.forward.struck));
  ::testing::Test::RecordProperty("rms_relative", std::to_string(a.rmsRelative));
  EXPECT_LT(a.rmsRelative, 1.5 * a.expectedRelative) << "expected about " << a.expectedRelative;
  EXPECT_LT(a.worstRelative, 5.0 * a.expectedRelative);
  const double meanSigma = 1.0 / std::sqrt(static_cast<double>(fwd.forward.struck));
  EXPECT_NEAR(a.meanRatio, 1.0, 5.0 * meanSigma + 0.005);
  EXPECT_EQ(fwd.forward.nonFinite, 0u);
  return fwd;
}

TEST(RenderForward, ALitDiffuseFloorConvergesToTheBackwardImage) {
  expectForwardConvergesToBackward(litFloor(1.0, 16));
  expectNoValidationMessages();
}

TEST(RenderForward, AMirrorShowsTheLitCeilingAsBackwardTracingDoes) {
  // The ceiling is out of the lens's focus by nothing (focus_distance 6 is its mirror image's
  // distance), so pixels compare one to one.
  Scene s = ceilingInAMirror(1.0, 16);
  expectForwardConvergesToBackward(s);
  // Without the mirror's bounce (max_depth 0) no photon reaches the lens from the ceiling.
  s.render.maxDepth = 0;
  EXPECT_EQ(renderForward(s, 1u << 20).forward.struck, 0u);
  expectNoValidationMessages();
}

TEST(RenderForward, ThroughGlassAndAHighlightTheImageMeansAgree) {
  // A glossy floor (Phong lobe) seen through an absorbing glass ball that also shades it: photons
  // reach the lens through refraction chains, pass the ball on their way from the light with its
  // transmission and Beer-Lambert absorption, and scatter into the highlight lobe.
  Scene s = sceneFromJson(R"({
    "camera": { "position": [0, 3, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov_y": 50, "aperture": 1.0 },
    "image": { "width": 16, "height": 16 }, "background": [0, 0, 0], "ambient": [0, 0, 0],
    "render": { "max_depth": 6, "bailout": 0 },
    "lights": [ { "type": "point", "position": [0.6, 2, 0.4], "color": [1, 0.9, 0.8] } ],
    "materials": {
      "floor": { "color": [0.8, 0.6, 0.4], "ambient": 0, "diffuse": 0.7, "specular": 0.3, "shininess": 20 },
      "glass": { "color": [1, 1, 1], "ambient": 0, "diffuse": 0, "transmission": 0.9, "ior": 1.5,
                 "absorption": [0.2, 0.1, 0.0] } },
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
                 { "type": "sphere", "center": [0, 1.0, 0], "radius": 0.6, "material": "glass" } ] })");
  s.render.spp = 256;
  Image backward = render(s).image;
  RenderResult fwd = renderForward(s, 1u << 24);
  ASSERT_GT(fwd.forward.struck, 100000u);
  auto mean = [](const Image& img, std::uint32_t lo, std::uint32_t hi) {
    double sum = 0.0;
    for (std::uint32_t y = lo; y < hi; ++y)
      for (std::uint32_t x = lo; x < hi; ++x) sum += img.at(x, y).r + img.at(x, y).g + img.at(x, y).b;
    return sum;
  };
  const double whole = mean(fwd.image, 0, 16) / mean(backward, 0, 16);
  const double ball = mean(fwd.image, 5, 11) / mean(backward, 5, 11); // the pixels seen through the ball
  RecordProperty("mean_ratio", std::to_string(whole));
  RecordProperty("ball_ratio", std::to_string(ball));
  // Weights vary here (Fresnel choices, the lobe), so a mean's relative deviation is taken as twice
  // 1/sqrt(photons struck): 0.55 % for the image (1.3e5 photons), 1.5 % for the 36 pixels of the ball.
  // Tolerances of about 4 of those. (At 4e8 photons both ratios are within 0.07 % of 1.)
  EXPECT_NEAR(whole, 1.0, 0.025);
  EXPECT_NEAR(ball, 1.0, 0.06);
  EXPECT_EQ(fwd.forward.nonFinite, 0u);
  expectNoValidationMessages();
}

TEST(RenderForward, TheStruckFractionFollowsTheLensArea) {
  // Halving the lens radius quarters its area and so the photons it catches (the scattered photons'
  // directions are spread far wider than the lens at the floor's distance).
  const std::uint64_t photons = 1u << 22;
  RenderResult wide = renderForward(litFloor(0.4, 16), photons);
  RenderResult narrow = renderForward(litFloor(0.2, 16), photons);
  ASSERT_GT(narrow.forward.struck, 1000u);
  double ratio = static_cast<double>(wide.forward.struck) / static_cast<double>(narrow.forward.struck);
  RecordProperty("struck_ratio", std::to_string(ratio));
  // Poisson counts of >= 1000: the ratio's deviation is under 4 %; the lens's own extent changes the
  // solid angle it subtends by (a / 3)^2, under 2 %.
  EXPECT_NEAR(ratio, 4.0, 0.25);
  EXPECT_EQ(wide.forward.emitted, photons);
  expectNoValidationMessages();
}

TEST(RenderForward, TheImageIsTheSameEveryRun) {
  Scene s = litFloor(0.5, 16);
  RenderResult a = renderForward(s, 1u << 18);
  RenderResult b = renderForward(s, 1u << 18);
  ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
  EXPECT_EQ(a.forward.struck, b.forward.struck);
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i) ASSERT_EQ(a.image.pixels[i], b.image.pixels[i]) << i;
  // Split into other batches (an odd size, neither the first batch's nor a power of two), the sums
  // are the same integers.
  RenderOptions small;
  small.maxBatchPhotons = 40000;
  s.render.method = Method::Forward;
  s.render.photons = 1u << 18;
  RenderResult c = render(s, small);
  EXPECT_GT(c.forward.batches, a.forward.batches);
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i) ASSERT_EQ(a.image.pixels[i], c.image.pixels[i]) << i;
  expectNoValidationMessages();
}

TEST(RenderForward, AnotherSeedIsAnotherPhotonStreamOfTheSameImage) {
  // render.seed moves the lights' photon streams: another image, the same one every run, and one
  // that converges to the same picture (the image's mean agrees within the photon noise).
  Scene s = litFloor(0.5, 16);
  RenderResult a = renderForward(s, 1u << 20);
  s.render.seed = 3;
  RenderResult b = renderForward(s, 1u << 20);
  RenderResult c = renderForward(s, 1u << 20);
  ASSERT_GT(a.forward.struck, 1000u);
  ASSERT_GT(b.forward.struck, 1000u);
  double meanA = 0.0, meanB = 0.0;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
    ASSERT_EQ(b.image.pixels[i], c.image.pixels[i]) << i;
    differ += a.image.pixels[i] != b.image.pixels[i];
    meanA += a.image.pixels[i].y;
    meanB += b.image.pixels[i].y;
  }
  EXPECT_GT(differ, a.image.pixels.size() / 2);
  // Each mean has a relative standard deviation of about 1 / sqrt(struck) (measured at 2^22 photons
  // over eight seeds: 0.9 % for 11 000 struck); four of the difference's standard deviations.
  const double sigma = std::sqrt(1.0 / a.forward.struck + 1.0 / b.forward.struck);
  EXPECT_NEAR(meanB / meanA, 1.0, 4.0 * sigma) << a.forward.struck << " and " << b.forward.struck << " struck";
  expectNoValidationMessages();
}

TEST(RenderForward, APinholeIsRefusedNotRenderedBlack) {
  Scene s = litFloor(0.0, 8);
  s.render.method = Method::Forward;
  try {
    render(s);
    FAIL() << "a pinhole camera rendered forward";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("camera.aperture"), std::string::npos) << e.what();
  }
}

TEST(RenderForward, ATimeLimitStopsWithinOneBatch) {
  Scene s = litFloor(0.5, 16);
  s.render.method = Method::Forward;
  s.render.timeLimit = 0.3;
  RenderOptions o;
  o.bandBudgetMs = 50.0;
  RenderResult r = render(s, o);
  EXPECT_GT(r.forward.photonsPerLight, 0u);
  EXPECT_GE(r.forward.batches, 2);
  // Batches are sized to end within the budget from the speed measured so far, so none starts once
  // the limit is spent: the total stays within the limit plus the last batch. (Not plus the batch's
  // planned 50 ms: on a loaded machine a batch can take longer than the speed measured before it.)
  EXPECT_GT(r.forward.lastBatchMs, 0.0);
  EXPECT_LE(r.timings.traceMs, 300.0 + r.forward.lastBatchMs) << r.forward.batches << " batches";
  expectNoValidationMessages();
}

TEST(CliForward, PrintsPhotonsAndTheStruckFraction) {
  auto dir = freshScratchDir("cli-forward");
  std::string scene = (dir / "floor.json").string();
  {
    std::string json = R"({ "camera": { "position": [0, 3, 0], "look_at": [0, 0, 0], "up": [0, 0, -1],
      "fov_y": 60, "aperture": 0.3 }, "image": { "width": 32, "height": 32 }, "ambient": [0, 0, 0],
      "lights": [ { "type": "point", "position": [0.6, 2, 0.4] } ],
      "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0 } ] })";
    std::FILE* f = std::fopen(scene.c_str(), "w");
    std::fputs(json.c_str(), f);
    std::fclose(f);
  }
  std::string out = (dir / "out.png").string();
  CliRun run = runVkray("render " + scene + " --method forward --photons 100000 --stats -q -o " + out, dir);
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("method: forward"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("photons emitted: 100000"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("photons struck: "), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("struck fraction: "), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("trace: "), std::string::npos) << run.out;
  EXPECT_TRUE(std::filesystem::exists(out));

  struct Bad {
    std::string args;
    std::string says;
    std::string output = "bad.png";
  };
  const Bad bad[] = {
      {"--method forward --photons 0", "--photons"},
      {"--method sideways", "--method"},
      {"--method forward --noise-threshold 0.01", "noise_threshold"},
      {"--method forward --tile 1/2", "--tile", "bad.pfm"},
      {"--method forward --inspect 1,1", "--inspect"},
      {"--method forward --precision float64", "float32"},
  };
  for (const Bad& b : bad) {
    std::string target = (dir / b.output).string();
    CliRun r = runVkray("render " + scene + " " + b.args + " -q -o " + target, dir);
    EXPECT_NE(r.exitCode, 0) << b.args;
    EXPECT_NE(r.err.find(b.says), std::string::npos) << b.args << ": " << r.err;
    EXPECT_FALSE(std::filesystem::exists(target)) << b.args;
  }
  // A pinhole: the scene file without an aperture.
  std::string pinhole = (dir / "pinhole.json").string();
  {
    std::string text = slurp(scene);
    text.replace(text.find(", \"aperture\": 0.3"), std::string(", \"aperture\": 0.3").size(), "");
    std::FILE* f = std::fopen(pinhole.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  CliRun p = runVkray("render " + pinhole + " --method forward -q -o " + (dir / "p.png").string(), dir);
  EXPECT_NE(p.exitCode, 0);
  EXPECT_NE(p.err.find("camera.aperture"), std::string::npos) << p.err;
}

TEST(CliForward, BenchPrintsBothMethodsAndWritesACsv) {
  auto dir = freshScratchDir("cli-forward-bench");
  const std::string csv = (dir / "forward.csv").string();
  CliRun run = runVkray("bench forward " + scenePath("seed.json") +
                            " --height 8 --runs 1 --reference-spp 4 --max-spp 2 --min-photons 4096 "
                            "--max-photons 16384 --csv " +
                            csv,
                        dir);
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("backward 1 spp: RMS error"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("x backward's time"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("aperture (of focus distance)"), std::string::npos) << run.out;
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "scene,method,count,median_ms,min_ms,max_ms,rms_error,rays,struck_fraction");
  std::map<std::string, int> rows;
  while (std::getline(in, line)) {
    EXPECT_EQ(line.find("nan"), std::string::npos) << line;
    rows[line.substr(line.find(',') + 1, line.find(',', line.find(',') + 1) - line.find(',') - 1)]++;
  }
  EXPECT_EQ(rows["backward"], 2); // 1 and 2 spp
  EXPECT_EQ(rows["forward"], 2);  // 4096 and 16384 photons
  EXPECT_EQ(rows["aperture"], 4); // the radius halved three times
}

TEST(SceneForward, LoadsTheMethodAndPhotonKeys) {
  Scene s = sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "render": { "method": "forward", "photons": 12345 }, "objects": [] })");
  EXPECT_EQ(s.render.method, Method::Forward);
  EXPECT_EQ(s.render.photons, 12345u);
  EXPECT_THROW(sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "render": { "photons": -1 }, "objects": [] })"),
               InputError);
  EXPECT_THROW(sceneFromJson(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "render": { "method": "both" }, "objects": [] })"),
               InputError);
}

} // namespace
} // namespace vkray::test
