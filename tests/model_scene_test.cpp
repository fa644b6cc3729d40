// Model files as scenes (host only): the fitted camera provably frames the model, a model file gets
// its own camera and lights or defaults, imported materials follow the ambient light; and the
// refusals of real files (assimp's test models) and of numbers past float32, each with its reason.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "test_support.h"
#include <nlohmann/json.hpp>

#include "scene/model_scene.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;
using glm::dvec3;
using json = nlohmann::json;

const fs::path kMeshDir = fs::path(VKRAY_SOURCE_DIR) / "tests" / "data" / "meshes";
const fs::path kAssimp = "/usr/share/assimp/models";

// Where p lands on the image: x and y in [-1, 1] across the image when it is in frame, by the
// pinhole model written out here independently of the renderer's camera code.
glm::dvec2 project(const Camera& c, double aspect, const dvec3& p, double& depth) {
  dvec3 forward = glm::normalize(c.lookAt - c.position);
  dvec3 right = glm::normalize(glm::cross(forward, c.up));
  dvec3 up = glm::cross(right, forward);
  dvec3 d = p - c.position;
  depth = glm::dot(d, forward);
  double tanHalf = std::tan(glm::radians(c.fovY) * 0.5);
  return {glm::dot(d, right) / depth / (tanHalf * aspect), glm::dot(d, up) / depth / tanHalf};
}

// Every corner of the box in front of the camera and inside the image less the margin.
void expectFramed(const Camera& camera, double aspect, const Bounds& b, const std::string& what) {
  for (int i = 0; i < 8; ++i) {
    dvec3 corner((i & 1) ? b.hi.x : b.lo.x, (i & 2) ? b.hi.y : b.lo.y, (i & 4) ? b.hi.z : b.lo.z);
    double depth = 0.0;
    glm::dvec2 q = project(camera, aspect, corner, depth);
    EXPECT_GT(depth, 0.0) << what << ", corner " << i;
    EXPECT_LE(std::abs(q.x), 1.0 - kFitMargin + 1e-9) << what << ", corner " << i;
    EXPECT_LE(std::abs(q.y), 1.0 - kFitMargin + 1e-9) << what << ", corner " << i;
  }
}

TEST(ModelScene, FittedCameraHasEveryCornerOfTheBoundsInFrameWithTheMargin) {
  const Bounds boxes[] = {
      {dvec3(-0.5), dvec3(0.5)},
      {dvec3(10.0, -3.0, 100.0), dvec3(10.5, 40.0, 100.2)}, // tall and thin, far from the origin
      {dvec3(-1000.0, 0.0, -1.0), dvec3(1000.0, 1.0, 1.0)}, // long and flat
  };
  const dvec3 froms[] = {kThreeQuarterView, dvec3(0, 0, 1), dvec3(-1, 0.2, -0.3), dvec3(1, 1, 0)};
  for (const Bounds& b : boxes) {
    for (const dvec3& from : froms) {
      for (double fov : {10.0, 40.0, 90.0}) {
        for (double aspect : {4.0 / 3.0, 1.0, 0.5, 3.0}) {
          Camera c = fitCamera(b, from, fov, aspect, "test");
          expectFramed(c, aspect, b, "fov " + std::to_string(fov) + ", aspect " + std::to_string(aspect));
        }
      }
    }
  }
}

TEST(ModelScene, FittingNothingIsAnError) {
  try {
    fitCamera(Bounds{}, kThreeQuarterView, 40.0, 1.0, "empty.json: camera.fit");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.json: camera.fit: nothing to frame"), std::string::npos) << e.what();
  }
}

TEST(ModelScene, AnObjFileIsASceneWithAFittedCameraAndDefaultLights) {
  Scene scene = loadScene(kMeshDir / "box.obj");
  ASSERT_EQ(scene.meshes.size(), 1u);
  EXPECT_GT(scene.triangles.size(), 0u);
  ASSERT_TRUE(scene.fitFrom);
  EXPECT_EQ(scene.camera.fovY, 40.0);
  expectFramed(scene.camera, double(scene.render.width) / scene.render.height, sceneBounds(scene), "box.obj");
  EXPECT_EQ(scene.lights.size(), 2u); // key and fill
  EXPECT_GT(scene.ambientLight.x, 0.0);
  EXPECT_TRUE(scene.planes.empty());

  // Taller than wide: refitting keeps the model in frame at the new aspect.
  scene.render.width = 200;
  scene.render.height = 800;
  refitCamera(scene);
  expectFramed(scene.camera, 0.25, sceneBounds(scene), "box.obj, refitted to 200x800");
}

