// Textures (host/scene/texture.*, the glTF importer's baseColorTexture, shaders/lib/texture.glsl).
// Host (Texture*): the mip chain keeps every level's mean and handles odd sides, sRGB decoding is
// exact, wrap modes and KHR_texture_transform, data URIs, the three forms of BoxTextured (external
// file, data URI, .glb buffer view), and bad input named in one line. GPU (RenderTexture*): sampled
// colours on BoxTextured match the PNG decoded by image_io's independent reader at texels found by
// a double-precision ray cast on the host; a textured scene renders the same with and without
// specialization; ray cones at 1 spp are closer to a 256-spp reference than bilinear at 1 spp.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "image/metrics.h"
#include "numerics_support.h"
#include "render/gpu_scene.h"
#include "render/kernel_variants.h"
#include "scene/features.h"
#include "scene/mesh_import.h"
#include "scene/scene_loader.h"
#include "scene/texture.h"
#include "test_support.h"
#include "util/error.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;
using test::render;
using test::sceneFromJson;
const fs::path kAssimp = "/usr/share/assimp/models/glTF2";
const char* const kBoxForms[] = {"BoxTextured-glTF/BoxTextured.gltf", "BoxTextured-glTF-Binary/BoxTextured.glb",
                                 "BoxTextured-glTF-Embedded/BoxTextured.gltf"};

bool haveBoxTextured() {
  return fs::exists(kAssimp / kBoxForms[0]);
}

glm::dvec4 mean(const TextureLevel& l) {
  glm::dvec4 sum(0.0);
  for (const auto& t : l.texels) sum += glm::dvec4(t);
  return sum / double(l.texels.size());
}

TEST(TextureMip, LevelsHalveDownToOneAndKeepTheMeanForOddSides) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  TextureLevel base;
  base.width = 7;
  base.height = 3;
  for (int i = 0; i < 21; ++i) base.texels.emplace_back(u(rng), u(rng), u(rng), u(rng));
  glm::dvec4 m0 = mean(base);
  std::vector<TextureLevel> levels = buildMipChain(base);
  ASSERT_EQ(levels.size(), 3u); // 7x3, 3x1, 1x1
  EXPECT_EQ(levels[1].width, 3u);
  EXPECT_EQ(levels[1].height, 1u);
  EXPECT_EQ(levels[2].width, 1u);
  EXPECT_EQ(levels[2].height, 1u);
  for (const auto& l : levels) {
    glm::dvec4 m = mean(l);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(m[c], m0[c], 1e-6);
  }
}

TEST(TextureMip, PowerOfTwoLevelIsTheTwoByTwoBoxAverage) {
  TextureLevel base;
  base.width = 4;
  base.height = 2;
  for (int i = 0; i < 8; ++i) base.texels.emplace_back(float(i), 0.0f, 0.0f, 1.0f);
  auto levels = buildMipChain(base);
  ASSERT_EQ(levels.size(), 3u);
  EXPECT_FLOAT_EQ(levels[1].texels[0].x, (0 + 1 + 4 + 5) / 4.0f);
  EXPECT_FLOAT_EQ(levels[1].texels[1].x, (2 + 3 + 6 + 7) / 4.0f);
  EXPECT_FLOAT_EQ(levels[2].texels[0].x, 3.5f);
}

TEST(TextureDecode, SrgbCodesDecodeExactly) {
  for (int k = 0; k < 256; ++k) {
    double c = k / 255.0;
    double linear = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    EXPECT_NEAR(srgbToLinear(static_cast<std::uint8_t>(k)), linear, 1e-7) << k;
  }
  // A PNG of every code (encodePng writes sRGB): each decodes to its code's linear value, alpha 1.
  Image img(256, 1);
  for (int k = 0; k < 256; ++k) img.at(k, 0) = glm::vec3(srgbToLinear(static_cast<std::uint8_t>(k)));
  std::vector<std::uint8_t> png = encodePng(img);
  TextureLevel l = decodeImage(png.data(), png.size(), "codes.png");
  ASSERT_EQ(l.width, 256u);
  for (int k = 0; k < 256; ++k) {
    EXPECT_EQ(l.texels[k].x, srgbToLinear(static_cast<std::uint8_t>(k))) << k;
    EXPECT_EQ(l.texels[k].w, 1.0f);
  }
}

TEST(TextureWrap, RepeatClampMirror) {
  EXPECT_EQ(wrapCoord(-1, 4, TextureWrap::Repeat), 3u);
  EXPECT_EQ(wrapCoord(9, 4, TextureWrap::Repeat), 1u);
  EXPECT_EQ(wrapCoord(-1, 4, TextureWrap::Clamp), 0u);
  EXPECT_EQ(wrapCoord(9, 4, TextureWrap::Clamp), 3u);
  EXPECT_EQ(wrapCoord(4, 4, TextureWrap::Mirror), 3u);
  EXPECT_EQ(wrapCoord(-1, 4, TextureWrap::Mirror), 0u);
  EXPECT_EQ(wrapCoord(9, 4, TextureWrap::Mirror), 1u);
  Texture t;
  TextureLevel l;
  l.width = 2;
  l.height = 1;
  l.texels = {glm::vec4(0.0f), glm::vec4(1.0f)};
  t.levels = {l};
  EXPECT_EQ(sampleNearest(t, 0, {1.25, 0.5}).x, 0.0f); // repeat: 0.25
  t.wrapS = TextureWrap::Clamp;
  EXPECT_EQ(sampleNearest(t, 0, {1.25, 0.5}).x, 1.0f);
  EXPECT_FLOAT_EQ(sampleBilinear(t, 0, {0.5, 0.5}).x, 0.5f);
  t.wrapS = TextureWrap::Repeat;
  EXPECT_FLOAT_EQ(sampleBilinear(t, 0, {0.0, 0.5}).x, 0.5f); // between the last and the first texel
}

