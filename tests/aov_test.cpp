// The AOV layers of `render --aov` (render/aov.h): the list's parsing, the EXR channels written from
// synthetic per-pixel statistics and first hits and read back with OpenEXR, and the first-hit
// kernel (shaders/aov.comp) against depths, normals and colours computed here in double precision
// from the camera model (docs/scene-format.md: camera), not from the renderer's own camera code.
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>

#include "image/exr_io.h"
#include "image/image_io.h"
#include "render/aov.h"
#include "scene/scene_loader.h"
#include "util/error.h"

#include "test_support.h"

namespace vkray::test {
namespace {

namespace fs = std::filesystem;
using glm::dvec3;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// The channels of an EXR file, as OpenEXR lists them (by name), with their pixel types.
std::vector<std::pair<std::string, Imf::PixelType>> channelsOf(const fs::path& path) {
  Imf::InputFile file(path.c_str());
  std::vector<std::pair<std::string, Imf::PixelType>> out;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
    out.emplace_back(it.name(), it.channel().type);
  }
  return out;
}

// One channel of an EXR file as float, row-major.
std::vector<float> readChannel(const fs::path& path, const std::string& name) {
  Imf::InputFile file(path.c_str());
  const Imath::Box2i window = file.header().dataWindow();
  const int w = window.max.x - window.min.x + 1, h = window.max.y - window.min.y + 1;
  std::vector<float> values(static_cast<std::size_t>(w) * h, -12345.0f);
  Imf::FrameBuffer frame;
  frame.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(values.data()), sizeof(float),
                                sizeof(float) * static_cast<std::size_t>(w)));
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  return values;
}

TEST(Aov, ParsesNamesAndAllInTheTablesOrder) {
  EXPECT_EQ(parseAovList("depth"), std::vector<Aov>{Aov::Depth});
  // The table's order whatever the list's; repeats count once; spaces around names are dropped.
  EXPECT_EQ(parseAovList("albedo, depth,normal,depth"), (std::vector<Aov>{Aov::Depth, Aov::Normal, Aov::Albedo}));
  const std::vector<Aov> all{Aov::Depth, Aov::Normal, Aov::Albedo, Aov::Spp, Aov::Error, Aov::Rays};
  EXPECT_EQ(parseAovList("all"), all);
  EXPECT_EQ(parseAovList("rays,all"), all);
  EXPECT_TRUE(needsFirstHits(parseAovList("normal")));
  EXPECT_FALSE(needsPixelStats(parseAovList("normal,albedo,depth")));
  EXPECT_TRUE(needsPixelStats(parseAovList("error")));
  EXPECT_FALSE(needsFirstHits(parseAovList("spp,error,rays")));
}

TEST(Aov, RefusesUnknownAndEmptyNamesSayingWhichAndTheKnownOnes) {
  const std::string known = "known: 'depth', 'normal', 'albedo', 'spp', 'error', 'rays', or 'all'";
  EXPECT_EQ(errorOf([] { parseAovList("depth,nromal"); }),
            "--aov: unknown AOV 'nromal' (did you mean 'normal'?); " + known);
  EXPECT_EQ(errorOf([] { parseAovList("motion"); }), "--aov: unknown AOV 'motion'; " + known);
  EXPECT_EQ(errorOf([] { parseAovList(""); }),
            "--aov: the list is empty: name one or more of 'depth', 'normal', 'albedo', 'spp', 'error', 'rays', or "
            "'all'");
  EXPECT_EQ(errorOf([] { parseAovList("depth,,normal"); }),
            "--aov: an empty name in 'depth,,normal': names are separated by single commas");
}

