// The interactive viewer. ViewSettings* and SceneWatcher* are host tests; Viewer* run build/vkray view
// in a window on lavapipe with the validation layer on, so they need a display (ctest runs them
// under xvfb-run): scripted runs exit cleanly, their screenshots equal the headless render of the
// same view bit for bit, the window shows that image under the overlay, and accumulation converges.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

#include "image/image_io.h"
#include "image/metrics.h"
#include "render/adaptive.h"
#include "scene/features.h"
#include "scene/scene_loader.h"
#include "viewer/scene_watcher.h"
#include "viewer/view_settings.h"

namespace vkray::test {
namespace {

namespace fs = std::filesystem;

void writeText(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

std::string scene(const std::string& name) {
  return std::string(VKRAY_SOURCE_DIR "/scenes/") + name;
}

// ---- Host: settings, effects, accumulation, reload ----------------------------------------------

TEST(ViewSettings, AccumulationAddsSamplesInSequenceAndRestartsAtZero) {
  Accumulation acc;
  auto s0 = acc.next(1, 100);
  EXPECT_EQ(s0.sampleBase, 0u);
  EXPECT_EQ(s0.count, 1u);
  EXPECT_FALSE(s0.accumulate) << "the first frame overwrites what an earlier view left";
  auto s1 = acc.next(1, 100);
  EXPECT_EQ(s1.sampleBase, 1u);
  EXPECT_TRUE(s1.accumulate);
  auto s2 = acc.next(4, 100);
  EXPECT_EQ(s2.sampleBase, 2u);
  EXPECT_EQ(s2.count, 4u);
  EXPECT_EQ(acc.samples(), 6u);
  acc.restart();
  auto r = acc.next(2, 100);
  EXPECT_EQ(r.sampleBase, 0u);
  EXPECT_FALSE(r.accumulate);
}

TEST(ViewSettings, AccumulationStopsAtTheCap) {
  Accumulation acc;
  EXPECT_EQ(acc.next(3, 5).count, 3u);
  EXPECT_EQ(acc.next(3, 5).count, 2u) << "the last frame stops exactly at the cap";
  EXPECT_EQ(acc.next(3, 5).count, 0u) << "converged: nothing more to trace";
  EXPECT_EQ(acc.samples(), 5u);
  EXPECT_EQ(acc.next(3, 8).count, 3u) << "raising the cap continues where it stopped";
}

TEST(ViewSettings, TheDisplayCyclesThroughTheImageAndItsMaps) {
  EXPECT_EQ(nextDisplayMode(DisplayMode::Image), DisplayMode::Error);
  EXPECT_EQ(nextDisplayMode(DisplayMode::Error), DisplayMode::Cost);
  EXPECT_EQ(nextDisplayMode(DisplayMode::Cost), DisplayMode::Image);
}

TEST(ViewSettings, SwitchedOffEffectsAreCompiledOut) {
  Scene s = loadScene(scene("showcase.json"));
  Features all = analyzeScene(s, s.render);
  ASSERT_TRUE(all.shadows);
  ASSERT_TRUE(all.reflection);
  ASSERT_TRUE(all.checker);
  EffectToggles off;
  off.shadows = false;
  off.reflection = false;
  off.checker = false;
  Scene t = withEffects(s, off);
  Features f = analyzeScene(t, t.render);
  EXPECT_FALSE(f.shadows);
  EXPECT_FALSE(f.reflection);
  EXPECT_FALSE(f.checker);
  EXPECT_TRUE(f.spheres) << "geometry stays";
  Scene same = withEffects(s, EffectToggles());
  EXPECT_EQ(analyzeScene(same, same.render).explain(), all.explain());
}

TEST(ViewSettings, RefractionOffMakesGlassOpaque) {
  Scene s = loadSceneFromString(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
      "materials": { "glass": { "transmission": 0.9, "ior": 1.5 } },
      "lights": [ { "type": "point", "position": [0, 5, 5] } ],
      "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "glass" } ] })",
                                "glass.json");
  ASSERT_TRUE(analyzeScene(s, s.render).refraction);
  EffectToggles off;
  off.refraction = false;
  Scene t = withEffects(s, off);
  EXPECT_FALSE(analyzeScene(t, t.render).refraction);
}

TEST(ViewSettings, KnobsCompareEverythingButTheImageSize) {
  RenderSettings a, b;
  b.width = 17;
  b.height = 3;
  EXPECT_TRUE(sameKnobs(a, b));
  b.maxDepth = a.maxDepth + 1;
  EXPECT_FALSE(sameKnobs(a, b));
  b = a;
  b.numerics = Numerics::Naive;
  EXPECT_FALSE(sameKnobs(a, b));
  b = a;
  b.bailout = 0.5;
  EXPECT_FALSE(sameKnobs(a, b));
  // Every other field of RenderSettings, one at a time.
  const std::vector<std::pair<const char*, std::function<void(RenderSettings&)>>> changes = {
      {"spp", [](RenderSettings& s) { s.spp = 4; }},
      {"antialiasing", [](RenderSettings& s) { s.antialiasing = Antialiasing::Adaptive; }},
      {"adaptive threshold", [](RenderSettings& s) { s.adaptiveThreshold = 0.25; }},
      {"fresnel", [](RenderSettings& s) { s.fresnel = FresnelMode::Schlick; }},
      {"transmissive shadows", [](RenderSettings& s) { s.transmissiveShadows = TransmissiveShadows::Opaque; }},
      {"bvh", [](RenderSettings& s) { s.bvh = BvhMode::Off; }},
      {"precision", [](RenderSettings& s) { s.precision = Precision::Float64; }},
      {"texture filter", [](RenderSettings& s) { s.textureFilter = TextureFilter::Nearest; }},
  };
  for (const auto& [what, change] : changes) {
    b = a;
    change(b);
    EXPECT_FALSE(sameKnobs(a, b)) << what;
  }
}

class SceneWatcherTest : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::freshScratchDir("watch");
    file_ = dir_ / "s.json";
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Rewrites the file and moves its time forward, so the change is seen whatever the clock's grain.
  void rewrite(const std::string& text) {
    auto t = fs::last_write_time(file_);
    writeText(file_, text);
    fs::last_write_time(file_, t + std::chrono::seconds(1));
  }
  fs::path dir_, file_;
};

constexpr const char* kSceneA = R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
  "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 1 } ] })";
constexpr const char* kSceneB = R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
  "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 2 } ] })";

TEST_F(SceneWatcherTest, ReloadsAChangedFile) {
  writeText(file_, kSceneA);
  SceneWatcher w(file_);
  EXPECT_FALSE(w.poll(std::chrono::milliseconds(0))) << "nothing changed yet";
  rewrite(kSceneB);
  EXPECT_TRUE(w.poll(std::chrono::milliseconds(0)));
  ASSERT_EQ(w.scene().spheres.size(), 1u);
  EXPECT_EQ(w.scene().spheres[0].radius, 2.0);
  EXPECT_EQ(w.error(), "");
}

TEST_F(SceneWatcherTest, ABrokenFileKeepsTheLastGoodSceneAndSaysWhy) {
  writeText(file_, kSceneA);
  SceneWatcher w(file_);
  rewrite(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
      "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": -1 } ] })");
  EXPECT_FALSE(w.poll(std::chrono::milliseconds(0)));
  EXPECT_EQ(w.scene().spheres[0].radius, 1.0) << "the last good scene stays";
  EXPECT_NE(w.error().find("objects[0].radius: must be > 0, got -1"), std::string::npos) << w.error();
  rewrite(kSceneB); // fixed
  EXPECT_TRUE(w.poll(std::chrono::milliseconds(0)));
  EXPECT_EQ(w.error(), "");
  EXPECT_EQ(w.scene().spheres[0].radius, 2.0);
}