TEST(TextureTransform, OffsetRotationScaleAsKhrTextureTransform) {
  TextureTransform x;
  x.offset = {0.5, 0.25};
  x.scale = {2.0, 3.0};
  glm::dvec2 p = x.apply({1.0, 1.0});
  EXPECT_DOUBLE_EQ(p.x, 2.5);
  EXPECT_DOUBLE_EQ(p.y, 3.25);
  TextureTransform r;
  r.rotation = std::acos(-1.0) / 2; // the extension's matrix (cos sin; -sin cos)
  glm::dvec2 q = r.apply({1.0, 0.0});
  EXPECT_NEAR(q.x, 0.0, 1e-12);
  EXPECT_NEAR(q.y, -1.0, 1e-12);
}

TEST(TextureDataUri, Base64AndPercentEncoding) {
  auto b = decodeDataUri("data:image/png;base64,aGVsbG8=", "x");
  EXPECT_EQ(std::string(b.begin(), b.end()), "hello");
  auto p = decodeDataUri("data:,a%20b", "x");
  EXPECT_EQ(std::string(p.begin(), p.end()), "a b");
  EXPECT_THROW(decodeDataUri("data:;base64,a$b", "x"), InputError);
  EXPECT_THROW(decodeDataUri("data:,%4", "x"), InputError);
  EXPECT_THROW(decodeDataUri("http://x", "x"), InputError);
}

TEST(TextureImport, BoxTexturedInAllThreeFormsHasTheTextureAndUvs) {
  if (!haveBoxTextured()) GTEST_SKIP() << "assimp's test models are not installed";
  Image png = readImage(kAssimp / "BoxTextured-glTF/CesiumLogoFlat.png");
  for (const char* form : kBoxForms) {
    SCOPED_TRACE(form);
    Scene scene;
    MeshRequest request;
    request.file = kAssimp / form;
    request.shownAs = form;
    importMesh(request, scene);
    ASSERT_EQ(scene.textures.size(), 1u);
    const Texture& t = *scene.textures[0];
    ASSERT_EQ(t.levels[0].width, png.width);
    ASSERT_EQ(t.levels[0].height, png.height);
    if (form == kBoxForms[0]) { // its sampler (the other two forms repeat)
      EXPECT_EQ(t.wrapS, TextureWrap::Mirror);
      EXPECT_EQ(t.wrapT, TextureWrap::Clamp);
    }
    EXPECT_EQ(t.levels.back().width, 1u);
    for (std::uint32_t y = 0; y < png.height; y += 37)
      for (std::uint32_t x = 0; x < png.width; x += 41)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(t.levels[0].at(x, y)[c], png.at(x, y)[c], 2e-3);
    for (const Triangle& tri : scene.triangles) EXPECT_TRUE(tri.uvs.has_value());
    EXPECT_TRUE(analyzeScene(scene, scene.render).textures);
  }
}

// A copy of BoxTextured.gltf in a scratch directory, with `png` (or no file) as its image.
fs::path scratchBox(const std::string& name, const std::string* png) {
  fs::path dir = fs::temp_directory_path() / ("vkray-texture-" + name);
  fs::create_directories(dir);
  fs::copy_file(kAssimp / "BoxTextured-glTF/BoxTextured.gltf", dir / "BoxTextured.gltf",
                fs::copy_options::overwrite_existing);
  fs::copy_file(kAssimp / "BoxTextured-glTF/BoxTextured0.bin", dir / "BoxTextured0.bin",
                fs::copy_options::overwrite_existing);
  fs::remove(dir / "CesiumLogoFlat.png");
  if (png) std::ofstream(dir / "CesiumLogoFlat.png", std::ios::binary) << *png;
  return dir / "BoxTextured.gltf";
}

std::string importError(const fs::path& file) {
  Scene scene;
  MeshRequest request;
  request.file = file;
  request.shownAs = file.filename().string();
  try {
    importMesh(request, scene);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// One PNG chunk: length, type, data and the CRC-32 (ISO 3309, as PNG's specification defines it)
// over type and data, computed bit by bit.
std::string pngChunk(const std::string& type, const std::string& data) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (char ch : type + data) {
    crc ^= static_cast<std::uint8_t>(ch);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xFFFFFFFFu;
  auto be32 = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
                       static_cast<char>(v)};
  };
  return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc);
}

TEST(TextureBadInput, MissingUndecodableAndAbsurdImagesNameTheFile) {
  if (!haveBoxTextured()) GTEST_SKIP() << "assimp's test models are not installed";
  std::string missing = importError(scratchBox("missing", nullptr));
  EXPECT_NE(missing.find("CesiumLogoFlat.png"), std::string::npos) << missing;
  EXPECT_NE(missing.find("not found"), std::string::npos) << missing;
  EXPECT_EQ(missing.find('\n'), std::string::npos);
  std::string garbage = "this is not a PNG";
  std::string bad = importError(scratchBox("garbage", &garbage));
  EXPECT_NE(bad.find("CesiumLogoFlat.png"), std::string::npos) << bad;
  EXPECT_NE(bad.find("not a PNG or JPEG"), std::string::npos) << bad;
  // A well-formed PNG header (CRCs right, an empty IDAT) claiming 17000 x 16 pixels: refused by
  // vkray's own limit before any pixel is decoded.
  std::string huge("\x89PNG\r\n\x1a\n", 8);
  huge += pngChunk("IHDR", std::string("\0\0\x42\x68\0\0\0\x10\x08\x06\0\0\0", 13));
  huge += pngChunk("IDAT", "");
  std::string absurd = importError(scratchBox("huge", &huge));
  EXPECT_NE(absurd.find("CesiumLogoFlat.png"), std::string::npos) << absurd;
  EXPECT_NE(absurd.find("larger than vkray accepts"), std::string::npos) << absurd;
}

// ---- GPU ---------------------------------------------------------------------------------------