TEST(ModelScene, AGltfFileBringsItsCameraAndLights) {
  Scene scene = loadScene(kMeshDir / "scene.gltf");
  EXPECT_FALSE(scene.fitFrom);
  EXPECT_NEAR(scene.camera.position.y, 1.0, 1e-12); // the file's camera node is at (0, 1, 5)
  EXPECT_NEAR(scene.camera.position.z, 5.0, 1e-12);
  EXPECT_EQ(scene.lights.size(), 1u); // its point light, no defaults
}

TEST(ModelScene, FloorAndBackgroundFromTheOptions) {
  ModelSceneOptions o;
  o.floor = true;
  o.background = dvec3(0.5, 0.25, 0.0);
  Scene scene = loadScene(kMeshDir / "box.obj", o);
  ASSERT_EQ(scene.planes.size(), 1u);
  Bounds b = sceneBounds(scene);
  double floorY = -scene.planes[0].offset; // normal +y: y + D = 0
  EXPECT_LT(floorY, b.lo.y);
  EXPECT_GT(floorY, b.lo.y - 0.01 * b.radius());
  EXPECT_EQ(scene.background, o.background);
}

TEST(ModelScene, ImportedMaterialsReflectAmbientLightAsTheyReflectDiffuseLight) {
  Scene scene = loadScene(kMeshDir / "box.obj");
  for (const Material& m : scene.materials) EXPECT_EQ(m.ambient, m.diffuse) << m.name;
  Scene gltf = loadScene(kMeshDir / "scene.gltf");
  for (const Material& m : gltf.materials) EXPECT_EQ(m.ambient, m.diffuse) << m.name;
}

TEST(ModelScene, SceneFileCameraFitFramesEveryObject) {
  const char* text = R"({
    "camera": { "fit": true, "from": [0, 0.3, 1], "fov_y": 30 },
    "image": { "width": 300, "height": 100 },
    "objects": [
      { "type": "sphere", "center": [0, 0, 0], "radius": 1 },
      { "type": "sphere", "center": [8, 2, -3], "radius": 0.5 },
      { "type": "plane", "normal": [0, 1, 0], "offset": 1 }
    ] })";
  Scene scene = loadSceneFromString(text, "fit.json");
  ASSERT_TRUE(scene.fitFrom);
  EXPECT_EQ(scene.camera.fovY, 30.0);
  Bounds b = sceneBounds(scene);
  EXPECT_EQ(b.hi.x, 8.5);
  expectFramed(scene.camera, 3.0, b, "fit.json");
  // Direction only: the camera looks along -from at the centre.
  dvec3 back = glm::normalize(scene.camera.position - scene.camera.lookAt);
  EXPECT_NEAR(glm::dot(back, glm::normalize(dvec3(0, 0.3, 1))), 1.0, 1e-12);
}