// Per-pixel statistics the renderer did not keep are an error, not layers of zeros.
TEST(Aov, RefusesPixelStatisticsTheRenderDidNotKeep) {
  PixelStats none;
  EXPECT_NO_THROW(checkPixelStats(parseAovList("depth,normal"), none));
  EXPECT_EQ(errorOf([&] { checkPixelStats(parseAovList("rays,spp"), none); }),
            "--aov spp,rays: the renderer returned no per-pixel statistics (samples, error, rays); the progressive "
            "renderer that keeps them is not in this build");
  EXPECT_THROW(aovChannels(parseAovList("error"), {}, none, 4), Error);
}

// Every AOV from synthetic first hits and statistics, encoded beside RGB and read back with
// OpenEXR: the documented names, 32-bit float even when RGB is half, the values bit for bit.
TEST(ExrAov, WritesEveryLayerAsFloatBesideRgb) {
  const std::uint32_t w = 5, h = 3;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  Image image(w, h);
  std::vector<FirstHit> hits(n);
  PixelStats stats;
  for (std::size_t i = 0; i < n; ++i) {
    const float f = static_cast<float>(i);
    image.pixels[i] = glm::vec3(0.1f * f, 0.2f * f, 0.3f * f);
    // Pixel 7 sees nothing: the kernel's miss record.
    hits[i] =
        i == 7 ? FirstHit{std::numeric_limits<float>::infinity(), glm::vec3(0.0f), glm::vec3(0.0f), 0.0f}
               : FirstHit{1.5f + f, glm::normalize(glm::vec3(1.0f, f, -2.0f)), glm::vec3(0.9f, 0.5f, 0.01f * f), 1.0f};
    stats.samples.push_back(4.0f + f);
    stats.error.push_back(0.001f * f);
    stats.rays.push_back(100.0f + 3.0f * f);
  }
  const std::vector<Aov> all = parseAovList("all");
  const std::vector<ExrChannel> layers = aovChannels(all, hits, stats, n);
  fs::path dir = freshScratchDir("exr-aov");
  for (ExrPixels pixels : {ExrPixels::Float, ExrPixels::Half}) {
    fs::path path = dir / (pixels == ExrPixels::Half ? "half.exr" : "float.exr");
    writeFileAtomic(path, encodeExr(image, pixels, layers));
    const Imf::PixelType rgb = pixels == ExrPixels::Half ? Imf::HALF : Imf::FLOAT;
    using C = std::pair<std::string, Imf::PixelType>;
    EXPECT_EQ(channelsOf(path), (std::vector<C>{{"B", rgb},
                                                {"G", rgb},
                                                {"R", rgb},
                                                {"albedo.B", Imf::FLOAT},
                                                {"albedo.G", Imf::FLOAT},
                                                {"albedo.R", Imf::FLOAT},
                                                {"depth.Z", Imf::FLOAT},
                                                {"error.Y", Imf::FLOAT},
                                                {"normal.X", Imf::FLOAT},
                                                {"normal.Y", Imf::FLOAT},
                                                {"normal.Z", Imf::FLOAT},
                                                {"rays.Y", Imf::FLOAT},
                                                {"spp.Y", Imf::FLOAT}}));
    std::vector<float> depth = readChannel(path, "depth.Z"), nx = readChannel(path, "normal.X"),
                       ny = readChannel(path, "normal.Y"), nz = readChannel(path, "normal.Z"),
                       ar = readChannel(path, "albedo.R"), ag = readChannel(path, "albedo.G"),
                       ab = readChannel(path, "albedo.B"), spp = readChannel(path, "spp.Y"),
                       err = readChannel(path, "error.Y"), rays = readChannel(path, "rays.Y");
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_EQ(depth[i], hits[i].depth) << i;
      EXPECT_EQ(glm::vec3(nx[i], ny[i], nz[i]), hits[i].normal) << i;
      EXPECT_EQ(glm::vec3(ar[i], ag[i], ab[i]), hits[i].albedo) << i;
      EXPECT_EQ(spp[i], stats.samples[i]) << i;
      EXPECT_EQ(err[i], stats.error[i]) << i;
      EXPECT_EQ(rays[i], stats.rays[i]) << i;
    }
    EXPECT_TRUE(std::isinf(depth[7]) && depth[7] > 0);
    if (pixels == ExrPixels::Float) {
      EXPECT_EQ(readExr(path).pixels, image.pixels); // RGB untouched
    }
  }
  fs::remove_all(dir);
}