// Closest hit of a ray on the scene's triangles in double (Moller-Trumbore): the uv set 0 there.
bool castUv(const Scene& s, glm::dvec3 o, glm::dvec3 d, glm::dvec2& uv) {
  double best = INFINITY;
  for (const Triangle& t : s.triangles) {
    glm::dvec3 e1 = t.v[1] - t.v[0], e2 = t.v[2] - t.v[0];
    glm::dvec3 p = glm::cross(d, e2);
    double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-12) continue;
    glm::dvec3 q = o - t.v[0];
    double b1 = glm::dot(q, p) / det;
    glm::dvec3 r = glm::cross(q, e1);
    double b2 = glm::dot(d, r) / det;
    double tt = glm::dot(e2, r) / det;
    if (b1 < 0 || b2 < 0 || b1 + b2 > 1 || tt <= 0 || tt >= best) continue;
    best = tt;
    glm::dvec4 w = (1 - b1 - b2) * (*t.uvs)[0] + b1 * (*t.uvs)[1] + b2 * (*t.uvs)[2];
    uv = glm::dvec2(w.x, w.y);
  }
  return best < INFINITY;
}

TEST(RenderTexture, SampledColoursMatchTheTextureOnBoxTextured) {
  if (!haveBoxTextured()) GTEST_SKIP() << "assimp's test models are not installed";
  // The PNG through image_io's own decoder: the oracle does not share texture.cpp's.
  Image png = readImage(kAssimp / "BoxTextured-glTF/CesiumLogoFlat.png");
  for (const char* form : kBoxForms) {
    SCOPED_TRACE(form);
    // Ambient light only: a pixel is ambient (0.8 for this material) x texel.
    std::string json = R"({"camera": {"position": [0.35, 0.45, 2.2], "look_at": [0, 0, 0], "fov_y": 35},
      "image": {"width": 64, "height": 64, "ambient": [1, 1, 1]},
      "render": {"max_depth": 0, "texture_filter": "nearest"},
      "objects": [{"type": "mesh", "file": ")" +
                       (kAssimp / form).string() + R"("}]})";
    Scene scene = sceneFromJson(json);
    RenderResult r = render(scene);
    EXPECT_TRUE(r.features.textures);
    CameraFrame cam = makeCameraFrame(scene.camera, 64, 64);
    int compared = 0, differing = 0;
    for (std::uint32_t y = 0; y < 64; ++y) {
      for (std::uint32_t x = 0; x < 64; ++x) {
        glm::dvec2 uv;
        glm::dvec3 d = glm::normalize(cam.rayDirection(x + 0.5, y + 0.5, 64, 64));
        if (!castUv(scene, cam.position, d, uv)) continue;
        // The file's sampler's wrap modes; texel borders, where float and double may differ, are skipped.
        double fx = uv.x * png.width, fy = uv.y * png.height;
        if (std::abs(fx - std::round(fx)) < 0.1 || std::abs(fy - std::round(fy)) < 0.1) continue;
        auto ix = wrapCoord(static_cast<std::int64_t>(std::floor(fx)), png.width, scene.textures[0]->wrapS);
        auto iy = wrapCoord(static_cast<std::int64_t>(std::floor(fy)), png.height, scene.textures[0]->wrapT);
        glm::vec3 want = 0.8f * png.at(ix, iy);
        glm::vec3 got = r.image.at(x, y);
        ++compared;
        if (glm::length(got - want) > 3e-3) ++differing;
      }
    }
    EXPECT_GT(compared, 1500);
    EXPECT_EQ(differing, 0) << "of " << compared;
  }
}

// BoxTextured.gltf with two uv sets: TEXCOORD_1 is the file's uvs (accessor 3), TEXCOORD_0 a new
// accessor reading the normals' buffer view as pairs of floats (uvs of the wrong kind, so a render
// that samples set 0 shows something else); the material samples set `texCoord`.
fs::path boxWithTwoUvSets(const std::string& name, int texCoord) {
  fs::path src = kAssimp / "BoxTextured-glTF";
  fs::path dir = test::freshScratchDir("texcoord-" + name);
  fs::copy_file(src / "BoxTextured0.bin", dir / "BoxTextured0.bin");
  fs::copy_file(src / "CesiumLogoFlat.png", dir / "CesiumLogoFlat.png");
  nlohmann::json gltf = nlohmann::json::parse(std::ifstream(src / "BoxTextured.gltf"));
  gltf["accessors"].push_back({{"bufferView", 1}, {"componentType", 5126}, {"count", 24}, {"type", "VEC2"}});
  auto& attributes = gltf["meshes"][0]["primitives"][0]["attributes"];
  attributes["TEXCOORD_1"] = attributes["TEXCOORD_0"];
  attributes["TEXCOORD_0"] = gltf["accessors"].size() - 1;
  gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = texCoord;
  std::ofstream(dir / "BoxTextured.gltf") << gltf.dump(2);
  return dir / "BoxTextured.gltf";
}

TEST(TextureImport, TexCoordOneSelectsTheSecondUvSet) {
  if (!haveBoxTextured()) GTEST_SKIP() << "assimp's test models are not installed";
  Scene original, twoSets;
  for (auto [scene, file] :
       {std::pair{&original, kAssimp / kBoxForms[0]}, std::pair{&twoSets, boxWithTwoUvSets("import", 1)}}) {
    MeshRequest request;
    request.file = file;
    request.shownAs = file.filename().string();
    importMesh(request, *scene);
  }
  ASSERT_EQ(twoSets.triangles.size(), original.triangles.size());
  ASSERT_TRUE(twoSets.materials.back().baseColorTexture.has_value());
  EXPECT_EQ(twoSets.materials.back().baseColorTexture->texCoord, 1u);
  for (std::size_t i = 0; i < original.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      glm::dvec4 a = (*original.triangles[i].uvs)[k], b = (*twoSets.triangles[i].uvs)[k];
      EXPECT_EQ(glm::dvec2(b.z, b.w), glm::dvec2(a.x, a.y)) << "triangle " << i << " corner " << k;
    }
  }
}

