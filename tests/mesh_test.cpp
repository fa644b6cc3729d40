// Mesh import (host/scene/mesh_import*.cpp) on the fixtures in tests/data/meshes (written by
// make_fixtures.py): known OBJ, glTF and PLY files give the known triangle counts, bounds, materials,
// normals, camera and lights (MeshImport); each class of broken file is refused with a message that
// names the file and the problem (MeshImportBroken). On the GPU (RenderMesh): a closed mesh read
// from a file and seen from inside through the BVH shows no background, and the bundled mesh scene
// renders.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/bench_meshes.h"
#include "numerics_support.h"
#include "scene/features.h"
#include "scene/mesh_import.h"
#include "scene/scene_loader.h"
#include "test_support.h"
#include "util/error.h"
#include "vk/buffer.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;
using glm::dvec3;
using nlohmann::json;

const fs::path kMeshDir = fs::path(VKRAY_SOURCE_DIR) / "tests" / "data" / "meshes";

// A scene with one mesh object (given as JSON) and a camera unless the mesh imports one.
Scene loadMeshScene(const json& mesh, bool camera = true) {
  json scene = {{"objects", json::array({mesh})},
                {"materials", {{"gold", {{"color", {1.0, 0.8, 0.2}}, {"reflection", 0.5}}}}}};
  if (camera) scene["camera"] = {{"position", {0, 0, 10}}, {"look_at", {0, 0, 0}}};
  return loadSceneFromString(scene.dump(), "mesh.json", kMeshDir);
}

json meshObject(const std::string& file) {
  return {{"type", "mesh"}, {"file", file}};
}

struct Bounds {
  dvec3 min{INFINITY};
  dvec3 max{-INFINITY};
};

Bounds boundsOf(const Scene& scene) {
  Bounds b;
  for (const Triangle& t : scene.triangles) {
    for (const dvec3& v : t.v) {
      b.min = glm::min(b.min, v);
      b.max = glm::max(b.max, v);
    }
  }
  return b;
}

void expectNear(const dvec3& a, const dvec3& b, double tol = 1e-12) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

void expectBounds(const Scene& scene, const dvec3& lo, const dvec3& hi) {
  Bounds b = boundsOf(scene);
  SCOPED_TRACE("bounds");
  expectNear(b.min, lo, 1e-9);
  expectNear(b.max, hi, 1e-9);
}

const Material& materialOf(const Scene& scene, std::size_t triangle) {
  return scene.materials.at(scene.triangles.at(triangle).material);
}

// ---- OBJ -----------------------------------------------------------------------------------------

// box.obj: six quads (12 triangles) with three MTL materials, mapped as docs/meshes.md states.
TEST(MeshImport, ObjBoxHasKnownTrianglesBoundsAndMaterials) {
  Scene scene = loadMeshScene(meshObject("box.obj"));
  ASSERT_EQ(scene.triangles.size(), 12u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].triangleCount, 12u);
  EXPECT_EQ(scene.meshes[0].droppedDegenerate, 0u);
  expectBounds(scene, {-1, 0, -0.5}, {1, 2, 0.5});
  for (const Triangle& t : scene.triangles) EXPECT_FALSE(t.normals) << "no vn lines: flat shading";

  // Faces in file order: 4 quads red, 1 chrome, 1 glass.
  const Material& red = materialOf(scene, 0);
  EXPECT_EQ(red.name, (kMeshDir / "box.obj").lexically_normal().string() + ": red");
  expectNear(red.color, {0.8, 0.1, 0.1});
  EXPECT_EQ(red.diffuse, 1.0);
  EXPECT_EQ(red.specular, 0.5); // the largest Ks component
  EXPECT_EQ(red.shininess, 64.0);
  EXPECT_EQ(red.reflection, 0.0); // illum 2: highlight only
  EXPECT_EQ(red.transmission, 0.0);
  for (int i = 1; i < 8; ++i) EXPECT_EQ(scene.triangles[i].material, scene.triangles[0].material);

  const Material& chrome = materialOf(scene, 8);
  EXPECT_EQ(chrome.specular, 0.9);
  EXPECT_EQ(chrome.shininess, 200.0);
  EXPECT_EQ(chrome.reflection, 0.9); // illum 3: Ks is also a mirror
  EXPECT_EQ(scene.triangles[9].material, scene.triangles[8].material);

  const Material& glass = materialOf(scene, 10);
  EXPECT_DOUBLE_EQ(glass.transmission, 0.75); // 1 - d
  EXPECT_EQ(glass.ior, 1.5);                  // Ni
  EXPECT_DOUBLE_EQ(glass.reflection, 0.1);    // illum 6: Ks, at most 1 - transmission
  EXPECT_EQ(scene.materials.size(), 1u + 3u) << "the scene's gold, then the file's three";
}