TEST(ExrAov, WritesOnlyTheLayersAskedFor) {
  Image image(2, 2);
  PixelStats stats{{1, 2, 3, 4}, {0, 0, 0, 0}, {5, 6, 7, 8}};
  fs::path dir = freshScratchDir("exr-aov-some");
  fs::path path = dir / "a.exr";
  writeImage(path, image, ImageWriteOptions{false, aovChannels(parseAovList("rays"), {}, stats, 4)});
  using C = std::pair<std::string, Imf::PixelType>;
  EXPECT_EQ(channelsOf(path),
            (std::vector<C>{{"B", Imf::FLOAT}, {"G", Imf::FLOAT}, {"R", Imf::FLOAT}, {"rays.Y", Imf::FLOAT}}));
  EXPECT_EQ(readChannel(path, "rays.Y"), stats.rays);
  // A layer of the wrong size, or layers for a format that cannot hold them, is the caller's mistake.
  EXPECT_THROW(encodeExr(image, ExrPixels::Float, {ExrChannel{"x.Y", {1, 2, 3}}}), Error);
  EXPECT_THROW(writeImage(dir / "a.pfm", image, ImageWriteOptions{false, {ExrChannel{"x.Y", {1, 2, 3, 4}}}}), Error);
  EXPECT_FALSE(fs::exists(dir / "a.pfm"));
  fs::remove_all(dir);
}

// ---- The first-hit kernel on analytic scenes --------------------------------------------------

// The pinhole camera of docs/scene-format.md in double precision: forward towards look_at, right =
// forward x up, the image plane at distance 1 spanning tan(fov_y / 2) vertically and that times the
// aspect horizontally; pixel (x, y) from the top-left, its centre at (x + 0.5, y + 0.5).
struct PinholeCamera {
  dvec3 eye, forward, right, up;
  double tanHalf, aspect;
  std::uint32_t width, height;
  explicit PinholeCamera(const Scene& s)
      : eye(s.camera.position), forward(glm::normalize(s.camera.lookAt - s.camera.position)),
        right(glm::normalize(glm::cross(forward, s.camera.up))), up(glm::cross(right, forward)),
        tanHalf(std::tan(s.camera.fovY * 3.14159265358979323846 / 360.0)),
        aspect(static_cast<double>(s.render.width) / s.render.height), width(s.render.width), height(s.render.height) {}
  dvec3 centreRay(std::uint32_t x, std::uint32_t y) const { // unit
    double u = 2.0 * (x + 0.5) / width - 1.0, v = 1.0 - 2.0 * (y + 0.5) / height;
    return glm::normalize(forward + u * tanHalf * aspect * right + v * tanHalf * up);
  }
};

RenderResult firstHits(const Scene& scene) {
  RenderOptions options;
  options.kernel = Kernel::Aov;
  RenderResult r = render(scene, options);
  EXPECT_EQ(r.firstHits.size(), static_cast<std::size_t>(scene.render.width) * scene.render.height);
  return r;
}