TEST(RenderTexture, TexCoordOneRendersAsTheFileItCameFrom) {
  if (!haveBoxTextured()) GTEST_SKIP() << "assimp's test models are not installed";
  auto renderBox = [](const fs::path& file) {
    std::string json = R"({"camera": {"position": [0.35, 0.45, 2.2], "look_at": [0, 0, 0], "fov_y": 35},
      "image": {"width": 48, "height": 48, "ambient": [1, 1, 1]},
      "render": {"max_depth": 0, "texture_filter": "bilinear"},
      "objects": [{"type": "mesh", "file": ")" +
                       file.string() + R"("}]})";
    return render(sceneFromJson(json)).image;
  };
  Image want = renderBox(kAssimp / kBoxForms[0]);
  Image setOne = renderBox(boxWithTwoUvSets("render1", 1));
  Image setZero = renderBox(boxWithTwoUvSets("render0", 0));
  EXPECT_EQ(setOne.pixels, want.pixels) << "texCoord 1 must sample TEXCOORD_1, the file's uvs";
  EXPECT_NE(setZero.pixels, want.pixels) << "the test cannot tell the sets apart";
}

// ClearCoatTest.gltf draws its labels with emissive textures over a black base: vkray does not
// render emission, and says so in one warning rather than leaving black boxes unexplained.
TEST(TextureImport, UnreadMaterialInputsAreNamedInOneWarning) {
  const fs::path clearCoat = kAssimp / "ClearCoat-glTF/ClearCoatTest.gltf";
  if (!fs::exists(clearCoat)) GTEST_SKIP() << "assimp's test models are not installed";
  MeshRequest request;
  request.file = clearCoat;
  request.shownAs = "ClearCoatTest.gltf";
  MeshData data = readGltf(request);
  ASSERT_EQ(data.warnings.size(), 1u);
  EXPECT_NE(data.warnings[0].find("emissive texture"), std::string::npos) << data.warnings[0];
  EXPECT_EQ(data.warnings[0].find('\n'), std::string::npos);
  request.file = kAssimp / kBoxForms[0];
  EXPECT_TRUE(readGltf(request).warnings.empty()) << "BoxTextured uses only what vkray reads";
}

TEST(RenderTexture, SpecializedAndAllFeaturesKernelsAgreeOnATexturedScene) {
  if (!haveBoxTextured()) GTEST_SKIP() << "assimp's test models are not installed";
  Scene scene = sceneFromJson(R"({"camera": {"position": [1.2, 1.4, 2.2], "look_at": [0, 0, 0]},
      "image": {"width": 40, "height": 30},
      "lights": [{"type": "point", "position": [3, 4, 5]}],
      "objects": [{"type": "mesh", "file": ")" +
                              (kAssimp / kBoxForms[1]).string() + R"("},
                  {"type": "plane", "normal": [0, 1, 0], "offset": 0.5}]})");
  RenderResult specialized = render(scene);
  RenderOptions general;
  general.specialize = false;
  RenderResult everything = render(scene, general);
  EXPECT_EQ(specialized.image.pixels, everything.image.pixels);
  // Without the texture the same scene runs the texture-free kernel.
  Scene plain = scene;
  for (Material& m : plain.materials) m.baseColorTexture.reset();
  EXPECT_FALSE(analyzeScene(plain, plain.render).textures);
  EXPECT_NE(render(plain).image.pixels, specialized.image.pixels);
}

// Two triangles of `material` over the quad p[0..3], uv[0..3] at its corners, wound (0, 2, 1), (0, 3, 2).
void addTexturedQuad(Scene& s, const std::array<glm::dvec3, 4>& p, const std::array<glm::dvec4, 4>& uv,
                     std::uint32_t material) {
  for (auto [a, b, c] : {std::array<int, 3>{0, 2, 1}, std::array<int, 3>{0, 3, 2}}) {
    Triangle t;
    t.v[0] = p[a];
    t.v[1] = p[b];
    t.v[2] = p[c];
    t.uvs = std::array<glm::dvec4, 3>{uv[a], uv[b], uv[c]};
    t.material = material;
    s.triangles.push_back(t);
  }
}

// A black and white checker texture repeated 64 times over a 40 x 40 square floor, seen at a
// grazing angle: far away, many texels fall in a pixel. 256 point samples per pixel are the
// reference; one cone-filtered sample should be much closer to it than one bilinear sample.
Scene checkerFloor() {
  Scene s;
  s.camera.position = {0.0, 0.6, 6.0};
  s.camera.lookAt = {0.0, 0.0, -20.0};
  s.camera.fovY = 40.0;
  s.render.width = 96;
  s.render.height = 64;
  s.render.maxDepth = 0;
  s.ambientLight = glm::dvec3(1.0);
  auto tex = std::make_shared<Texture>();
  TextureLevel l; // 16 x 16 texels: a 2 x 2 checker of 8 x 8-texel squares
  l.width = 16;
  l.height = 16;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x)
      l.texels.push_back(((x / 8 + y / 8) % 2 == 0) ? glm::vec4(1.0f) : glm::vec4(0, 0, 0, 1));
  tex->levels = buildMipChain(l);
  s.textures.push_back(tex);
  Material m;
  m.color = glm::dvec3(1.0);
  m.ambient = 1.0;
  m.diffuse = 0.0;
  m.baseColorTexture = MaterialTexture{};
  s.materials.push_back(m);
  const double h = 20.0, tiles = 64.0;
  addTexturedQuad(s, {{{-h, 0, -h}, {h, 0, -h}, {h, 0, h}, {-h, 0, h}}},
                  {{{0, 0, 0, 0}, {tiles, 0, 0, 0}, {tiles, tiles, 0, 0}, {0, tiles, 0, 0}}}, 0);
  return s;
}

TEST(RenderTexture, RayConesAtOneSampleAreCloserToTheReferenceThanBilinear) {
  Scene s = checkerFloor();
  s.render.textureFilter = TextureFilter::Nearest;
  s.render.spp = 256;
  Image reference = render(s).image;
  s.render.spp = 1;
  s.render.textureFilter = TextureFilter::Bilinear;
  ImageError bilinear = compareImages(render(s).image, reference);
  s.render.textureFilter = TextureFilter::Cone;
  ImageError cone = compareImages(render(s).image, reference);
  s.render.textureFilter = TextureFilter::Nearest;
  ImageError nearest = compareImages(render(s).image, reference);
  std::cout << "[ ray cones ] RMSE against 256-spp nearest: cone " << cone.rmse << ", bilinear " << bilinear.rmse
            << ", nearest " << nearest.rmse << " (1 spp, 96 x 64)\n";
  RecordProperty("cone_rmse", std::to_string(cone.rmse));
  RecordProperty("bilinear_rmse", std::to_string(bilinear.rmse));
  EXPECT_LT(cone.rmse, 0.75 * bilinear.rmse);
}