TEST_F(SceneWatcherTest, ChecksNoMoreOftenThanAskedAndSurvivesADeletedFile) {
  writeText(file_, kSceneA);
  SceneWatcher w(file_);
  rewrite(kSceneB);
  EXPECT_FALSE(w.poll(std::chrono::hours(1))) << "checked within the interval";
  fs::remove(file_);
  EXPECT_FALSE(w.poll(std::chrono::milliseconds(0)));
  EXPECT_NE(w.error(), "") << "a missing file is reported";
  EXPECT_EQ(w.scene().spheres[0].radius, 1.0);
}

// ---- The viewer in a window ----------------------------------------------------------------------

struct RunResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};

class Viewer : public ::testing::Test {
protected:
  static void SetUpTestSuite() {
    // One pipeline cache for the suite's runs: the first compiles the kernel, the rest reuse it.
    cacheDir_ = test::scratchDir("viewer-cache");
  }
  static void TearDownTestSuite() { fs::remove_all(cacheDir_); }
  void SetUp() override {
    const char* display = std::getenv("DISPLAY");
    if (display == nullptr || *display == '\0') {
      GTEST_SKIP() << "no display: the viewer tests run under xvfb-run (ctest's 'viewer' entry)";
    }
    dir_ = test::freshScratchDir("viewer-test");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  // Runs build/vkray with args on lavapipe; `env` prefixes the command (e.g. "env -u DISPLAY").
  RunResult vkray(const std::string& args, const std::string& env = "") const {
    std::string cmd = env + " VKRAY_DEVICE=llvmpipe VKRAY_CACHE_DIR='" + cacheDir_.string() + "' '" VKRAY_BINARY "' " +
                      args + " >'" + (dir_ / "out").string() + "' 2>'" + (dir_ / "err").string() + "'";
    int status = std::system(cmd.c_str());
    RunResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = slurp(dir_ / "out");
    r.err = slurp(dir_ / "err");
    return r;
  }

  // Scripted viewer run with validation; fails the test unless it exits 0 without a message.
  Image view(const std::string& sceneFile, const std::string& flags, const std::string& shot) {
    fs::path out = dir_ / shot;
    RunResult r = vkray("view '" + sceneFile + "' " + flags + " --screenshot '" + out.string() + "' --validate");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "") << "the validation layer (or something else) complained";
    EXPECT_TRUE(fs::exists(out)) << r.out << r.err;
    return fs::exists(out) ? readImage(out) : Image();
  }

  Image render(const std::string& sceneFile, const std::string& flags, const std::string& file) {
    fs::path out = dir_ / file;
    RunResult r = vkray("render '" + sceneFile + "' -o '" + out.string() + "' -q --validate " + flags);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    return fs::exists(out) ? readImage(out) : Image();
  }

  static void expectBitIdentical(const Image& a, const Image& b) {
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
      if (std::memcmp(&a.pixels[i], &b.pixels[i], sizeof(glm::vec3)) != 0) ++differing;
    }
    EXPECT_EQ(differing, 0u) << "of " << a.pixels.size() << " pixels";
  }

  static fs::path cacheDir_;
  fs::path dir_;
};

fs::path Viewer::cacheDir_;