// A floor seen from above, stored with its normal pointing down (away from the eye): depth is the
// distance along each pixel-centre ray to y = 0, the normal +y (turned towards the eye), the albedo
// the material's colour; above the horizon, the documented misses.
TEST(RenderAov, DepthOfAPlaneIsTheDistanceAlongEachPixelRay) {
  Scene scene = sceneFromJson(R"({
    "camera": { "position": [0.3, 2, 4], "look_at": [0, 0, -1], "fov_y": 70 },
    "image": { "width": 64, "height": 48 }, "background": [0.2, 0.3, 0.4],
    "materials": { "m": { "color": [0.8, 0.6, 0.4] } },
    "lights": [ { "position": [1, 5, 1] } ],
    "objects": [ { "type": "plane", "normal": [0, -1, 0], "offset": 0, "material": "m" } ] })");
  RenderResult r = firstHits(scene);
  PinholeCamera cam(scene);
  int hits = 0, misses = 0;
  double worst = 0.0;
  for (std::uint32_t y = 0; y < cam.height; ++y) {
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const FirstHit& h = r.firstHits[y * cam.width + x];
      dvec3 d = cam.centreRay(x, y);
      // Rays within a few degrees of the horizon are left out: there float32 rounding of the
      // direction may decide hit or miss, and t's error grows as 1 / |d.y|.
      if (std::abs(d.y) < 0.05) continue;
      if (d.y > 0) {
        ++misses;
        EXPECT_TRUE(std::isinf(h.depth) && h.depth > 0) << x << "," << y << ": " << h.depth;
        EXPECT_EQ(h.normal, glm::vec3(0.0f));
        EXPECT_EQ(h.albedo, glm::vec3(0.0f));
        EXPECT_EQ(h.hit, 0.0f);
        continue;
      }
      ++hits;
      double t = -cam.eye.y / d.y; // d is unit: t is the distance
      // 1e-5 relative: the kernel's direction is float32 (relative error ~1e-7 per component),
      // amplified by at most 1 / |d.y| <= 20 in t = -o.y / d.y, plus float32 rounding of t.
      worst = std::max(worst, std::abs(h.depth - t) / t);
      EXPECT_NEAR(h.depth, t, 1e-5 * t) << x << "," << y;
      EXPECT_EQ(h.normal, glm::vec3(0.0f, 1.0f, 0.0f)) << x << "," << y; // exact: a plane's stored unit normal
      EXPECT_EQ(h.albedo, glm::vec3(0.8f, 0.6f, 0.4f)) << x << "," << y; // the colour as packed, bit for bit
      EXPECT_EQ(h.hit, 1.0f);
    }
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(misses, 100);
  RecordProperty("worst relative depth error", std::to_string(worst));
}

// A sphere's normal at the first hit is (p - centre) / radius with p on the pixel-centre ray.
TEST(RenderAov, NormalOfASphereIsTheRadialDirectionAtTheHit) {
  Scene scene = sceneFromJson(R"({
    "camera": { "position": [0.4, 0.5, 3], "look_at": [0.2, -0.1, -1], "fov_y": 40 },
    "image": { "width": 48, "height": 40 },
    "materials": { "ball": { "color": [0.1, 0.7, 0.3] } },
    "lights": [ { "position": [1, 5, 1] } ],
    "objects": [ { "type": "sphere", "center": [0.2, -0.1, -1], "radius": 0.8, "material": "ball" } ] })");
  RenderResult r = firstHits(scene);
  PinholeCamera cam(scene);
  const dvec3 c(0.2, -0.1, -1);
  const double radius = 0.8;
  int hits = 0;
  for (std::uint32_t y = 0; y < cam.height; ++y) {
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const FirstHit& h = r.firstHits[y * cam.width + x];
      dvec3 d = cam.centreRay(x, y);
      // |eye + t d - c| = radius: t^2 + 2 b t + k = 0.
      dvec3 oc = cam.eye - c;
      double b = glm::dot(oc, d), k = glm::dot(oc, oc) - radius * radius;
      double disc = b * b - k;
      // Rays within 5 % of the radius from the silhouette are left out: there the hit itself is
      // ill-conditioned (t moves as 1 / sqrt(disc)).
      if (std::abs(disc) < 0.05 * radius * radius) continue;
      if (disc < 0) {
        EXPECT_EQ(h.hit, 0.0f) << x << "," << y;
        EXPECT_TRUE(std::isinf(h.depth)) << x << "," << y;
        continue;
      }
      ++hits;
      double t = -b - std::sqrt(disc);
      dvec3 n = (cam.eye + t * d - c) / radius;
      ASSERT_EQ(h.hit, 1.0f) << x << "," << y;
      // 1e-4: float32 camera-relative hit point and radius, normalised; away from the silhouette
      // the error of p is a few ulp of the distance (~4), well under 1e-5 of the radius.
      EXPECT_NEAR(h.depth, t, 1e-4 * t) << x << "," << y;
      EXPECT_NEAR(h.normal.x, n.x, 1e-4) << x << "," << y;
      EXPECT_NEAR(h.normal.y, n.y, 1e-4) << x << "," << y;
      EXPECT_NEAR(h.normal.z, n.z, 1e-4) << x << "," << y;
      EXPECT_LT(glm::dot(dvec3(h.normal), d), 0.0) << "faces the eye";
      EXPECT_EQ(h.albedo, glm::vec3(0.1f, 0.7f, 0.3f));
    }
  }
  EXPECT_GT(hits, 300); // of 1920 pixels: the sphere fills about a quarter of the image
}