// The checker floor with a texture whose every mip level is one flat grey, level k at (k + 1) / 16:
// the pixel's colour says which levels the sampler read and whether it blended them.
Scene levelFloor(TextureMinFilter minFilter) {
  Scene s = checkerFloor();
  auto tex = std::make_shared<Texture>(*s.textures[0]);
  for (std::size_t k = 0; k < tex->levels.size(); ++k) {
    for (auto& t : tex->levels[k].texels) t = glm::vec4(glm::vec3(float(k + 1) / 16.0f), 1.0f);
  }
  tex->minFilter = minFilter;
  s.textures[0] = tex;
  s.render.textureFilter = TextureFilter::Cone;
  return s;
}

// The floor's pixels: those the untextured floor (white, ambient 1) renders white.
std::vector<bool> floorPixels() {
  Scene s = checkerFloor();
  s.materials[0].baseColorTexture.reset();
  Image plain = render(s).image;
  std::vector<bool> mask;
  for (const glm::vec3& p : plain.pixels) mask.push_back(std::abs(p.r - 1.0f) < 1e-4f);
  return mask;
}

// The floor pixels' greys, in sixteenths, and the share of them not, within 1e-4, one level's grey
// (blends fall between them).
struct LevelsSeen {
  std::set<long> greys;
  double blendedShare = 0.0;
};

LevelsSeen levelsSeen(const Image& image, const std::vector<bool>& floor, std::size_t levels) {
  LevelsSeen seen;
  std::size_t blended = 0, n = 0;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    if (!floor[i]) continue;
    const float r = image.pixels[i].r;
    bool onLevel = false;
    for (std::size_t k = 0; k < levels; ++k) onLevel |= std::abs(r - float(k + 1) / 16.0f) < 1e-4f;
    blended += onLevel ? 0 : 1;
    seen.greys.insert(std::lround(r * 16.0f));
    ++n;
  }
  seen.blendedShare = double(blended) / double(std::max<std::size_t>(n, 1));
  return seen;
}

TEST(RenderTexture, MinFilterChoosesTheLevelsASampleReads) {
  const std::size_t levels = checkerFloor().textures[0]->levels.size();
  const std::vector<bool> floor = floorPixels();
  ASSERT_GT(std::count(floor.begin(), floor.end(), true), 1000);
  // The default blends the two levels around the cone's: much of the floor is between two greys.
  LevelsSeen trilinear = levelsSeen(render(levelFloor(TextureMinFilter::Trilinear)).image, floor, levels);
  EXPECT_GT(trilinear.blendedShare, 0.3);
  // MIPMAP_NEAREST reads one level: every floor pixel is exactly one level's grey, and several
  // levels are seen across the receding floor.
  for (TextureMinFilter f : {TextureMinFilter::NearestLevel, TextureMinFilter::NearestLevelNearest}) {
    LevelsSeen one = levelsSeen(render(levelFloor(f)).image, floor, levels);
    EXPECT_EQ(one.blendedShare, 0.0);
    EXPECT_GE(one.greys.size(), 3u);
  }
  // No mipmaps: the image itself everywhere, so the whole floor is level 0's grey.
  for (TextureMinFilter f : {TextureMinFilter::Linear, TextureMinFilter::Nearest}) {
    LevelsSeen none = levelsSeen(render(levelFloor(f)).image, floor, levels);
    EXPECT_EQ(none.blendedShare, 0.0);
    EXPECT_EQ(none.greys, std::set<long>{1});
  }
}

// minFilter LINEAR under the cone filter samples as the global bilinear filter does, texel for texel,
// on the real checker (the cone's level choice is then unused).
TEST(RenderTexture, MinFilterLinearEqualsTheBilinearFilter) {
  Scene s = checkerFloor();
  auto tex = std::make_shared<Texture>(*s.textures[0]);
  tex->minFilter = TextureMinFilter::Linear;
  s.render.textureFilter = TextureFilter::Bilinear;
  Image bilinear = render(s).image;
  s.textures[0] = tex;
  s.render.textureFilter = TextureFilter::Cone;
  Image linear = render(s).image;
  EXPECT_EQ(compareImages(linear, bilinear).maxAbs, 0.0);
  // ... while the default minFilter, trilinear, does not (the test can tell them apart).
  tex->minFilter = TextureMinFilter::Trilinear;
  EXPECT_GT(compareImages(render(s).image, bilinear).maxAbs, 0.05);
}

// Ray cones through curved surfaces. A 65 x 65 image, so the middle pixel's single sample is the
// optical axis; a square wall of side `side` with a 256 x 256 texture whose level k is the flat grey
// (k + 1) / 16, so trilinear filtering shows the level of detail as the grey: r = (lod + 1) / 16,
// with lod = log2(cone width at the wall x 256 / side) on the axis (the wall faces the ray).
// The expected width comes from paraxial ray-transfer (ABCD) matrices in double precision, applied
// to the cone's edge ray (half its width off the axis, at half its spread angle): the textbook
// optics that shaders/lib/texture.glsl's cone rules are written from, followed through the whole
// path, against the kernel's own ray tree.
struct ParaxialRay {
  double h = 0.0; // height off the axis
  double u = 0.0; // angle to the axis (positive: away from it)
  void travel(double t) { h += u * t; }
  // A surface of curvature k (positive: bulging towards the ray) between indices n1 and n2.
  void refract(double k, double n1, double n2) { u = (n1 / n2) * u + (n1 / n2 - 1.0) * k * h; }
  // A mirror of curvature k, unfolded: the reflected ray continues along the axis.
  void reflect(double k) { u = u + 2.0 * k * h; }
};

constexpr int kConeImage = 65;
constexpr double kConeFovY = 30.0;

double pixelAngle() {
  return std::atan(2.0 * std::tan(glm::radians(kConeFovY) / 2.0) / kConeImage);
}