TEST_F(Viewer, ScriptedRunExitsCleanlyUnderValidation) {
  fs::path shot = dir_ / "shot.png";
  RunResult r = vkray("view '" + scene("showcase.json") + "' --width 96 --height 72 --frames 3 --screenshot '" +
                      shot.string() + "' --validate --stats");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  Image img = readImage(shot);
  EXPECT_EQ(img.width, 96u);
  EXPECT_EQ(img.height, 72u);
  EXPECT_NE(r.out.find("render size: 96x72"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("samples: 3"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("fps: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("present mode: vsync (FIFO)\n"), std::string::npos) << "vsync is the default\n" << r.out;
}

// What the window shows is the Renderer's image: read back from the swapchain image after the overlay
// (--screenshot-window) and compared with the Renderer's own screenshot of the same frame. Right of the
// overlay's panel they agree to one 8-bit level, and nearly everywhere exactly: the resolve pass
// encodes sRGB with a fit whose largest error is 0.008 of a level (shaders/resolve.comp) and the store
// (direct path) or the blit (from a half-float image) rounds that to 8 bits, while the PNG writer
// encodes the float sums exactly on the host. Values within 0.008 levels of a rounding boundary may
// round the other way: at most 1.6 % of evenly spread values, so on the direct path at most 2 % may
// differ. The blit path's half floats add up to half their spacing, 0.062 levels below 1, before the
// blit rounds: at most 14 % of values, so 15 % (2.6 % are seen on the showcase). A swapped channel,
// a flipped row order or a missing/double sRGB encoding would be off by far more. Under the panel the overlay was drawn
// on the window, and not into the screenshot. Both resolve paths (presenter.h) are checked: lavapipe's swapchain images
// are storage images, so the default is the direct one.
// panelRight: 0 when the overlay is hidden (the whole window is compared).
void expectWindowShowsRenderersImage(const fs::path& shot, const fs::path& window, double maxDifferentShare,
                                     std::uint32_t panelRight = 8 + 340 + 8) {
  Image a = readImage(shot);
  Image b = readImage(window);
  ASSERT_EQ(a.width, b.width);
  ASSERT_EQ(a.height, b.height);
  int maxOutside = 0;
  std::size_t valuesOutside = 0;
  std::size_t differentOutside = 0;
  std::size_t differentInside = 0;
  for (std::uint32_t y = 0; y < a.height; ++y) {
    for (std::uint32_t x = 0; x < a.width; ++x) {
      int d = 0;
      for (int c = 0; c < 3; ++c) {
        int dc = std::abs(int(encodeSrgb8(a.at(x, y)[c])) - encodeSrgb8(b.at(x, y)[c]));
        d = std::max(d, dc);
        if (x >= panelRight) {
          ++valuesOutside;
          differentOutside += dc != 0;
        }
      }
      if (x >= panelRight)
        maxOutside = std::max(maxOutside, d);
      else if (d > 8)
        ++differentInside;
    }
  }
  EXPECT_LE(maxOutside, 1) << "8-bit levels between the window and the Renderer's image";
  EXPECT_LE(double(differentOutside), maxDifferentShare * double(valuesOutside))
      << "8-bit values that differ, of " << valuesOutside;
  if (panelRight > 0) {
    EXPECT_GT(differentInside, std::size_t(panelRight) * a.height / 2) << "the overlay covers its panel";
  }
}

TEST_F(Viewer, TheWindowShowsTheRenderersImageWithTheOverlayOnTop) {
  for (const std::string path : {"direct", "blit"}) {
    SCOPED_TRACE(path);
    fs::path shot = dir_ / (path + "-shot.png");
    fs::path window = dir_ / (path + "-window.png");
    RunResult r =
        vkray("view '" + scene("showcase.json") + "' --width 480 --height 200 --frames 2 --no-vsync --screenshot '" +
              shot.string() + "' --screenshot-window '" + window.string() + "' --validate --stats" +
              (path == "blit" ? " --no-direct-resolve" : ""));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_NE(r.out.find("present mode: no vsync ("), std::string::npos) << "--no-vsync\n" << r.out;
    EXPECT_NE(r.out.find("resolve path: " + path + "\n"), std::string::npos) << r.out;
    expectWindowShowsRenderersImage(shot, window, path == "blit" ? 0.15 : 0.02);
  }
}

// On the direct path the panel is drawn on a layer that the resolve pass composites, and redrawn only
// when it changes: hidden, the layer is cleared once and the window is the Renderer's image
// everywhere. The resolve pass's workgroups are one image row wide (presenter.h), rounded up to
// whole SIMD batches and capped by the device's workgroup limits (1024 on lavapipe): a width of 8k,
// one that is not, and one beyond the cap (two groups per row) must each get every pixel right.
TEST_F(Viewer, WithTheOverlayHiddenTheWindowIsTheRenderersImage) {
  for (const std::string size : {"480x200", "437x61", "1100x24"}) {
    SCOPED_TRACE(size);
    const std::string width = size.substr(0, size.find('x'));
    const std::string height = size.substr(size.find('x') + 1);
    fs::path shot = dir_ / ("hidden-shot-" + size + ".png");
    fs::path window = dir_ / ("hidden-window-" + size + ".png");
    RunResult r = vkray("view '" + scene("showcase.json") + "' --width " + width + " --height " + height +
                        " --frames 3 --no-vsync --no-overlay --screenshot '" + shot.string() +
                        "' --screenshot-window '" + window.string() + "' --validate --stats");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_NE(r.out.find("resolve path: direct\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("window size: " + size + "\n"), std::string::npos) << r.out;
    expectWindowShowsRenderersImage(shot, window, 0.02, 0);
  }
}

// A click (here --inspect, which picks the pixel as a click does) shows the pixel's ray tree: the
// same rays `render --inspect` prints, drawn over the image (the window differs from the Renderer's
// image along them, beside the panel), and the image itself is untouched: after the restart the
// inspection makes, N frames are still `render --spp N` bit for bit.
TEST_F(Viewer, AnInspectedPixelShowsTheRenderersTreeAndLeavesTheImageAlone) {
  const std::string size = "--width 480 --height 360";
  fs::path shot = dir_ / "inspect-shot.pfm", window = dir_ / "inspect-window.png";
  RunResult r =
      vkray("view '" + scene("glass.json") + "' " + size + " --frames 3 --no-vsync --inspect 384,198 " +
            "--screenshot '" + shot.string() + "' --screenshot-window '" + window.string() + "' --validate --stats");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const std::string marker = "inspected pixel: 384,198 (";
  const auto at = r.out.find(marker);
  ASSERT_NE(at, std::string::npos) << r.out;
  const int viewerRays = std::stoi(r.out.substr(at + marker.size()));

  RunResult tree = vkray("render '" + scene("glass.json") + "' " + size + " --inspect 384,198 --validate");
  ASSERT_EQ(tree.exitCode, 0) << tree.err;
  int rendererRays = 0;
  for (std::size_t p = tree.out.find("{\"index\":"); p != std::string::npos; p = tree.out.find("{\"index\":", p + 1))
    ++rendererRays;
  EXPECT_GT(rendererRays, 5) << "a glass pixel's tree";
  EXPECT_EQ(viewerRays, rendererRays);

  expectBitIdentical(readImage(shot), render(scene("glass.json"), size + " --spp 3", "inspect-render.pfm"));

  // Right of the panel (340 wide at most), the lines are all that differs.
  Image image = readImage(shot), shown = readImage(window);
  ASSERT_EQ(image.width, shown.width);
  std::size_t onLines = 0;
  for (std::uint32_t y = 0; y < image.height; ++y) {
    for (std::uint32_t x = 360; x < image.width; ++x) {
      glm::vec3 a = glm::clamp(image.at(x, y), 0.0f, 1.0f), b = shown.at(x, y);
      // The window is sRGB 8-bit: compare in display terms, well above its rounding.
      glm::vec3 ad(linearToSrgb(a.r), linearToSrgb(a.g), linearToSrgb(a.b));
      glm::vec3 bd(linearToSrgb(b.r), linearToSrgb(b.g), linearToSrgb(b.b));
      onLines += glm::length(ad - bd) > 0.25f;
    }
  }
  EXPECT_GT(onLines, 50u) << "the rays are drawn over the image";
}

// The viewer traces sample k of every pixel's sequence in frame k and adds it to the sums; the
// headless render at spp N traces samples 0..N-1 in one loop, s0 + s1 + ... in the same order, with
// the same specialized pipeline. So N still frames of 1 sample equal `render --spp N` bit for bit.
// (N = 1 is not compared: a headless 1-spp render goes through pixel centres, the viewer's first
// frame through sample 0 of the sequence, which is what lets later frames converge.)
TEST_F(Viewer, ScreenshotAfterNFramesEqualsTheHeadlessRenderAtNSppBitForBit) {
  const std::string size = "--width 96 --height 72";
  Image viewed = view(scene("showcase.json"), size + " --frames 4 --spp 1", "view.pfm");
  Image headless = render(scene("showcase.json"), size + " --spp 4 --stats", "render.pfm");
  expectBitIdentical(viewed, headless);
}

// A model file opens as a scene in the viewer as in `render`: the same fitted camera, lights and floor.
TEST_F(Viewer, AModelFileIsASceneAsInTheHeadlessRender) {
  const std::string model = VKRAY_SOURCE_DIR "/tests/data/meshes/box.obj";
  const std::string flags = "--width 96 --height 72 --floor --background 0.2,0.3,0.4";
  Image viewed = view(model, flags + " --frames 2 --spp 1", "model-view.pfm");
  Image headless = render(model, flags + " --spp 2 --stats", "model-render.pfm");
  expectBitIdentical(viewed, headless);
}

// A `name: value` line of --stats output, as a number (NaN when absent).
double statValue(const std::string& out, const std::string& name) {
  auto at = out.find("\n" + name + ": ");
  if (at == std::string::npos) return std::nan("");
  return std::stod(out.substr(at + name.size() + 3));
}

// The viewer counts rays in a sample of its frames (the first traced frame of each half-second
// interval and every 16th one) through the counting pipeline, and traces the others with the same
// kernel built without counters. Its "rays per frame" is the counted frames' average, and must
// match a headless render's rays per sample within 1 %: frames differ only in where each pixel's
// jittered sample falls, which moved 0.07 % of the rays at this size. Dividing by every frame
// instead of the counted ones, or counting a frame twice or not at all, is off by 12 % or more.
TEST_F(Viewer, RayCountsFromASampleOfTheFramesMatchTheHeadlessCounts) {
  const std::string size = " --width 96 --height 72";
  RunResult v = vkray("view '" + scene("showcase.json") + "'" + size + " --frames 40 --stats --validate");
  ASSERT_EQ(v.exitCode, 0) << v.err;
  EXPECT_EQ(v.err, "");
  const double timed = statValue(v.out, "frames timed");
  const double counted = statValue(v.out, "ray-counted frames");
  const double perFrame = statValue(v.out, "rays per frame");
  EXPECT_GE(counted, 1.0) << v.out;
  EXPECT_LT(counted, timed) << "every frame paid for counting\n" << v.out;

  fs::path out = dir_ / "counts.png";
  RunResult h = vkray("render '" + scene("showcase.json") + "' -o '" + out.string() + "'" + size +
                      " --spp 40 --stats --validate");
  ASSERT_EQ(h.exitCode, 0) << h.err;
  const double perSample = statValue(h.out, "rays") / 40.0;
  EXPECT_NEAR(perFrame, perSample, 0.01 * perSample) << v.out << h.out;
}

// ---- Convergence figures and maps (viewer/convergence.h) -----------------------------------------

// The split-half estimate of the final image's error (its last frame is measured): with more samples
// the mean estimate falls and more pixels pass the threshold. The showcase's noise is at its edges
// (antialiasing) and in its glossy highlights; with the stratified sequence it falls about as 1/n.
TEST_F(Viewer, TheErrorFallsAndTheConvergedShareRisesAsSamplesAccumulate) {
  double previousError = 1e30, firstConverged = -1.0, previousConverged = -1.0;
  for (int frames : {4, 16, 64}) {
    SCOPED_TRACE(frames);
    RunResult r =
        vkray("view '" + scene("showcase.json") + "' --width 64 --height 48 --no-ray-counts --frames " +
              std::to_string(frames) + " --stats --validate --screenshot '" + (dir_ / "s.pfm").string() + "'");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_NE(r.out.find("noise threshold: 0.01 (default)\n"), std::string::npos) << r.out;
    EXPECT_EQ(statValue(r.out, "error samples"), frames) << "the last frame is measured\n" << r.out;
    const double error = statValue(r.out, "error mean");
    const double converged = statValue(r.out, "converged");
    EXPECT_GT(error, 0.0) << r.out;
    EXPECT_LT(error, previousError) << r.out;
    EXPECT_GE(converged, previousConverged) << r.out;
    EXPECT_GE(statValue(r.out, "error p95"), error) << r.out;
    if (firstConverged < 0) firstConverged = converged;
    previousError = error;
    previousConverged = converged;
  }
  EXPECT_GT(previousConverged, firstConverged + 1.0) << "percent converged at 64 against 4 samples";
  EXPECT_GT(previousConverged, 50.0) << "most of the showcase is smooth at 64 samples";
}

// A view of one flat, unlit colour: every sample of every pixel is the same, so the estimate is 0 up
// to the sums' rounding and every pixel has converged. Started in the error map (--display error),
// whose screenshot holds the estimates; the window shows the map under the validation layer.
TEST_F(Viewer, AFlatSceneHasNoErrorAndHasConvergedEverywhere) {
  fs::path flat = dir_ / "flat.json";
  writeText(flat, R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] }, "ambient": [1, 1, 1],
      "materials": { "m": { "color": [0.3, 0.5, 0.7], "ambient": 1, "diffuse": 0, "specular": 0 } },
      "objects": [ { "type": "plane", "normal": [0, 0, 1], "point": [0, 0, 0], "material": "m" } ] })");
  fs::path shot = dir_ / "error.pfm";
  RunResult r = vkray("view '" + flat.string() + "' --width 48 --height 32 --frames 8 --display error --stats " +
                      "--validate --noise-threshold 0.001 --screenshot '" + shot.string() + "' --screenshot-window '" +
                      (dir_ / "window.png").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("display: error\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("noise threshold: 0.001\n"), std::string::npos) << r.out;
  EXPECT_LT(statValue(r.out, "error mean"), 1e-6) << r.out;
  EXPECT_EQ(statValue(r.out, "converged"), 100.0) << r.out;
  Image errors = readImage(shot);
  ASSERT_EQ(errors.width, 48u);
  float worst = 0.0f;
  for (const glm::vec3& p : errors.pixels) worst = std::max(worst, p.x);
  EXPECT_LT(worst, 1e-5f) << "every pixel's estimate (and none missing, which reads +inf)";
}

// The converged share is the headless stopping rule applied to the estimates the error map shows:
// a pixel has converged when kOwnShare of its own squared estimate plus the rest of the mean square
// over its 3 x 3 neighbourhood (inside the image) is at most the threshold squared, and, below
// kContrastGuardSamples samples, the range of that neighbourhood's means (the largest channel) over
// the samples is at most kContrastShare of the threshold (host/render/adaptive.h). The means come
// from a headless render of the same 8 samples.
TEST_F(Viewer, TheConvergedShareIsTheHeadlessRuleOnTheErrorMap) {
  const double threshold = 0.01;
  fs::path shot = dir_ / "estimates.pfm";
  RunResult r = vkray("view '" + scene("showcase.json") + "' --width 64 --height 48 --frames 8 --display error " +
                      "--no-ray-counts --stats --validate --noise-threshold 0.01 --screenshot '" + shot.string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  Image e = readImage(shot);
  ASSERT_EQ(e.width, 64u);
  Image means = render(scene("showcase.json"), "--width 64 --height 48 --spp 8", "u8.pfm");
  ASSERT_EQ(means.pixels.size(), e.pixels.size());
  ASSERT_LT(8.0f, ProgressiveImage::kContrastGuardSamples);
  std::size_t converged = 0, quiet = 0;
  for (std::uint32_t y = 0; y < e.height; ++y) {
    for (std::uint32_t x = 0; x < e.width; ++x) {
      double sum = 0.0;
      int count = 0;
      glm::dvec3 lo(1e30), hi(-1e30);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = int(x) + dx, v = int(y) + dy;
          if (u < 0 || v < 0 || u >= int(e.width) || v >= int(e.height)) continue;
          const double q = e.at(u, v).x;
          sum += q * q;
          ++count;
          lo = glm::min(lo, glm::dvec3(means.at(u, v)));
          hi = glm::max(hi, glm::dvec3(means.at(u, v)));
        }
      }
      const double own = e.at(x, y).x;
      const double ownShare = ProgressiveImage::kOwnShare;
      const bool estimate = ownShare * own * own + (1.0 - ownShare) * sum / count <= threshold * threshold;
      const double range = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
      quiet += estimate;
      converged += estimate && range / 8.0 <= ProgressiveImage::kContrastShare * threshold;
    }
  }
  const double share = 100.0 * double(converged) / double(e.pixels.size());
  EXPECT_GT(share, 5.0);
  EXPECT_LT(share, 99.0) << "some pixels of the showcase are still noisy at 8 samples";
  EXPECT_GT(quiet, converged + 50) << "the contrast rule holds pixels whose estimates alone would pass";
  // Float against double at the threshold may flip a pixel or two (each is 0.033 %).
  EXPECT_NEAR(statValue(r.out, "converged"), share, 0.07) << r.out;
}

// The error map is the three-block estimate of the frames' samples. After 6 frames the viewer has
// copied the sums at 1, 2 and 4 samples and keeps the last two copies, so the blocks are samples
// [0, 2), [2, 4) and [4, 6). Viewer frames are the headless render's samples bit for bit, so
// headless renders at 2, 4 and 6 spp give each block's mean (from the means times their counts,
// in double), and sigma^2 = sum_j m_j (x_j - x)^2 / ((3 - 1) n), the largest channel. Float sums
// on the GPU against double on the host: within 0.1 % where the estimate is above 1e-3.
TEST_F(Viewer, TheErrorMapIsTheThreeBlockEstimateOfTheFrames) {
  const std::string size = "--width 64 --height 48";
  Image estimates = view(scene("showcase.json"), size + " --no-ray-counts --frames 6 --display error", "error.pfm");
  Image u2 = render(scene("showcase.json"), size + " --spp 2", "u2.pfm");
  Image u4 = render(scene("showcase.json"), size + " --spp 4", "u4.pfm");
  Image u6 = render(scene("showcase.json"), size + " --spp 6", "u6.pfm");
  ASSERT_EQ(estimates.pixels.size(), u6.pixels.size());
  std::size_t compared = 0;
  for (std::size_t i = 0; i < u6.pixels.size(); ++i) {
    const glm::dvec3 s2 = 2.0 * glm::dvec3(u2.pixels[i]), s4 = 4.0 * glm::dvec3(u4.pixels[i]),
                     s6 = 6.0 * glm::dvec3(u6.pixels[i]);
    const glm::dvec3 mean = s6 / 6.0;
    const std::array<glm::dvec3, 3> blocks{s2 / 2.0, (s4 - s2) / 2.0, (s6 - s4) / 2.0};
    double worst = 0.0;
    for (int c = 0; c < 3; ++c) {
      double squares = 0.0;
      for (const glm::dvec3& b : blocks) squares += 2.0 * (b[c] - mean[c]) * (b[c] - mean[c]);
      worst = std::max(worst, squares / (2.0 * 6.0));
    }
    const double expected = std::sqrt(worst);
    const double got = estimates.pixels[i].x;
    if (expected > 1e-3) {
      EXPECT_NEAR(got, expected, 1e-3 * expected) << "pixel " << i;
      ++compared;
    } else {
      EXPECT_NEAR(got, expected, 2e-6) << "pixel " << i;
    }
  }
  EXPECT_GT(compared, 100u) << "the showcase has noisy pixels at 6 samples";
}

// The cost map counts the rays each pixel traced (eye, shadow, reflection, refraction) per sample.
// The left half of the view is a mirror, whose pixels also trace a reflection ray and the shadow ray
// of what it shows (a lit wall behind the camera); the right half is a lit diffuse wall (an eye ray
// and a shadow ray); above and below them the eye rays meet nothing: one ray per sample, exactly.
TEST_F(Viewer, TheCostMapCountsRaysPerSample) {
  fs::path file = dir_ / "mirror.json";
  writeText(file, R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 40 },
      "materials": { "mirror": { "color": [1, 1, 1], "diffuse": 0, "specular": 0, "reflection": 1 },
                     "wall": { "color": [0.8, 0.8, 0.8] } },
      "lights": [ { "type": "point", "position": [0, 1, 6] } ],
      "objects": [
        { "type": "polygon", "material": "mirror", "vertices": [[-2, -0.8, 0], [0, -0.8, 0], [0, 0.8, 0], [-2, 0.8, 0]] },
        { "type": "polygon", "material": "wall", "vertices": [[0, -0.8, 0], [2, -0.8, 0], [2, 0.8, 0], [0, 0.8, 0]] },
        { "type": "plane", "normal": [0, 0, -1], "point": [0, 0, 10], "material": "wall" } ] })");
  fs::path shot = dir_ / "cost.pfm";
  RunResult r = vkray("view '" + file.string() + "' --width 64 --height 48 --frames 4 --display cost --stats " +
                      "--validate --screenshot '" + shot.string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("display: cost\n"), std::string::npos) << r.out;
  Image cost = readImage(shot);
  ASSERT_EQ(cost.width, 64u);
  const float mirror = cost.at(16, 24).x, wall = cost.at(48, 24).x;
  EXPECT_EQ(cost.at(0, 0).x, 1.0f) << "background: the eye ray alone";
  EXPECT_EQ(cost.at(63, 47).x, 1.0f) << "background: the eye ray alone";
  EXPECT_EQ(wall, 2.0f) << "the wall: the eye ray and the light's shadow ray";
  EXPECT_GE(mirror, 3.0f) << "the mirror: the eye ray, its reflection and the reflected wall's shadow ray";
  EXPECT_GT(mirror, wall);
  // The same view shown as the image is still the headless render's.
  Image viewed = view(file.string(), "--width 64 --height 48 --frames 4 --no-overlay", "image.pfm");
  Image headless = render(file.string(), "--width 64 --height 48 --spp 4 --stats", "render.pfm");
  expectBitIdentical(viewed, headless);
}

TEST_F(Viewer, PngScreenshotOfAGlassSceneEqualsTheHeadlessPng) {
  // Refraction this time (another specialization), with the overlay hidden, through 8-bit PNGs.
  fs::path glass = dir_ / "glass.json";
  writeText(glass, R"({ "camera": { "position": [0, 1.5, 6], "look_at": [0, 0.8, 0] },
      "background": [0.3, 0.4, 0.6],
      "materials": { "glass": { "color": [1, 1, 1], "diffuse": 0, "ambient": 0, "transmission": 0.9,
                                "reflection": 0.1, "ior": 1.5 },
                     "floor": { "checker": { "color2": [0.1, 0.1, 0.1], "scale": 0.5 } } },
      "lights": [ { "type": "point", "position": [2, 6, 4] } ],
      "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" },
                   { "type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "glass" } ] })");
  const std::string size = "--width 80 --height 64 --max-depth 4";
  Image viewed = view(glass.string(), size + " --frames 2 --no-overlay", "view.png");
  Image headless = render(glass.string(), size + " --spp 2 --stats", "render.png");
  expectBitIdentical(viewed, headless);
}

TEST_F(Viewer, AResizeRestartsAccumulationAtTheNewSize) {
  // Halfway through, the window is resized; the swapchain, the display image and the Renderer's image
  // are re-created, and the frames counted again, so the result is a clean 4-frame image at the new size.
  Image viewed = view(scene("showcase.json"), "--width 96 --height 72 --frames 4 --resize-to 64x40", "resized.pfm");
  EXPECT_EQ(viewed.width, 64u);
  EXPECT_EQ(viewed.height, 40u);
  Image headless = render(scene("showcase.json"), "--width 64 --height 40 --spp 4 --stats", "render.pfm");
  expectBitIdentical(viewed, headless);
}

TEST_F(Viewer, StillFramesConvergeTowardsTheHighSppRender) {
  const std::string size = "--width 64 --height 48";
  Image reference = render(scene("showcase.json"), size + " --spp 256", "reference.pfm");
  double previous = 1e30;
  for (int frames : {1, 4, 16, 64}) {
    Image viewed = view(scene("showcase.json"), size + " --no-ray-counts --frames " + std::to_string(frames),
                        "view" + std::to_string(frames) + ".pfm");
    double rmse = compareImages(viewed, reference).rmse;
    EXPECT_LT(rmse, previous) << frames << " frames";
    previous = rmse;
  }
  EXPECT_LT(previous, 0.01) << "64 frames are close to the 256-sample reference";
}

TEST_F(Viewer, EditingTheSceneFileReloadsIt) {
  // Scene A is on screen; the test replaces the file (as editors do: a new file renamed over the old
  // one) once the viewer says it is viewing. The run's frames start again with the new scene, so its
  // screenshot is exactly the headless render of scene B.
  const char* a = R"({ "camera": { "position": [0, 0, 4], "look_at": [0, 0, 0] },
      "lights": [ { "type": "point", "position": [3, 3, 3] } ],
      "materials": { "m": { "color": [0.9, 0.2, 0.1] } },
      "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m" } ] })";
  std::string b = a;
  b.replace(b.find("[0.9, 0.2, 0.1]"), 15, "[0.1, 0.3, 0.9]");
  fs::path file = dir_ / "edited.json";
  writeText(file, a);
  fs::path shot = dir_ / "edited.pfm";
  std::string cmd = "VKRAY_DEVICE=llvmpipe VKRAY_CACHE_DIR='" + cacheDir_.string() + "' '" VKRAY_BINARY "' view '" +
                    file.string() + "' --width 48 --height 36 --frames 8 --validate --screenshot '" + shot.string() +
                    "' 2>'" + (dir_ / "err").string() + "'";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::vector<std::string> lines;
  char line[1024];
  bool edited = false;
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    lines.emplace_back(line);
    if (!edited && lines.back().rfind("vkray: viewing ", 0) == 0) {
      fs::path next = dir_ / "edited.json.new";
      writeText(next, b);
      // A later time than the first version's, whatever the file system's time grain.
      fs::last_write_time(next, fs::last_write_time(file) + std::chrono::seconds(2));
      fs::rename(next, file);
      edited = true;
    }
  }
  int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(dir_ / "err");
  EXPECT_EQ(slurp(dir_ / "err"), "");
  ASSERT_TRUE(edited) << "the viewer never said it was viewing";
  bool reloaded = false;
  for (const auto& l : lines) reloaded = reloaded || l.rfind("vkray: reloaded ", 0) == 0;
  EXPECT_TRUE(reloaded);
  Image viewed = readImage(shot);
  writeText(dir_ / "b.json", b);
  Image headless = render((dir_ / "b.json").string(), "--width 48 --height 36 --spp 8 --stats", "b.pfm");
  expectBitIdentical(viewed, headless);
}