// From inside a sphere the normal is turned towards the eye: -(p - centre) / radius.
TEST(RenderAov, NormalFacesTheEyeFromInsideASphere) {
  Scene scene = sceneFromJson(R"({
    "camera": { "position": [0, 0, 0], "look_at": [0, 0, -1], "fov_y": 60 },
    "image": { "width": 32, "height": 24 },
    "materials": { "room": { "color": [0.25, 0.5, 0.75] } },
    "objects": [ { "type": "sphere", "center": [0, 0, 0], "radius": 10, "material": "room" } ] })");
  RenderResult r = firstHits(scene);
  PinholeCamera cam(scene);
  for (std::uint32_t y = 0; y < cam.height; ++y) {
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const FirstHit& h = r.firstHits[y * cam.width + x];
      dvec3 d = cam.centreRay(x, y);
      ASSERT_EQ(h.hit, 1.0f);
      EXPECT_NEAR(h.depth, 10.0, 1e-4 * 10.0) << x << "," << y; // float32 sphere test, as above
      // The outward normal at the hit is d; towards the eye it is -d.
      EXPECT_NEAR(h.normal.x, -d.x, 1e-4);
      EXPECT_NEAR(h.normal.y, -d.y, 1e-4);
      EXPECT_NEAR(h.normal.z, -d.z, 1e-4);
      EXPECT_EQ(h.albedo, glm::vec3(0.25f, 0.5f, 0.75f));
    }
  }
}

// The albedo is the colour shading sees: on a checker, the colour of the cell at the hit.
TEST(RenderAov, AlbedoOfACheckerIsTheColourOfTheCellHit) {
  Scene scene = sceneFromJson(R"({
    "camera": { "position": [0.25, 3, 3], "look_at": [0, 0, -1], "fov_y": 60 },
    "image": { "width": 48, "height": 36 },
    "materials": { "floor": { "color": [0.9, 0.8, 0.7], "checker": { "color2": [0.1, 0.2, 0.3], "scale": 1 } } },
    "objects": [ { "type": "plane", "normal": [0, 1, 0], "offset": 0, "material": "floor" } ] })");
  RenderResult r = firstHits(scene);
  PinholeCamera cam(scene);
  int first = 0, second = 0;
  for (std::uint32_t y = 0; y < cam.height; ++y) {
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const FirstHit& h = r.firstHits[y * cam.width + x];
      dvec3 d = cam.centreRay(x, y);
      if (d.y > -0.05) continue;
      dvec3 p = cam.eye + (-cam.eye.y / d.y) * d;
      // Hits within 1e-3 of a cell boundary are left out (float32 hit points may fall either side).
      auto nearEdge = [](double v) { return std::abs(v - std::round(v)) < 1e-3; };
      if (nearEdge(p.x) || nearEdge(p.z)) continue;
      // The checker is read just below the surface (shade.glsl): the cell with y in [-1, 0).
      double cells = std::floor(p.x) + -1.0 + std::floor(p.z);
      bool odd = std::fmod(std::abs(cells), 2.0) == 1.0;
      glm::vec3 expected = odd ? glm::vec3(0.1f, 0.2f, 0.3f) : glm::vec3(0.9f, 0.8f, 0.7f);
      EXPECT_EQ(h.albedo, expected) << x << "," << y;
      (odd ? second : first)++;
    }
  }
  EXPECT_GT(first, 100);
  EXPECT_GT(second, 100);
}