Scene coneScene() {
  Scene s;
  s.camera.position = {0.0, 0.0, 0.0};
  s.camera.lookAt = {0.0, 0.0, -1.0};
  s.camera.fovY = kConeFovY;
  s.render.width = kConeImage;
  s.render.height = kConeImage;
  s.render.spp = 1;
  s.render.textureFilter = TextureFilter::Cone;
  s.ambientLight = glm::dvec3(1.0);
  auto tex = std::make_shared<Texture>();
  TextureLevel l;
  l.width = 256;
  l.height = 256;
  l.texels.assign(256 * 256, glm::vec4(1.0f));
  tex->levels = buildMipChain(l);
  for (std::size_t k = 0; k < tex->levels.size(); ++k) {
    for (auto& t : tex->levels[k].texels) t = glm::vec4(glm::vec3(float(k + 1) / 16.0f), 1.0f);
  }
  s.textures.push_back(tex);
  Material wall; // material 0: the textured wall, ambient only
  wall.color = glm::dvec3(1.0);
  wall.ambient = 1.0;
  wall.diffuse = 0.0;
  wall.baseColorTexture = MaterialTexture{};
  s.materials.push_back(wall);
  Material mirror; // material 1
  mirror.ambient = mirror.diffuse = 0.0;
  mirror.reflection = 1.0;
  s.materials.push_back(mirror);
  Material glass; // material 2
  glass.ambient = glass.diffuse = 0.0;
  glass.transmission = 1.0;
  glass.ior = 1.5;
  s.materials.push_back(glass);
  return s;
}

// The wall: a square of side `side` centred on the axis in the plane z, facing the direction `facing`
// (+1 or -1 along z), uv from 0 to 1 across it.
void addWall(Scene& s, double z, double side, double facing) {
  const double h = side / 2.0;
  const glm::dvec3 p0{-h, -h, z}, p1{h, -h, z}, p2{h, h, z}, p3{-h, h, z};
  const glm::dvec4 uv0{0, 0, 0, 0}, uv1{1, 0, 0, 0}, uv2{1, 1, 0, 0}, uv3{0, 1, 0, 0};
  // Listed the other way round for the other face: triangles (p0, p1, p2) and (p0, p2, p3).
  if (facing > 0)
    addTexturedQuad(s, {p0, p3, p2, p1}, {uv0, uv3, uv2, uv1}, 0);
  else
    addTexturedQuad(s, {p0, p1, p2, p3}, {uv0, uv1, uv2, uv3}, 0);
}

double middleGrey(const Scene& s) {
  const Image image = render(s).image;
  return image.pixels[(kConeImage / 2) * kConeImage + kConeImage / 2].r;
}

double greyForWidth(double width, double side) {
  return (std::log2(width * 256.0 / side) + 1.0) / 16.0;
}

TEST(RenderTexture, ConesWidenAtConvexMirrorsAndNarrowInGlass) {
  const double alpha = pixelAngle();
  const double d = 4.0, radius = 1.0, behind = 4.0;
  // A flat mirror (the plane z = -d) keeps the cone's spread: the width grows with the whole path.
  {
    Scene s = coneScene();
    s.render.maxDepth = 1;
    s.planes.push_back(Plane{{0, 0, 1}, d, 1});
    const double side = 8.0;
    addWall(s, behind, side, -1.0); // behind the eye, which does not block rays
    ParaxialRay edge{0.0, alpha / 2.0};
    edge.travel(d);
    edge.reflect(0.0);
    edge.travel(d + behind);
    const double expected = greyForWidth(2.0 * edge.h, side);
    EXPECT_NEAR(middleGrey(s), expected, 0.002) << "flat mirror, lod " << expected * 16.0 - 1.0;
  }
  // A convex mirror (a sphere of radius 1 whose front is d - 1 away) spreads it by 2 w / R.
  {
    Scene s = coneScene();
    s.render.maxDepth = 1;
    s.spheres.push_back(Sphere{{0, 0, -d}, radius, 1});
    const double side = 8.0;
    addWall(s, behind, side, -1.0);
    ParaxialRay edge{0.0, alpha / 2.0};
    edge.travel(d - radius);
    edge.reflect(1.0 / radius);
    edge.travel(d - radius + behind);
    const double expected = greyForWidth(2.0 * edge.h, side);
    const double withoutCurvature = greyForWidth(alpha * (2.0 * (d - radius) + behind), side);
    ASSERT_GT(expected - withoutCurvature, 2.0 / 16.0); // the curvature is worth two levels here
    EXPECT_NEAR(middleGrey(s), expected, 0.002) << "convex mirror, lod " << expected * 16.0 - 1.0;
  }
  // A glass ball is a converging lens: the cone narrows towards the image of the eye behind it.
  // Fresnel reflection at normal incidence takes ((n - 1) / (n + 1))^2 at each surface; depth 2
  // leaves out the rays reflected inside the ball.
  {
    Scene s = coneScene();
    s.render.maxDepth = 2;
    s.spheres.push_back(Sphere{{0, 0, -d}, radius, 2});
    const double side = 2.0;
    addWall(s, -d - radius - behind, side, 1.0);
    ParaxialRay edge{0.0, alpha / 2.0};
    edge.travel(d - radius);
    edge.refract(1.0 / radius, 1.0, 1.5);
    edge.travel(2.0 * radius);
    edge.refract(-1.0 / radius, 1.5, 1.0);
    edge.travel(behind);
    const double f = (0.5 / 2.5) * (0.5 / 2.5);
    const double expected = (1.0 - f) * (1.0 - f) * greyForWidth(2.0 * std::abs(edge.h), side);
    const double straight = (1.0 - f) * (1.0 - f) * greyForWidth(alpha * (d + radius + behind), side);
    ASSERT_GT(straight - expected, 0.5 / 16.0); // and about a level here
    EXPECT_NEAR(middleGrey(s), expected, 0.002) << "glass ball, lod " << expected * 16.0 / 0.9216 - 1.0;
  }
}