TEST_F(Viewer, ABrokenEditKeepsTheLastGoodSceneAndSaysWhy) {
  fs::path file = dir_ / "s.json";
  writeText(file, R"({ "camera": { "position": [0, 0, 4], "look_at": [0, 0, 0] },
      "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 1 } ] })");
  std::string cmd = "VKRAY_DEVICE=llvmpipe VKRAY_CACHE_DIR='" + cacheDir_.string() + "' '" VKRAY_BINARY "' view '" +
                    file.string() + "' --width 32 --height 24 --frames 6 --validate --screenshot '" +
                    (dir_ / "s.pfm").string() + "' 2>'" + (dir_ / "err").string() + "'";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char line[1024];
  bool edited = false;
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    if (!edited && std::string(line).rfind("vkray: viewing ", 0) == 0) {
      fs::path next = dir_ / "s.json.new";
      writeText(next, "{ \"camera\": ");
      fs::last_write_time(next, fs::last_write_time(file) + std::chrono::seconds(2));
      fs::rename(next, file);
      edited = true;
    }
  }
  int status = pclose(pipe);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(dir_ / "err");
  std::string err = slurp(dir_ / "err");
  EXPECT_EQ(err.rfind("vkray: reload failed, keeping the last good scene: " + file.string(), 0), 0u) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(readImage(dir_ / "s.pfm").width, 32u) << "the last good scene was still shown and saved";
}