TEST(MeshImport, MaterialOverrideReplacesTheFilesMaterials) {
  json mesh = meshObject("box.obj");
  mesh["material"] = "gold";
  Scene scene = loadMeshScene(mesh);
  ASSERT_EQ(scene.triangles.size(), 12u);
  for (const Triangle& t : scene.triangles) EXPECT_EQ(scene.materials.at(t.material).name, "gold");
  // With an override the file's materials are not read, so a broken usemtl does not matter.
  json broken = meshObject("broken/obj-unknown-material.obj");
  broken["material"] = {{"color", {0.1, 0.2, 0.3}}};
  Scene s2 = loadMeshScene(broken);
  ASSERT_EQ(s2.triangles.size(), 1u);
  expectNear(materialOf(s2, 0).color, {0.1, 0.2, 0.3});
}

// translate / rotate / scale compose as T * Rz * Ry * Rx * S; a row-major matrix gives the same.
TEST(MeshImport, TransformPlacesTheMesh) {
  json trs = meshObject("box.obj");
  trs["transform"] = {{"translate", {10, 0, 0}}, {"rotate", {0, 90, 0}}, {"scale", 2}};
  Scene a = loadMeshScene(trs);
  // Scaled: [-2,2]x[0,4]x[-1,1]; turned 90 degrees about y: (x, y, z) -> (z, y, -x); moved.
  expectBounds(a, {9, 0, -2}, {11, 4, 2});

  json mat = meshObject("box.obj");
  mat["transform"] = {{"matrix", {0, 0, 2, 10, 0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 0, 1}}};
  Scene b = loadMeshScene(mat);
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (std::size_t i = 0; i < a.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) expectNear(a.triangles[i].v[k], b.triangles[i].v[k], 1e-12);
  }

  json flat = meshObject("box.obj");
  flat["transform"] = {{"scale", {1, 0, 1}}};
  try {
    loadMeshScene(flat);
    FAIL() << "a singular transform was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("objects[0].transform: is singular"), std::string::npos) << e.what();
  }
}

// fan.obj: a pentagon becomes 3 triangles, a quad by relative indices 2; a triangle with a repeated
// vertex and a collinear one are dropped and counted.
TEST(MeshImport, PolygonsBecomeFansAndDegenerateTrianglesAreDroppedAndCounted) {
  Scene scene = loadMeshScene(meshObject("fan.obj"));
  EXPECT_EQ(scene.triangles.size(), 5u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].triangleCount, 5u);
  EXPECT_EQ(scene.meshes[0].droppedDegenerate, 2u);
  expectBounds(scene, {-1, 0, 0}, {3, 2, 1});
  // The relative-index quad sits at z = 1.
  expectNear(scene.triangles[3].v[0], {0, 0, 1});
}

// Skinning weights ("vw" lines) are not used, and tinyobjloader converts their joint ids to int
// unchecked (undefined for 1e42, a fuzz finding), so they are screened out before it reads the
// file. The screen ends lines where tinyobjloader does, at a lone CR too, so a bad position after
// one is still refused.
TEST(MeshImport, VertexWeightLinesAreIgnoredAndLoneCarriageReturnsEndLines) {
  const fs::path dir = test::scratchDir("mesh-test-weights");
  const fs::path weights = dir / "weights.obj";
  std::ofstream(weights, std::ios::binary) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvw 0 1e42 0.5\n  vw\t1 2 0.5\nf 1 2 3\n";
  Scene scene = loadMeshScene(meshObject(weights.string()));
  ASSERT_EQ(scene.triangles.size(), 1u);
  expectNear(scene.triangles[0].v[1], {1, 0, 0});

  const fs::path cr = dir / "cr.obj";
  std::ofstream(cr, std::ios::binary) << "v 0 0 0\rv nan 0 0\rv 0 1 0\rf 1 2 3\r";
  try {
    loadMeshScene(meshObject(cr.string()));
    ADD_FAILURE() << "a NaN position after a lone CR was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 2 (v line 2) is not finite (NaN or Inf)"), std::string::npos)
        << e.what();
  }
}