// ---- The command line -------------------------------------------------------------------------

using Outcome = CliRun;

// The floor of RenderAov.DepthOfAPlaneIsTheDistanceAlongEachPixelRay, as a scene file.
const char* const kFloorScene = R"({
  "camera": { "position": [0.3, 2, 4], "look_at": [0, 0, -1], "fov_y": 70 },
  "image": { "width": 40, "height": 30 }, "background": [0.2, 0.3, 0.4], "ambient": [0.1, 0.1, 0.1],
  "materials": { "m": { "color": [0.8, 0.6, 0.4] } },
  "lights": [ { "position": [1, 5, 1] } ],
  "objects": [ { "type": "plane", "normal": [0, -1, 0], "offset": 0, "material": "m" } ] })";

class CliAov : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = freshScratchDir("cli-aov");
    scene_ = dir_ / "floor.json";
    std::ofstream(scene_) << kFloorScene;
  }
  void TearDown() override { fs::remove_all(dir_); }

  // build/vkray with args (shell-quoted), on lavapipe.
  Outcome vkray(const std::string& args) const { return runVkray(args, dir_); }
  std::string render(const fs::path& out, const std::string& flags) const {
    return "render '" + scene_.string() + "' -o '" + out.string() + "' -q " + flags;
  }

  fs::path dir_, scene_;
};