TEST(ModelScene, SceneFileCameraFitRefusesAPositionAndEmptyScenes) {
  auto message = [](const std::string& text) -> std::string {
    try {
      loadSceneFromString(text, "fit.json");
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(
      message(
          R"({"camera": {"fit": true, "position": [0,0,5]}, "objects": [{"type":"sphere","center":[0,0,0],"radius":1}]})")
          .find("fit.json: camera.position: give either camera.fit or camera.position"),
      std::string::npos);
  EXPECT_NE(message(R"({"camera": {"fit": true}, "objects": [{"type":"plane","normal":[0,1,0]}]})")
                .find("fit.json: camera.fit: nothing to frame"),
            std::string::npos);
}

// ---- Refusals of real files (Debian's assimp-testmodels) ------------------------------------------

std::string refusal(const fs::path& file) {
  try {
    loadScene(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

#define REQUIRE_ASSIMP_MODELS()                                                                                        \
  if (!fs::exists(kAssimp)) GTEST_SKIP() << kAssimp << " is absent (apt-get install assimp-testmodels)"

TEST(HardeningAssimp, WrongJsonTypeIsNamedByItsPath) {
  REQUIRE_ASSIMP_MODELS();
  fs::path f = kAssimp / "glTF2/wrongTypes/badArray.gltf";
  EXPECT_EQ(refusal(f), f.string() + ": meshes[0].primitives: must be an array, got an object");
}

TEST(HardeningAssimp, Utf16TextIsNamed) {
  REQUIRE_ASSIMP_MODELS();
  fs::path f = kAssimp / "OBJ/box_UTF16BE.obj";
  EXPECT_NE(refusal(f).find(f.string() + ": is UTF-16 (big endian) text"), std::string::npos) << refusal(f);
}

TEST(HardeningAssimp, PointCloudHasNoTriangles) {
  REQUIRE_ASSIMP_MODELS();
  fs::path f = kAssimp / "OBJ/point_cloud.obj";
  std::string what = refusal(f);
  EXPECT_NE(what.find(f.string() + ": no triangles: the file has 3 vertices but no faces"), std::string::npos) << what;
}

TEST(HardeningAssimp, PointsAndLinesOnlyAreNotSurfaces) {
  REQUIRE_ASSIMP_MODELS();
  fs::path f = kAssimp / "glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf";
  std::string what = refusal(f);
  EXPECT_NE(what.find("no triangles: its primitives are points or lines only (mode 0)"), std::string::npos) << what;
}

TEST(HardeningAssimp, DracoIsRefusedByName) {
  REQUIRE_ASSIMP_MODELS();
  fs::path f = kAssimp / "glTF2/draco/2CylinderEngine.gltf";
  std::string what = refusal(f);
  EXPECT_NE(what.find(f.string() + ": extensionsRequired[0]: the file requires KHR_draco_mesh_compression"),
            std::string::npos)
      << what;
}

TEST(HardeningAssimp, AnyUnsupportedRequiredExtensionIsRefusedByName) {
  REQUIRE_ASSIMP_MODELS();
  fs::path f = kAssimp / "glTF2/BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf";
  std::string what = refusal(f);
  EXPECT_NE(what.find("requires extension 'KHR_technique_webgl', which vkray does not support"), std::string::npos)
      << what;
}

// glTF 1.0 shares the extension but not the schema: it is refused by its version, not by the first
// member whose type changed in 2.0 (its `scene` is a string), and so is its binary form.
TEST(HardeningAssimp, GltfOneIsRefusedByItsVersion) {
  REQUIRE_ASSIMP_MODELS();
  for (const char* name : {"glTF/TwoBoxes/TwoBoxes.gltf", "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf"}) {
    fs::path f = kAssimp / name;
    std::string what = refusal(f);
    EXPECT_NE(what.find(f.string() + ": asset.version: is '1"), std::string::npos) << what;
    EXPECT_NE(what.find("a glTF 1.0 file; vkray reads glTF 2.0"), std::string::npos) << what;
  }
  fs::path glb = kAssimp / "glTF/BoxTextured-glTF-Binary/BoxTextured.glb";
  std::string what = refusal(glb);
  EXPECT_NE(what.find(glb.string() + ": is binary glTF 1.0 (its header says version 1); vkray reads glTF 2.0"),
            std::string::npos)
      << what;
}

// A model in a format vkray does not read, given where a scene or model goes, is named as such, not
// as a JSON syntax error at its first byte; a scene file without the .json extension still loads.
TEST(HardeningAssimp, ForeignModelFormatIsNamedNotParsedAsJson) {
  REQUIRE_ASSIMP_MODELS();
  for (const char* name : {"STL/Spider_ascii.stl", "FBX/box.fbx"}) {
    fs::path f = kAssimp / name;
    EXPECT_EQ(refusal(f), f.string() + ": neither a JSON scene (it does not begin with '{') nor a model vkray reads "
                                       "(.obj, .gltf, .glb, .ply); convert other model formats, e.g. with assimp "
                                       "export (Debian's assimp-utils)");
  }
}

TEST(HardeningSceneFile, SceneWithoutTheJsonExtensionLoads) {
  fs::path dir = test::scratchDir("model-test");
  fs::path f = dir / "scene";
  std::ofstream(f) << "\xEF\xBB\xBF // a comment first\n/* and another */ { \"camera\": { \"position\": [0, 0, 5], "
                      "\"look_at\": [0, 0, 0] }, \"objects\": [] }";
  std::string what = refusal(f);
  fs::path broken = dir / "scene.txt";
  std::ofstream(broken) << "{ \"camera\": ";
  std::string brokenWhat = refusal(broken);
  fs::remove_all(dir);
  EXPECT_EQ(what, "accepted");
  // A file that opens an object is a scene with a mistake in it: the parser says where.
  EXPECT_NE(brokenWhat.find("scene.txt:1:"), std::string::npos) << brokenWhat;
  EXPECT_NE(brokenWhat.find("invalid JSON"), std::string::npos) << brokenWhat;
}

// A Draco primitive in a file that only lists Draco as used (not required) is refused at the primitive.
TEST(HardeningGltf, DracoPrimitiveIsRefusedAtItsPath) {
  fs::path dir = test::scratchDir("model-test");
  fs::path f = dir / "draco-used.gltf";
  std::ofstream(f) << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_draco_mesh_compression"],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0},
                "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}}]}]})";
  std::string what = refusal(f);
  fs::remove_all(dir);
  EXPECT_NE(what.find("meshes[0].primitives[0].extensions.KHR_draco_mesh_compression: the primitive is "
                      "Draco-compressed"),
            std::string::npos)
      << what;
}

// ---- Numbers in float32's range ------------------------------------------------------------------

std::string sceneRefusal(const std::string& objects, const std::string& extra = "") {
  std::string text = R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, )" + extra +
                     R"("materials": {"glass": {"transmission": 1, "ior": 1.5}}, "objects": [)" + objects + "]}";
  try {
    loadSceneFromString(text, "range.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(HardeningFloat32, NumbersPastFloat32AreRefusedWithTheirPath) {
  EXPECT_EQ(sceneRefusal(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e39})"),
            "range.json: objects[0].radius: must be within float32's range (+-3.40282347e+38; the GPU computes in "
            "float32), got 1e+39");
  std::string glass = sceneRefusal(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e308, "material": "glass"})");
  EXPECT_NE(glass.find("range.json: objects[0].radius: must be within float32's range"), std::string::npos) << glass;
  std::string colour =
      sceneRefusal(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1})", R"("background": [0, 5e38, 0], )");
  EXPECT_NE(colour.find("range.json: background[1]: must be within float32's range"), std::string::npos) << colour;
}

TEST(HardeningFloat32, FiniteValuesWhoseSquaresOverflowAreRefusedWithTheReason) {
  std::string radius = sceneRefusal(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e20, "material": "glass"})");
  EXPECT_NE(radius.find("range.json: objects[0].radius: must be at most 1e+18, got 1e+20: the kernel squares the "
                        "radius (radius^2 in the sphere test) in float32"),
            std::string::npos)
      << radius;
  std::string center = sceneRefusal(R"({"type": "sphere", "center": [0, 3e19, 0], "radius": 1})");
  EXPECT_NE(center.find("range.json: objects[0].center[1]: must be within +-1e+18, got 3e+19"), std::string::npos)
      << center;
}

TEST(HardeningFloat32, JsonNumberOverflowNamesItsLineAndColumn) {
  std::string text = "{\n  \"camera\": { \"position\": [0, 0, 5], \"look_at\": [0, 0, 0] },\n"
                     "  \"objects\": [ { \"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1e999 } ]\n}";
  try {
    loadSceneFromString(text, "big.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "big.json:3:67: invalid JSON: number overflow parsing '1e999'");
  }
}

TEST(HardeningFloat32, MeshVertexPastFloat32IsNamedByFileAndVertex) {
  fs::path dir = test::scratchDir("model-test");
  fs::path f = dir / "far.obj";
  std::ofstream(f) << "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n";
  std::string what = refusal(f);
  fs::path g = dir / "far2.obj";
  std::ofstream(g) << "v 0 0 0\nv 1 0 0\nv 0 1 5e20\nf 1 2 3\n";
  std::string what2 = refusal(g);
  fs::remove_all(dir);
  EXPECT_EQ(what, f.string() + ": vertex 2 (used by face 0) has y = 1e+39, outside float32's range (+-3.40282347e+38)");
  EXPECT_NE(what2.find(g.string() + ": vertex 2 (used by face 0) has z = 5e+20, past +-1e+18"), std::string::npos)
      << what2;
}

TEST(HardeningFloat32, MeshMaterialPastFloat32IsNamed) {
  fs::path dir = test::scratchDir("model-test");
  std::ofstream(dir / "hot.mtl") << "newmtl hot\nKd 1e39 0 0\n";
  fs::path f = dir / "hot.obj";
  std::ofstream(f) << "mtllib hot.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl hot\nf 1 2 3\n";
  std::string what = refusal(f);
  fs::remove_all(dir);
  EXPECT_EQ(what, f.string() + ": material '" + f.string() +
                      ": hot' has 1e+39, outside float32's range (+-3.40282347e+38; the GPU computes in float32)");
}

TEST(HardeningPolygon, NonPlanarPolygonNamesTheVertexOffThePlane) {
  for (int lifted = 0; lifted < 4; ++lifted) {
    json verts = json::array({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
    verts[static_cast<std::size_t>(lifted)][2] = 0.25;
    json object = {{"type", "polygon"}, {"vertices", verts}};
    std::string what = sceneRefusal(object.dump());
    std::string expected = "objects[0].vertices: is not planar: vertex "; // appended: GCC 12 misfires on a + chain
    expected += std::to_string(lifted);
    expected += " is";
    EXPECT_NE(what.find(expected), std::string::npos) << what;
  }
  // A pentagon with its fourth vertex lifted.
  json verts = json::array({{0, 0, 0}, {2, 0, 0}, {3, 1.5, 0}, {1, 3, 0.4}, {-1, 1.5, 0}});
  std::string what = sceneRefusal(json({{"type", "polygon"}, {"vertices", verts}}).dump());
  EXPECT_NE(what.find("is not planar: vertex 3 is"), std::string::npos) << what;
}

} // namespace
} // namespace vkray