// box-ascii.ply and box-binary.ply (big endian, with an element vkray skips) hold box.obj's box:
// the same triangles, in the same order, all of one (the default) material.
TEST(MeshImport, PlyBoxesAreTheObjBox) {
  json objBox = meshObject("box.obj");
  objBox["material"] = "gold";
  Scene obj = loadMeshScene(objBox);
  for (const char* file : {"box-ascii.ply", "box-binary.ply"}) {
    SCOPED_TRACE(file);
    Scene ply = loadMeshScene(meshObject(file));
    ASSERT_EQ(ply.triangles.size(), obj.triangles.size());
    for (std::size_t t = 0; t < ply.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(ply.triangles[t].v[k], obj.triangles[t].v[k]);
      EXPECT_FALSE(ply.triangles[t].normals);
      EXPECT_EQ(ply.triangles[t].material, ply.triangles[0].material);
    }
  }
}

// smooth.obj has vertex normals: they become shading normals, transformed by the inverse transpose
// and turned to the geometric normal's side; "flat" ignores them; "smooth" computes them.
TEST(MeshImport, VertexNormalsGiveSmoothShading) {
  json mesh = meshObject("smooth.obj");
  mesh["transform"] = {{"scale", {1, 1, 4}}};
  Scene scene = loadMeshScene(mesh);
  ASSERT_EQ(scene.triangles.size(), 2u);
  ASSERT_TRUE(scene.triangles[0].normals);
  // vn (-0.5, -0.5, 1) under scale (1, 1, 4): inverse transpose (1, 1, 1/4), then normalised.
  expectNear((*scene.triangles[0].normals)[0], glm::normalize(dvec3(-0.5, -0.5, 0.25)), 1e-12);

  mesh["normals"] = "flat";
  for (const Triangle& t : loadMeshScene(mesh).triangles) EXPECT_FALSE(t.normals);

  json box = meshObject("box.obj");
  box["normals"] = "smooth";
  Scene smooth = loadMeshScene(box);
  for (const Triangle& t : smooth.triangles) {
    ASSERT_TRUE(t.normals);
    // Every box vertex is a corner: its area-weighted normal points along a diagonal.
    for (const dvec3& n : *t.normals) {
      EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
      EXPECT_GT(std::abs(n.x), 0.1);
      EXPECT_GT(std::abs(n.y), 0.1);
      EXPECT_GT(std::abs(n.z), 0.1);
    }
  }
}

// ---- glTF ----------------------------------------------------------------------------------------

// scene.gltf / scene.glb (the same content): a box (12 triangles, with normals) scaled and moved,
// a triangle-strip quad under a turned parent (2), a single triangle (1) and a line (skipped).
void expectKnownGltfScene(const Scene& scene) {
  ASSERT_EQ(scene.triangles.size(), 15u);
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_EQ(scene.meshes[0].droppedDegenerate, 0u);
  expectBounds(scene, {-1, -2, -1}, {2.5, 1, 1});
  // The box: base colour red, metallic 0, roughness 1 -> matte, no highlight, no mirror.
  const Material& red = materialOf(scene, 0);
  EXPECT_NE(red.name.find(": rough red"), std::string::npos) << red.name;
  expectNear(red.color, {1, 0, 0});
  EXPECT_DOUBLE_EQ(red.diffuse, 0.8);
  EXPECT_DOUBLE_EQ(red.specular, 0.0);
  EXPECT_DOUBLE_EQ(red.reflection, 0.0);
  EXPECT_DOUBLE_EQ(red.shininess, 1.0);
  EXPECT_TRUE(scene.triangles[0].normals) << "the box has NORMAL";
  // The quad: metallic 1, roughness 0 -> a perfect mirror with the sharpest highlight.
  const Material& metal = materialOf(scene, 12);
  EXPECT_DOUBLE_EQ(metal.reflection, 1.0);
  EXPECT_DOUBLE_EQ(metal.specular, 1.0);
  EXPECT_DOUBLE_EQ(metal.diffuse, 0.0);
  EXPECT_DOUBLE_EQ(metal.shininess, 1000.0);
  EXPECT_FALSE(scene.triangles[12].normals);
  // The quad lies in the plane x = -1 (translated to z = -1, then turned 90 degrees about y).
  for (int i = 12; i < 14; ++i) {
    for (const dvec3& v : scene.triangles[i].v) EXPECT_NEAR(v.x, -1.0, 1e-12);
  }
  // The triangle: KHR_materials_transmission 0.9, KHR_materials_ior 1.33, roughness 0.5.
  const Material& water = materialOf(scene, 14);
  EXPECT_DOUBLE_EQ(water.transmission, 0.9);
  EXPECT_DOUBLE_EQ(water.ior, 1.33);
  EXPECT_DOUBLE_EQ(water.specular, 0.0625);
  EXPECT_DOUBLE_EQ(water.shininess, 30.0);
  EXPECT_NEAR(water.diffuse, 0.08, 1e-12);
  EXPECT_EQ(scene.materials.size(), 1u + 3u) << "the scene's gold and three: the unused material is not added";
  EXPECT_TRUE(scene.lights.empty()) << "lights only when asked for";
}