// `render --aov depth,normal,albedo`: the RGB the PFM holds, bit for bit, and the layers under
// their documented names, float even with --exr-half; depth as the camera model gives it.
TEST_F(CliAov, WritesLayersBesideThePfmsRgb) {
  fs::path pfm = dir_ / "a.pfm", exr = dir_ / "a.exr", half = dir_ / "h.exr";
  Outcome r = vkray(render(pfm, "--validate"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = vkray(render(exr, "--validate --aov depth,normal,albedo"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err, "");
  r = vkray(render(half, "--aov normal,depth --exr-half"));
  ASSERT_EQ(r.exitCode, 0) << r.err;

  using C = std::pair<std::string, Imf::PixelType>;
  EXPECT_EQ(channelsOf(exr), (std::vector<C>{{"B", Imf::FLOAT},
                                             {"G", Imf::FLOAT},
                                             {"R", Imf::FLOAT},
                                             {"albedo.B", Imf::FLOAT},
                                             {"albedo.G", Imf::FLOAT},
                                             {"albedo.R", Imf::FLOAT},
                                             {"depth.Z", Imf::FLOAT},
                                             {"normal.X", Imf::FLOAT},
                                             {"normal.Y", Imf::FLOAT},
                                             {"normal.Z", Imf::FLOAT}}));
  EXPECT_EQ(channelsOf(half), (std::vector<C>{{"B", Imf::HALF},
                                              {"G", Imf::HALF},
                                              {"R", Imf::HALF},
                                              {"depth.Z", Imf::FLOAT},
                                              {"normal.X", Imf::FLOAT},
                                              {"normal.Y", Imf::FLOAT},
                                              {"normal.Z", Imf::FLOAT}}));
  EXPECT_EQ(readExr(exr).pixels, readImage(pfm).pixels);
  EXPECT_EQ(readChannel(half, "depth.Z"), readChannel(exr, "depth.Z"));

  Scene scene = loadScene(scene_);
  PinholeCamera cam(scene);
  std::vector<float> depth = readChannel(exr, "depth.Z"), ny = readChannel(exr, "normal.Y"),
                     ag = readChannel(exr, "albedo.G");
  int hits = 0;
  for (std::uint32_t y = 0; y < cam.height; ++y) {
    for (std::uint32_t x = 0; x < cam.width; ++x) {
      const std::size_t i = y * cam.width + x;
      dvec3 d = cam.centreRay(x, y);
      if (std::abs(d.y) < 0.05) continue; // as in RenderAov.DepthOfAPlane...
      if (d.y > 0) {
        EXPECT_TRUE(std::isinf(depth[i])) << x << "," << y;
        EXPECT_EQ(ny[i], 0.0f);
        EXPECT_EQ(ag[i], 0.0f);
        continue;
      }
      ++hits;
      double t = -cam.eye.y / d.y;
      EXPECT_NEAR(depth[i], t, 1e-5 * t) << x << "," << y; // tolerance as in RenderAov.DepthOfAPlane...
      EXPECT_EQ(ny[i], 1.0f);
      EXPECT_EQ(ag[i], 0.6f);
    }
  }
  EXPECT_GT(hits, 300);
}

// Bad --aov input is one line naming the flag, exit 1, before any work, and nothing is written.
TEST_F(CliAov, RefusesBadInputBeforeAnyWork) {
  struct Case {
    std::string output, flags, error;
  };
  const std::string png = (dir_ / "a.png").string(), pfm = (dir_ / "a.pfm").string(), exr = (dir_ / "a.exr").string();
  const std::string known = "'depth', 'normal', 'albedo', 'spp', 'error', 'rays', or 'all'";
  const Case cases[] = {
      {exr, "--aov depth,nromal", "--aov: unknown AOV 'nromal' (did you mean 'normal'?); known: " + known},
      {exr, "--aov ''", "--aov: the list is empty: name one or more of " + known},
      {exr, "--aov depth,", "--aov: an empty name in 'depth,': names are separated by single commas"},
      {png, "--aov depth",
       "--aov: the output '" + png + "' is not an .exr file (PNG and PFM hold RGB alone, not layers)"},
      {pfm, "--aov all",
       "--aov: the output '" + pfm + "' is not an .exr file (PNG and PFM hold RGB alone, not layers)"},
      {pfm, "--aov depth --tile 1/2",
       "--aov: tiles (--tile) are .pfm files, which hold no layers: render the whole image to an .exr for AOVs"},
  };
  for (const Case& c : cases) {
    Outcome r = vkray(render(c.output, c.flags));
    EXPECT_EQ(r.exitCode, 1) << c.flags;
    EXPECT_EQ(r.err, "vkray: error: " + c.error + "\n") << c.flags;
    EXPECT_FALSE(fs::exists(c.output)) << c.flags;
  }
}

// spp, error and rays come from the renderer's per-pixel statistics: written when it keeps them,
// refused (and nothing written) when it returns none, never layers of zeros.
TEST_F(CliAov, PixelStatisticsAreWrittenOrRefusedNeverZeros) {
  fs::path exr = dir_ / "s.exr";
  Outcome r = vkray(render(exr, "--aov spp,error,rays,depth --spp 4"));
  if (r.exitCode != 0) {
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "vkray: error: --aov spp,error,rays: the renderer returned no per-pixel statistics (samples, "
                     "error, rays); the progressive renderer that keeps them is not in this build\n");
    EXPECT_FALSE(fs::exists(exr));
    return;
  }
  std::vector<float> spp = readChannel(exr, "spp.Y"), rays = readChannel(exr, "rays.Y");
  readChannel(exr, "error.Y"); // present
  for (std::size_t i = 0; i < spp.size(); ++i) {
    EXPECT_GE(spp[i], 1.0f) << i;
    EXPECT_GE(rays[i], spp[i]) << i; // at least one eye ray per sample
  }
}

} // namespace
} // namespace vkray::test