// Mesh triangles take their curvature from their vertex normals: a tessellated ball with radial
// normals mirrors the wall as the analytic sphere does (the level within 0.06 of the sphere's; the
// facets' hit points lie up to 0.001 radius inside the sphere, and the shading normal bends the
// reflected axis a little), and the same ball shaded flat, as a flat mirror at its facet would.
TEST(RenderTexture, AMeshBallWithRadialNormalsMirrorsLikeTheSphere) {
  const double alpha = pixelAngle();
  const double d = 4.0, radius = 1.0, behind = 4.0, side = 8.0;
  const test::numerics::Mesh ball = test::numerics::icosphere(glm::dvec3(0.0, 0.0, -d), radius, 4);
  auto ballScene = [&](bool smooth) {
    Scene s = coneScene();
    s.render.maxDepth = 1;
    addWall(s, behind, side, -1.0);
    for (const auto& f : ball.faces) {
      Triangle t;
      std::array<glm::dvec3, 3> normals;
      for (int i = 0; i < 3; ++i) {
        t.v[i] = glm::dvec3(ball.vertices[f[i]]);
        normals[i] = glm::normalize(t.v[i] - glm::dvec3(0.0, 0.0, -d));
      }
      if (smooth) t.normals = normals;
      t.material = 1;
      s.triangles.push_back(t);
    }
    return s;
  };
  ParaxialRay edge{0.0, alpha / 2.0};
  edge.travel(d - radius);
  edge.reflect(1.0 / radius);
  edge.travel(d - radius + behind);
  const double sphere = greyForWidth(2.0 * edge.h, side);
  EXPECT_NEAR(middleGrey(ballScene(true)), sphere, 0.004) << "lod " << sphere * 16.0 - 1.0;
  const double flat = greyForWidth(alpha * (2.0 * (d - radius) + behind), side);
  EXPECT_NEAR(middleGrey(ballScene(false)), flat, 0.004) << "lod " << flat * 16.0 - 1.0;
}

} // namespace
} // namespace vkray

namespace vkray {
namespace {

// A 1 x 1 quad in z = 0 (x in [x0, 1], y in [-1, 1]) with uv u = (x + 1) / 2, over a white wall at
// z = -1, lit from the side so the quad's shadow falls on the wall. Its material's texture is 2 x 1
// texels: the left one red with alpha 0, the right one green with alpha 1.
Scene maskScene(double x0, bool mask) {
  Scene s;
  s.camera.position = {0.0, 0.0, 5.0};
  s.camera.lookAt = {0.0, 0.0, 0.0};
  s.camera.fovY = 50.0;
  s.render.width = 64;
  s.render.height = 48;
  s.render.maxDepth = 0;
  s.render.textureFilter = TextureFilter::Nearest;
  s.ambientLight = glm::dvec3(0.1);
  s.lights.push_back(PointLight{{2.5, 1.0, 3.0}, {1.0, 1.0, 1.0}, true});
  auto tex = std::make_shared<Texture>();
  TextureLevel l;
  l.width = 2;
  l.height = 1;
  l.texels = {glm::vec4(1, 0, 0, 0), glm::vec4(0, 1, 0, 1)};
  tex->levels = buildMipChain(l);
  tex->wrapS = tex->wrapT = TextureWrap::Clamp;
  s.textures.push_back(tex);
  Material quad;
  quad.color = glm::dvec3(1.0);
  quad.baseColorTexture = MaterialTexture{};
  if (mask) quad.alphaCutoff = 0.5;
  Material wall;
  wall.color = glm::dvec3(0.9);
  s.materials = {quad, wall};
  s.planes.push_back(Plane{{0, 0, 1}, 1.0, 1});
  auto corner = [](const glm::dvec3& q) { return glm::dvec4((q.x + 1) / 2, (1 - q.y) / 2, 0, 0); };
  const glm::dvec3 p0{x0, -1, 0}, p1{1, -1, 0}, p2{1, 1, 0}, p3{x0, 1, 0};
  // Listed the other way round, so the triangles are (p0, p1, p2) and (p0, p2, p3).
  addTexturedQuad(s, {p0, p3, p2, p1}, {corner(p0), corner(p3), corner(p2), corner(p1)}, 0);
  return s;
}

// The masked quad renders as the quad's opaque half alone, its shadow included: the cut-out half
// is gone for eye rays and shadow rays alike (only pixels on the cut line may differ).
TEST(RenderTexture, AlphaMaskCutsOutForEyeAndShadowRays) {
  Scene masked = maskScene(-1.0, true);
  EXPECT_TRUE(analyzeScene(masked, masked.render).alphaMask);
  Image cut = test::render(masked).image;
  Image half = test::render(maskScene(0.0, false)).image;
  Image whole = test::render(maskScene(-1.0, false)).image;
  int differ = 0, differWhole = 0;
  for (std::size_t i = 0; i < cut.pixels.size(); ++i) {
    differ += glm::length(cut.pixels[i] - half.pixels[i]) > 1e-5f;
    differWhole += glm::length(cut.pixels[i] - whole.pixels[i]) > 1e-5f;
  }
  EXPECT_LE(differ, 2 * 48) << "beyond the pixels on the cut line";
  EXPECT_GT(differWhole, 300) << "the cut-out half should show the wall and let light through";
  Scene opaque = maskScene(-1.0, false);
  EXPECT_FALSE(analyzeScene(opaque, opaque.render).alphaMask);
}

} // namespace
} // namespace vkray