TEST(MeshImport, GltfHasKnownTrianglesBoundsAndMaterials) {
  for (const char* file : {"scene.gltf", "scene.glb"}) {
    SCOPED_TRACE(file);
    expectKnownGltfScene(loadMeshScene(meshObject(file)));
  }
}

TEST(MeshImport, GltfCameraAndPointLightsAreImportedWhenAsked) {
  json mesh = meshObject("scene.glb");
  mesh["import_camera"] = true;
  mesh["import_lights"] = true;
  mesh["light_scale"] = 0.5;
  mesh["transform"] = {{"translate", {1, 0, 0}}};
  Scene scene = loadMeshScene(mesh, /*camera=*/false);
  expectNear(scene.camera.position, {1, 1, 5});
  expectNear(glm::normalize(scene.camera.lookAt - scene.camera.position), {0, 0, -1});
  expectNear(scene.camera.up, {0, 1, 0});
  EXPECT_NEAR(scene.camera.fovY, 0.8 * 180.0 / M_PI, 1e-9);
  ASSERT_EQ(scene.lights.size(), 1u);
  expectNear(scene.lights[0].position, {1, 3, 0});
  expectNear(scene.lights[0].color, dvec3(1, 0.5, 0.25) * 2.0 * 0.5);

  // A camera in the scene file as well: which one is meant is ambiguous.
  EXPECT_THROW(loadMeshScene(mesh, /*camera=*/true), InputError);
  // OBJ files have no cameras or lights.
  json obj = meshObject("box.obj");
  obj["import_lights"] = true;
  EXPECT_THROW(loadMeshScene(obj), InputError);
}

// ---- Broken files --------------------------------------------------------------------------------

struct BrokenMesh {
  const char* file;    // under tests/data/meshes/broken
  const char* option;  // a key set to true on the mesh object, or ""
  const char* problem; // part of the message
};

class MeshImportBroken : public ::testing::TestWithParam<BrokenMesh> {};