TEST_F(Viewer, AMovingCameraRestartsAccumulationEveryFrame) {
  // --spin orbits the camera every frame: each frame re-prepares the Renderer (with the frame before
  // it finished) and the image starts again, so it ends with one sample per pixel. (--motion-scale 1:
  // full resolution while moving, to compare with the still image.)
  fs::path shot = dir_ / "spin.png";
  RunResult r = vkray("view '" + scene("showcase.json") +
                      "' --width 64 --height 48 --frames 5 --spin 7 --motion-scale 1 --screenshot '" + shot.string() +
                      "' --validate --stats");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("samples: 1\n"), std::string::npos) << r.out;
  Image still = view(scene("showcase.json"), "--width 64 --height 48 --frames 1", "still.png");
  EXPECT_GT(compareImages(readImage(shot), still).rmse, 0.01) << "the camera did move";
}

TEST_F(Viewer, AMovingCameraRendersAtTheMotionScale) {
  RunResult r = vkray("view '" + scene("showcase.json") + "' --width 64 --height 48 --frames 3 --spin 7 " +
                      "--motion-scale 0.5 --validate --stats --screenshot '" + (dir_ / "m.pfm").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_NE(r.out.find("render size: 32x24\n"), std::string::npos) << r.out;
  EXPECT_EQ(readImage(dir_ / "m.pfm").width, 32u);
}

// The keys, the mouse wheel and minimizing, end to end: a window manager (twm) and xdotool drive
// a live viewer through the X server as a user would. C prints the camera, the wheel zooms (but not
// while the pointer is over the overlay, which H hides), R resets, F then W flies forward, P saves a
// screenshot, minimizing pauses tracing, Esc quits; all under the validation layer.
TEST_F(Viewer, KeysWheelAndMinimizeWorkThroughTheXServer) {
  if (std::system("command -v xdotool >/dev/null && command -v twm >/dev/null") != 0) {
    GTEST_SKIP() << "needs xdotool and twm (tools/install-deps installs them)";
  }
  // twm with nothing to draw (Xvfb has only the "fixed" font) and no interactive placement.
  writeText(dir_ / "twmrc", "RandomPlacement\nNoTitle\nTitleFont \"fixed\"\nResizeFont \"fixed\"\n"
                            "MenuFont \"fixed\"\nIconFont \"fixed\"\nIconManagerFont \"fixed\"\n");
  const std::string dir = dir_.string();
  std::string script = R"(set -u
cd ')" + dir + R"('
LANG=C LC_ALL=C twm -f twmrc 2>/dev/null &
wm=$!
trap 'kill $wm 2>/dev/null' EXIT
sleep 0.5
VKRAY_DEVICE=llvmpipe VKRAY_CACHE_DIR=')" +
                       cacheDir_.string() + R"(' ')" VKRAY_BINARY R"(' view ')" + scene("seed.json") +
                       R"(' --width 96 --height 72 --stats --validate >out 2>err &
vk=$!
win=$(timeout 60 xdotool search --sync --onlyvisible --name '^vkray' | head -1)
if [ -z "$win" ]; then kill $vk; echo "no window" >&2; exit 3; fi
# The window is mapped before the first frame: wait for that frame (and the overlay's panel in it),
# or a slow start (pipeline builds under the sanitizers) would see the wheel before the panel.
for i in $(seq 600); do grep -q '^vkray: viewing' out && break; sleep 0.1; done
xdotool windowfocus --sync "$win"
xdotool mousemove --window "$win" 48 36
sleep 1
xdotool key c; sleep 0.5
xdotool click 4 click 4 click 4; sleep 0.5
xdotool key c; sleep 0.5
xdotool key h; sleep 0.5
xdotool click 4 click 4 click 4; sleep 0.5
xdotool key c; sleep 0.5
xdotool key r; sleep 0.5
xdotool key c; sleep 0.5
xdotool key f; xdotool keydown w; sleep 1; xdotool keyup w; sleep 0.5
xdotool key c p; sleep 1
xdotool windowminimize --sync "$win"; sleep 1.5
xdotool windowmap --sync "$win"; sleep 0.5
xdotool windowfocus --sync "$win"
xdotool key Escape
for i in $(seq 600); do kill -0 $vk 2>/dev/null || break; sleep 0.1; done
wait $vk
)";
  writeText(dir_ / "drive.sh", script);
  int status = std::system(("sh '" + (dir_ / "drive.sh").string() + "'").c_str());
  std::string out = slurp(dir_ / "out");
  std::string err = slurp(dir_ / "err");
  ASSERT_TRUE(WIFEXITED(status)) << err;
  ASSERT_EQ(WEXITSTATUS(status), 0) << "the viewer (or the script driving it) failed: " << err << out;
  EXPECT_EQ(err, "") << "the validation layer (or something else) complained";

  std::vector<std::string> cameras;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("\"camera\":", 0) == 0) cameras.push_back(line);
  }
  ASSERT_EQ(cameras.size(), 5u) << out;
  const std::string sceneCamera =
      R"("camera": { "position": [0, 2.6, 8], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov_y": 40 })";
  EXPECT_EQ(cameras[0], sceneCamera);
  EXPECT_EQ(cameras[1], sceneCamera) << "the wheel over the overlay must not move the camera";
  EXPECT_NE(cameras[2], sceneCamera) << "the wheel zooms once the overlay is hidden";
  EXPECT_NE(cameras[2].find("\"look_at\": [0, 1, 0]"), std::string::npos) << "zooming keeps the orbit target";
  EXPECT_EQ(cameras[3], sceneCamera) << "R resets to the scene's camera";
  EXPECT_NE(cameras[4], sceneCamera) << "F then W flies the camera forward";
  EXPECT_EQ(slurp(dir_ / "seed-camera.json"), cameras[4]) << "C also saves the camera to a file";
  EXPECT_TRUE(fs::exists(dir_ / "seed-001.png")) << out;
  const std::size_t at = out.find("minimized: ");
  ASSERT_NE(at, std::string::npos) << out;
  EXPECT_GE(std::stod(out.substr(at + 11)), 1000.0) << "the 1.5 s minimized must be spent paused";
}

TEST_F(Viewer, NoDisplayIsAOneLineError) {
  fs::path shot = dir_ / "x.png";
  RunResult r = vkray("view '" + scene("showcase.json") + "' --frames 1 --screenshot '" + shot.string() + "'",
                      "env -u DISPLAY -u WAYLAND_DISPLAY");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err.rfind("vkray: error: cannot open a window", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(shot));
}

TEST_F(Viewer, BrokenSceneFailsBeforeAnyWindowOpens) {
  fs::path bad = dir_ / "bad.json";
  writeText(bad, R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] },
      "objects": [ { "type": "sphere", "center": [0,0,0], "radius": -1 } ] })");
  RunResult r = vkray("view '" + bad.string() + "' --frames 1", "env -u DISPLAY");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err, "vkray: error: " + bad.string() + ": objects[0].radius: must be > 0, got -1\n");
}

} // namespace
} // namespace vkray::test