namespace vkray {
namespace {

// A glTF triangle facing +z (x, y in [-1, 1]), with COLOR_0 (normalized unsigned bytes) or without.
fs::path colouredTriangle(bool withColors) {
  fs::path dir = fs::temp_directory_path() / "vkray-texture-colours";
  fs::create_directories(dir);
  const float pos[9] = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
  const std::uint8_t rgba[12] = {255, 128, 64, 255, 255, 128, 64, 255, 255, 128, 64, 255};
  std::ofstream(dir / "tri.bin", std::ios::binary)
      .write(reinterpret_cast<const char*>(pos), sizeof pos)
      .write(reinterpret_cast<const char*>(rgba), sizeof rgba);
  std::string attributes = withColors ? R"({"POSITION": 0, "COLOR_0": 1})" : R"({"POSITION": 0})";
  fs::path file = dir / (withColors ? "coloured.gltf" : "plain.gltf");
  std::ofstream(file) << R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
    "meshes": [{"primitives": [{"attributes": )"
                      << attributes << R"(}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}],
    "buffers": [{"uri": "tri.bin", "byteLength": 48}]})";
  return file;
}

TEST(TextureVertexColours, Color0IsReadAsNormalizedLinearRgba) {
  Scene scene;
  MeshRequest request;
  request.file = colouredTriangle(true);
  request.shownAs = "coloured.gltf";
  importMesh(request, scene);
  ASSERT_EQ(scene.triangles.size(), 1u);
  ASSERT_TRUE(scene.triangles[0].colors.has_value());
  EXPECT_DOUBLE_EQ((*scene.triangles[0].colors)[1].y, 128 / 255.0);
  EXPECT_TRUE(analyzeScene(scene, scene.render).vertexColors);
}

// Vertex colours multiply the base colour: the coloured triangle is the plain one times the colour.
TEST(RenderTextureVertexColours, MultiplyTheBaseColour) {
  auto sceneFor = [](bool colours) {
    return sceneFromJson(R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0]},
      "image": {"width": 16, "height": 16}, "ambient": [1, 1, 1],
      "lights": [{"type": "point", "position": [0.5, 0.5, 3]}],
      "objects": [{"type": "mesh", "file": ")" +
                         colouredTriangle(colours).string() + R"("}]})");
  };
  Image coloured = render(sceneFor(true)).image;
  Image plain = render(sceneFor(false)).image;
  glm::vec3 c = coloured.at(8, 9), p = plain.at(8, 9);
  ASSERT_GT(p.x, 0.05f);
  EXPECT_NEAR(c.x, p.x * 1.0f, 1e-5f);
  EXPECT_NEAR(c.y, p.y * (128 / 255.0f), 1e-5f);
  EXPECT_NEAR(c.z, p.z * (64 / 255.0f), 1e-5f);
}

} // namespace
} // namespace vkray

namespace vkray {
namespace {

// OBJ map_Kd: the MTL's image becomes the material's texture; vt's v (up) becomes uv's v (down).
TEST(TextureObj, MapKdTexturesTheMaterialWithFlippedV) {
  fs::path dir = fs::temp_directory_path() / "vkray-texture-obj";
  fs::create_directories(dir);
  fs::copy_file(fs::path(VKRAY_SOURCE_DIR) / "scenes/meshes/tiles.png", dir / "tiles.png",
                fs::copy_options::overwrite_existing);
  std::ofstream(dir / "quad.mtl") << "newmtl tiled\nKd 1 1 1\nmap_Kd tiles.png\n";
  std::ofstream(dir / "lost.mtl") << "newmtl lost\nmap_Kd nowhere.png\n";
  std::ofstream(dir / "quad.obj") << "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tiled\nf 1/1 2/2 3/3 4/4\n";
  std::ofstream(dir / "lost.obj") << "mtllib lost.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nusemtl lost\nf 1 2 3\n";
  Scene scene;
  MeshRequest request;
  request.file = dir / "quad.obj";
  request.shownAs = "quad.obj";
  importMesh(request, scene);
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(scene.textures[0]->levels[0].width, 64u);
  ASSERT_EQ(scene.triangles.size(), 2u);
  ASSERT_TRUE(scene.triangles[0].uvs.has_value());
  EXPECT_EQ((*scene.triangles[0].uvs)[0], glm::dvec4(0, 1, 0, 0)); // vt 0 0: the image's bottom-left
  EXPECT_EQ((*scene.triangles[0].uvs)[2], glm::dvec4(1, 0, 0, 0));
  EXPECT_TRUE(analyzeScene(scene, scene.render).textures);
  request.file = dir / "lost.obj";
  std::string error = importError(request.file);
  EXPECT_NE(error.find("nowhere.png: texture file not found"), std::string::npos) << error;
}

// assimp's spider: an MTL written on Windows ("map_Kd .\\SpiderTex.jpg") with five JPEG textures.
TEST(TextureObj, WindowsSeparatorsInMapKdFindTheImages) {
  const fs::path spider = "/usr/share/assimp/models/OBJ/spider.obj";
  if (!fs::exists(spider)) GTEST_SKIP() << "assimp's test models are not installed";
  Scene scene;
  MeshRequest request;
  request.file = spider;
  request.shownAs = "spider.obj";
  importMesh(request, scene);
  ASSERT_EQ(scene.textures.size(), 5u);
  for (const auto& texture : scene.textures) {
    EXPECT_EQ(texture->name.find('\\'), std::string::npos) << texture->name;
    EXPECT_GT(texture->levels[0].width, 1u) << texture->name;
  }
}

} // namespace
} // namespace vkray

namespace vkray {
namespace {

// Every bundled scene but the textured one gets the kernel without texture code: TEXTURES,
// VERTEX_COLORS and ALPHA_MASK are off (tools/compare-renders and tools/count-jit-instructions
// show those kernels unchanged); scenes/textured.json gets TEXTURES, and VERTEX_COLORS for its vase.
TEST(TextureSpecialization, OnlyTheTexturedSceneCompilesTextureCode) {
  for (const auto& entry : fs::directory_iterator(fs::path(VKRAY_SOURCE_DIR) / "scenes")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    Scene scene = loadScene(entry.path());
    Features f = analyzeScene(scene, scene.render);
    vulkan::Specialization spec =
        specializationFor(f, scene.render, RenderOptions{}, SceneShape{}, SceneMemoryUse{}, false, false);
    bool textured = entry.path().filename() == "textured.json";
    EXPECT_EQ(spec.values().at(gpu::kSpecTextures), textured ? 1u : 0u);
    // textured.json's vase is a PLY with vertex colours; no other bundled scene has any.
    EXPECT_EQ(spec.values().at(gpu::kSpecVertexColors), textured ? 1u : 0u);
    EXPECT_EQ(spec.values().at(gpu::kSpecAlphaMask), 0u);
  }
}

} // namespace
} // namespace vkray