// Every class of damage the importers must survive is refused, never a crash or a hang, with one
// line naming the object, the file and what is wrong.
TEST_P(MeshImportBroken, IsRefusedWithAMessage) {
  const BrokenMesh& bad = GetParam();
  json mesh = meshObject(std::string("broken/") + bad.file);
  if (*bad.option) mesh[bad.option] = true;
  try {
    loadMeshScene(mesh, std::string(bad.option) != "import_camera");
    FAIL() << "accepted " << bad.file;
  } catch (const InputError& e) {
    std::string what = e.what();
    std::string file = (kMeshDir / "broken" / bad.file).lexically_normal().string();
    EXPECT_EQ(what.rfind("mesh.json: objects[0].file: " + file + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(bad.problem), std::string::npos) << what << "\nexpected: " << bad.problem;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

const BrokenMesh kBrokenMeshes[] = {
    // indices out of range
    {"obj-index-out-of-range.obj", "", "face 2: vertex index out of range (resolves to 7; the file has 3 vertices)"},
    {"gltf-index-out-of-range.gltf", "", "index 2 is 9, but there are 3 vertices"},
    // NaN / Inf vertices
    {"obj-inf-vertex.obj", "", "vertex 2 (v line 2) is not finite (NaN or Inf)"},
    {"obj-nan-vertex.obj", "", "vertex 3 (v line 3) is not finite (NaN or Inf)"},
    {"obj-not-a-number.obj", "", "vertex 3 (v line 3): '1.5.2' is not a number"},
    {"gltf-nan-position.gltf", "", "POSITION 2 is not finite (NaN or Inf)"},
    {"gltf-inf-position.gltf", "", "POSITION 1 is not finite (NaN or Inf)"},
    // missing buffers and data
    {"gltf-missing-buffer.gltf", "", "buffer"},
    {"gltf-missing-buffer-file.gltf", "", "not a valid glTF file"},
    {"gltf-accessor-without-data.gltf", "", "has no bufferView (no data)"},
    {"obj-unknown-material.obj", "", "usemtl 'velvet' is not in the material library"},
    // unsupported features, by name
    {"gltf-draco-required.gltf", "", "KHR_draco_mesh_compression"},
    {"gltf-sparse.gltf", "", "is sparse, which vkray does not support"},
    {"gltf-short-positions.gltf", "", "component type SHORT"},
    {"gltf-orthographic-camera.gltf", "import_camera", "orthographic; vkray has only perspective cameras"},
    {"gltf-directional-light.gltf", "import_lights", "directional; vkray has only point lights"},
    {"ply-point-cloud.ply", "", "has no faces (a point cloud); vkray renders surfaces"},
    {"ply-index-out-of-range.ply", "", "line 13: face 0: vertex index 5 is out of range (the file has 3 vertices)"},
};

INSTANTIATE_TEST_SUITE_P(Fixtures, MeshImportBroken, ::testing::ValuesIn(kBrokenMeshes),
                         [](const ::testing::TestParamInfo<BrokenMesh>& info) {
                           std::string name = info.param.file;
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

TEST(MeshImportBroken, EveryFixtureHasARow) {
  for (const auto& entry : fs::directory_iterator(kMeshDir / "broken")) {
    std::string name = entry.path().filename().string();
    bool listed = std::any_of(std::begin(kBrokenMeshes), std::end(kBrokenMeshes),
                              [&](const BrokenMesh& m) { return name == m.file; });
    EXPECT_TRUE(listed) << name << " has no row in kBrokenMeshes";
  }
}

// ---- GPU -----------------------------------------------------------------------------------------

// Writes a mesh as an OBJ file (shared vertices, as a modelling tool would).
fs::path writeObj(const test::numerics::Mesh& mesh, const std::string& name) {
  fs::path dir = test::scratchDir("mesh-test");
  fs::path path = dir / name;
  std::ofstream out(path);
  out.precision(17);
  for (const auto& v : mesh.vertices) out << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  for (const auto& f : mesh.faces) {
    out << 'f';
    for (std::uint32_t i : f) out << ' ' << i + 1;
    out << '\n';
  }
  return path;
}

// A colour no surface in the scene has.
const glm::vec3 kMagenta(1.0f, 0.0f, 1.0f);

// A closed mesh, read from an OBJ file, placed by a transform (rotated, scaled unevenly, moved far
// from the origin), packed relative to the camera and traced through the BVH: from inside, every
// eye ray must hit it. Odd image sizes put the centre and diagonal pixels on vertices and edges.
TEST(RenderMesh, ClosedMeshFromInsideShowsNoBackground) {
  using test::numerics::icosphere;
  fs::path file = writeObj(icosphere(dvec3(0.0), 1.0, 4), "ball.obj"); // 5120 triangles
  struct View {
    dvec3 eye, lookAt;
    double fov;
    const char* normals;
  };
  const dvec3 c(1000.0, -20.0, 300.0);
  const dvec3 rotate(17, 31, 5), scale(1.5, 1.7, 2.0);
  const glm::dmat4 world = composeTransform(c, rotate, scale);
  auto at = [&](double x, double y, double z) { return dvec3(world * glm::dvec4(x, y, z, 1.0)); };
  const View views[] = {
      {c, c + dvec3(1, 0, 0), 90, "auto"},
      {at(0.1, 0.3, -0.05), at(0.2, 1.0, 0.2), 120, "smooth"},
      {at(0, 0, 0.95), at(0, 0, 2), 150, "auto"},            // close to the wall, looking at it
      {at(-0.5, -0.6, 0.1), at(0.3, 0.2, -0.1), 60, "flat"}, // across the whole ball
  };
  for (const View& v : views) {
    json scene = {{"camera",
                   {{"position", {v.eye.x, v.eye.y, v.eye.z}},
                    {"look_at", {v.lookAt.x, v.lookAt.y, v.lookAt.z}},
                    {"fov_y", v.fov}}},
                  {"image", {{"width", 41}, {"height", 41}}},
                  {"background", {1, 0, 1}},
                  {"ambient", {1, 1, 1}},
                  {"render", {{"max_depth", 0}, {"bvh", "on"}}},
                  {"materials", {{"wall", {{"color", {0.5, 0.5, 0.5}}, {"ambient", 1}, {"diffuse", 0}}}}},
                  {"objects", json::array({{{"type", "mesh"},
                                            {"file", file.string()},
                                            {"material", "wall"},
                                            {"normals", v.normals},
                                            {"transform",
                                             {{"translate", {c.x, c.y, c.z}},
                                              {"rotate", {rotate.x, rotate.y, rotate.z}},
                                              {"scale", {scale.x, scale.y, scale.z}}}}}})}};
    Scene s = loadSceneFromString(scene.dump(), "inside.json");
    ASSERT_EQ(s.triangles.size(), 5120u);
    RenderResult r = test::render(s);
    ASSERT_TRUE(r.features.useBvh);
    int background = 0;
    for (const glm::vec3& p : r.image.pixels) background += p == kMagenta ? 1 : 0;
    EXPECT_EQ(background, 0) << "view from " << v.eye.x << "," << v.eye.y << "," << v.eye.z;
  }
  test::expectNoValidationMessages();
  fs::remove_all(file.parent_path());
}

// A light inside a closed convex mesh lights all of it: no shadow ray from the wall may find the
// wall again (offsets from the geometric normal, any-hit traversal). Shadows on and off: same image.
TEST(RenderMesh, LightInsideClosedMeshCastsNoFalseShadows) {
  using test::numerics::icosphere;
  fs::path file = writeObj(icosphere(dvec3(0.0), 1.0, 3), "ball.obj");
  auto sceneWith = [&](bool shadows) {
    json scene = {{"camera", {{"position", {0.3, -0.2, 0.1}}, {"look_at", {1, 0.2, -0.5}}, {"fov_y", 110}}},
                  {"image", {{"width", 48}, {"height", 36}}},
                  {"ambient", {0.1, 0.1, 0.1}},
                  {"render", {{"max_depth", 0}, {"bvh", "on"}}},
                  {"lights", json::array({{{"position", {-0.4, 0.3, 0.2}}, {"shadows", shadows}}})},
                  {"materials", {{"wall", {{"color", {0.9, 0.8, 0.7}}, {"diffuse", 0.9}, {"specular", 0.3}}}}},
                  {"objects", json::array({{{"type", "mesh"},
                                            {"file", file.string()},
                                            {"material", "wall"},
                                            {"normals", "smooth"},
                                            {"transform", {{"scale", {3, 2, 2.5}}}}}})}};
    return loadSceneFromString(scene.dump(), "lamp.json");
  };
  Image withShadows = test::render(sceneWith(true)).image;
  Image without = test::render(sceneWith(false)).image;
  test::expectNoValidationMessages();
  int differing = 0;
  // Shadows off compiles the shadow code out: another variant (test::variantsExact).
  for (std::size_t i = 0; i < without.pixels.size(); ++i)
    differing += !test::sameColour(withShadows.pixels[i], without.pixels[i]);
  EXPECT_EQ(differing, 0);
  fs::remove_all(file.parent_path());
}

// The bundled mesh scene loads, uses the BVH, smooth normals, shadows and reflection, and renders
// without NaN; most of the image is geometry.
TEST(RenderMesh, BundledMeshSceneRenders) {
  Scene scene = loadScene(test::scenePath("meshes.json"));
  EXPECT_GE(scene.meshes.size(), 2u);
  for (const MeshInfo& m : scene.meshes) EXPECT_GT(m.triangleCount, 0u) << m.file;
  scene.render.width = 160;
  scene.render.height = 120;
  RenderResult r = test::render(scene);
  test::expectNoValidationMessages();
  EXPECT_TRUE(r.features.useBvh);
  EXPECT_TRUE(r.features.shadows);
  EXPECT_TRUE(r.features.reflection);
  EXPECT_TRUE(r.features.smoothNormals);
  EXPECT_EQ(r.stats.nonFinite, 0u);
  EXPECT_GT(r.stats.shadow, 0u);
  EXPECT_GT(r.stats.reflection, 0u);
}

// The other scene arrays (spheres, polygons, materials, ...) are storage buffers: one larger than the
// device binds is refused before anything is allocated, with the array, the device and the limit
// named ("spheres needs 138 MiB but llvmpipe ... binds at most 128 MiB per storage buffer
// (maxStorageBufferRange)"), never bound truncated.
TEST(RenderMesh, ArraysBeyondTheStorageBufferLimitAreRefusedWithTheLimitNamed) {
  const vulkan::Context& context = test::gpu();
  vk::DeviceSize tooBig = static_cast<vk::DeviceSize>(context.info().maxStorageBufferRange) + 48;
  try {
    vulkan::Buffer buffer(context, tooBig, vk::BufferUsageFlagBits::eStorageBuffer, vulkan::MemoryUse::DeviceLocal,
                          "triangles");
    FAIL() << "a storage buffer beyond maxStorageBufferRange was created";
  } catch (const DeviceError& e) {
    std::string what = e.what();
    EXPECT_EQ(what.rfind("triangles needs ", 0), 0u) << what;
    EXPECT_NE(what.find("(maxStorageBufferRange)"), std::string::npos) << what;
    EXPECT_NE(what.find(context.info().name), std::string::npos) << what;
  }
  test::expectNoValidationMessages();
}

// The triangle, normal and BVH arrays are texel buffers: one with more texels than the device reads
// is refused the same way, naming maxTexelBufferElements, before anything is allocated.
TEST(RenderMesh, ArraysBeyondTheTexelBufferLimitAreRefusedWithTheLimitNamed) {
  const vulkan::Context& context = test::gpu();
  std::uint64_t limit = context.info().maxTexelBufferElements;
  ASSERT_GT(limit, 0u);
  try {
    vulkan::Buffer buffer(context, (limit + 1) * 16, vk::Format::eR32G32B32A32Sfloat, vulkan::MemoryUse::DeviceLocal,
                          "triangles");
    FAIL() << "a texel buffer beyond maxTexelBufferElements was created";
  } catch (const DeviceError& e) {
    std::string what = e.what();
    EXPECT_EQ(what.rfind("triangles needs " + std::to_string(limit + 1) + " texels but ", 0), 0u) << what;
    EXPECT_NE(what.find("(maxTexelBufferElements)"), std::string::npos) << what;
    EXPECT_NE(what.find(context.info().name), std::string::npos) << what;
  }
  // Within the limit, the buffer comes with its view.
  vulkan::Buffer one(context, 4, vk::Format::eR32Uint, vulkan::MemoryUse::DeviceLocal, "one reference");
  EXPECT_TRUE(one.texelView());
  test::expectNoValidationMessages();
}

// ---- Command line --------------------------------------------------------------------------------

// `render --stats` reports the BVH (build time, nodes, depth, bytes per triangle) and each mesh's
// triangle and dropped-degenerate counts. Bytes per triangle counts what the kernel reads, as
// `bench meshes` does: 48-byte triangles, the BVH, and three 16-byte shading normals for each of
// smooth.obj's 2 triangles (the only ones with vertex normals).
TEST(CliMesh, StatsReportTheBvhAndTheMeshes) {
  fs::path dir = test::scratchDir("cli-mesh");
  fs::path scene = dir / "fan.json";
  std::ofstream(scene) << R"({ "camera": { "position": [1, 1, 6], "look_at": [1, 1, 0] },
    "objects": [ { "type": "mesh", "file": ")"
                       << (kMeshDir / "fan.obj").string() << R"(" },
                 { "type": "mesh", "file": ")"
                       << (kMeshDir / "box.obj").string() << R"(" },
                 { "type": "mesh", "file": ")"
                       << (kMeshDir / "smooth.obj").string() << R"(" } ] })";
  std::string cmd = std::string("VKRAY_DEVICE=llvmpipe '") + VKRAY_BINARY + "' render '" + scene.string() + "' -o '" +
                    (dir / "out.png").string() + "' --width 32 --height 24 --bvh on --stats -q >" +
                    (dir / "out.txt").string() + " 2>&1";
  int status = std::system(cmd.c_str());
  std::ifstream in(dir / "out.txt");
  std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(status, 0) << out;
  for (const char* line :
       {"bvh build: ", "bvh nodes: ", "bvh depth: ", "bvh bytes: ", "bytes per triangle: ",
        "fan.obj: 5 triangles, 2 degenerate dropped", "box.obj: 12 triangles, 0 degenerate dropped"}) {
    EXPECT_NE(out.find(line), std::string::npos) << "missing '" << line << "' in\n" << out;
  }
  auto value = [&](const std::string& name) {
    auto at = out.find(name);
    return at == std::string::npos ? -1.0 : std::stod(out.substr(at + name.size()));
  };
  const double triangles = 5 + 12 + 2;
  const double expected = (value("bvh bytes: ") + triangles * 48 + 2 * 3 * 16) / triangles;
  EXPECT_NEAR(value("bytes per triangle: "), expected, 0.05) << out;
  fs::remove_all(dir);
}

// `bench meshes --rounds N` measures every size N times, round r of every size before round r + 1
// of any, prints each ratio's median and range over the rounds, and keeps one row per size (its
// median round) in the table and the CSV, which tools/plot-mesh-bench reads.
TEST(CliMesh, BenchRoundsAreInterleavedAndSummarised) {
  fs::path dir = test::freshScratchDir("cli-mesh-rounds");
  const std::string csv = (dir / "rounds.csv").string();
  test::CliRun run = test::runVkray(
      "bench meshes --sizes 200,2000 --width 32 --height 24 --runs 1 --rounds 3 --no-embree --csv " + csv, dir);
  ASSERT_EQ(run.exitCode, 0) << run.err;
  // Each round's lines, "round R of 3, T triangles: ...", in the order printed.
  std::vector<std::pair<int, long>> order;
  std::istringstream lines(run.out);
  for (std::string line; std::getline(lines, line);) {
    int round = 0;
    long triangles = 0;
    if (std::sscanf(line.c_str(), "round %d of 3, %ld triangles:", &round, &triangles) == 2)
      order.emplace_back(round, triangles);
  }
  ASSERT_EQ(order.size(), 6u) << run.out;
  for (std::size_t i = 0; i < order.size(); ++i) {
    EXPECT_EQ(order[i].first, static_cast<int>(i / 2) + 1) << run.out; // round 1 twice, then 2, then 3
    EXPECT_EQ(order[i].second, order[i % 2].second) << run.out;        // the small mesh, then the large
  }
  EXPECT_LT(order[0].second, order[1].second) << run.out;
  EXPECT_NE(run.out.find("over 3 rounds, median [least-largest], Mrays/s:"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("each size's median round"), std::string::npos) << run.out;
  std::istringstream in(test::slurp(csv));
  std::string line;
  int rows = 0;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("triangles,build_ms,", 0), 0u) << line;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 2); // one per size, not one per round
}

// The shadow rays' time is the median of the pairs' differences where it stands above the
// eye-only runs' spread, and 0 (printed as "below the runs' noise") where it does not: one run of
// the 10 k mesh at 160 x 120, its shadow rays mostly marked "nothing between", printed 340 Mrays/s.
TEST(BenchMeshes, ShadowTimeWithinTheRunsNoiseIsNotResolved) {
  // Eye-only runs 10 ± 0.5 ms: half their range is 0.5 ms.
  const std::vector<double> eye = {9.5, 10.0, 10.5, 10.2, 9.8};
  EXPECT_DOUBLE_EQ(resolvedShadowMs(eye, {2.0, 2.2, 1.9, 2.1, 2.4}), 2.1);
  EXPECT_DOUBLE_EQ(resolvedShadowMs(eye, {0.4, 0.6, 0.3, 0.5, 0.45}), 0.0); // median 0.45 < 0.5
  EXPECT_DOUBLE_EQ(resolvedShadowMs(eye, {0.5, 0.5, 0.5}), 0.0);            // equal to the noise
  EXPECT_DOUBLE_EQ(resolvedShadowMs(eye, {-0.2, 0.1, -0.1}), 0.0);
  // One or two runs: no spread to judge by, only a difference at or below zero is noise.
  EXPECT_DOUBLE_EQ(resolvedShadowMs({10.0}, {0.05}), 0.05);
  EXPECT_DOUBLE_EQ(resolvedShadowMs({10.0, 12.0}, {0.2, 0.4}), 0.3);
  EXPECT_DOUBLE_EQ(resolvedShadowMs({10.0}, {-0.05}), 0.0);
  EXPECT_DOUBLE_EQ(resolvedShadowMs({}, {}), 0.0);
}

} // namespace
} // namespace vkray
