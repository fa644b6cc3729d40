// Scene loading: valid files produce the values they say; every class of bad input is rejected with
// one line that names the file, the JSON path and the problem.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "scene/scene_loader.h"
#include "util/error.h"

namespace vkray {
namespace {

const char* kMinimal = R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] } })";

// A scene with one of every kind, every material field and comments in both styles.
const char* kFull = R"(
// line comment
{
  /* block comment */
  "camera": { "position": [1, 2, 3], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov_y": 50 },
  "image": { "width": 320, "height": 200 },
  "background": [0.1, 0.2, 0.3],
  "ambient": "#808080",
  "render": { "max_depth": 3, "spp": 4, "bailout": 0.01, "antialiasing": "adaptive",
              "adaptive_threshold": 0.2, "numerics": "naive", "fresnel": "schlick",
              "transmissive_shadows": "opaque", "bvh": "off" },
  "materials": {
    "floor": { "color": [0.5, 0.5, 0.5], "ambient": 0.2, "diffuse": 0.7, "specular": 0.3,
               "shininess": 20, "reflection": 0.25, "checker": { "color2": [0, 0, 0], "scale": 2 } },
    "glass": { "color": [1, 1, 1], "transmission": 0.9, "ior": 1.5, "absorption": [0.1, 0, 0] }
  },
  "lights": [ { "type": "point", "position": [0, 10, 0], "color": [1, 1, 1] },
              { "position": [5, 5, 5], "shadows": false } ],
  "objects": [
    { "type": "plane", "normal": [0, 2, 0], "offset": -2, "material": "floor" },
    { "type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "glass" },
    { "type": "polygon", "vertices": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]], "material": "floor" },
    { "type": "triangle", "vertices": [[0,0,1],[1,0,1],[0,1,1]] },
    { "type": "sphere", "center": [3, 1, 0], "radius": 0.5, "material": { "color": [1, 0, 0] } }
  ]
})";

TEST(SceneLoad, MinimalSceneGetsDefaults) {
  Scene s = loadSceneFromString(kMinimal, "min.json");
  EXPECT_EQ(s.render.width, 800u);
  EXPECT_EQ(s.render.height, 600u);
  EXPECT_EQ(s.render.maxDepth, 5);
  EXPECT_EQ(s.render.spp, 1);
  EXPECT_DOUBLE_EQ(s.camera.fovY, 45.0);
  EXPECT_EQ(s.camera.up, glm::dvec3(0, 1, 0));
  EXPECT_TRUE(s.spheres.empty());
}

TEST(SceneLoad, FullSceneRoundTripsEveryField) {
  Scene s = loadSceneFromString(kFull, "full.json");
  EXPECT_EQ(s.camera.position, glm::dvec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(s.camera.fovY, 50.0);
  EXPECT_EQ(s.render.width, 320u);
  EXPECT_EQ(s.render.height, 200u);
  EXPECT_EQ(s.background, glm::dvec3(0.1, 0.2, 0.3));
  EXPECT_NEAR(s.ambientLight.x, 0.2158605, 1e-6); // #80 sRGB decoded to linear
  EXPECT_EQ(s.render.maxDepth, 3);
  EXPECT_EQ(s.render.spp, 4);
  EXPECT_DOUBLE_EQ(s.render.bailout, 0.01);
  EXPECT_EQ(s.render.antialiasing, Antialiasing::Adaptive);
  EXPECT_EQ(s.render.numerics, Numerics::Naive);
  EXPECT_EQ(s.render.fresnel, FresnelMode::Schlick);
  EXPECT_EQ(s.render.transmissiveShadows, TransmissiveShadows::Opaque);
  EXPECT_EQ(s.render.bvh, BvhMode::Off);

  ASSERT_GE(s.materials.size(), 2u);
  const Material& floor = s.materials[0];
  EXPECT_EQ(floor.name, "floor");
  EXPECT_DOUBLE_EQ(floor.reflection, 0.25);
  ASSERT_TRUE(floor.checker.has_value());
  EXPECT_DOUBLE_EQ(floor.checker->scale, 2.0);
  const Material& glass = s.materials[1];
  EXPECT_DOUBLE_EQ(glass.transmission, 0.9);
  EXPECT_DOUBLE_EQ(glass.ior, 1.5);
  EXPECT_EQ(glass.absorption, glm::dvec3(0.1, 0, 0));

  ASSERT_EQ(s.lights.size(), 2u);
  EXPECT_TRUE(s.lights[0].shadows);
  EXPECT_FALSE(s.lights[1].shadows);
  EXPECT_EQ(s.lights[1].color, glm::dvec3(1.0));

  ASSERT_EQ(s.planes.size(), 1u);
  // n = (0, 2, 0), D = -2 normalises to n = (0, 1, 0), D = -1: the plane y = 1.
  EXPECT_EQ(s.planes[0].normal, glm::dvec3(0, 1, 0));
  EXPECT_DOUBLE_EQ(s.planes[0].offset, -1.0);
  ASSERT_EQ(s.spheres.size(), 2u);
  EXPECT_EQ(s.spheres[0].material, 1u);
  EXPECT_EQ(s.materials[s.spheres[1].material].color, glm::dvec3(1, 0, 0)); // inline material
  ASSERT_EQ(s.polygons.size(), 1u);
  EXPECT_NEAR(s.polygons[0].normal.z, 1.0, 1e-12); // counter-clockwise seen from +z
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.materials[s.triangles[0].material].name, "(default)");
}

TEST(SceneLoad, PlaneThroughPoint) {
  Scene s = loadSceneFromString(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "objects": [ { "type": "plane", "normal": [0, 0, 1], "point": [0, 0, -3] } ] })",
                                "p.json");
  ASSERT_EQ(s.planes.size(), 1u);
  EXPECT_DOUBLE_EQ(s.planes[0].offset, 3.0);
}

TEST(SceneLoad, BundledScenesLoad) {
  for (const auto& entry : std::filesystem::directory_iterator(VKRAY_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(loadScene(entry.path()));
  }
}

// One row per class of bad input: the JSON (objects inserted into a valid scene) and the text the
// message must contain (file, JSON path, problem).
struct BadInput {
  const char* name;
  std::string json;
  std::string expect;
};

std::string withObjects(const std::string& objects, const std::string& extra = "") {
  return R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
              "materials": { "red": { "color": [1, 0, 0] } }, )" +
         extra + R"( "objects": [ )" + objects + "] }";
}

class SceneLoadRejects : public ::testing::TestWithParam<BadInput> {};

TEST_P(SceneLoadRejects, WithPathAndProblem) {
  const BadInput& bad = GetParam();
  try {
    loadSceneFromString(bad.json, "bad.json");
    FAIL() << "accepted: " << bad.json;
  } catch (const InputError& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("bad.json"), std::string::npos) << what;
    EXPECT_NE(what.find(bad.expect), std::string::npos) << "message: " << what << "\nexpected: " << bad.expect;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "not one line: " << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Table, SceneLoadRejects,
    ::testing::Values(
        BadInput{"Truncated", R"({ "camera": { "position": [0, 0)", "bad.json:1:"},
        BadInput{"Garbage", "\x01\x02\xff garbage", "invalid JSON"},
        BadInput{"TopLevelArray", "[1, 2]", "(top level): must be an object, got an array"},
        BadInput{"MissingCamera", "{}", "(top level): missing required key 'camera'"},
        BadInput{"MissingLookAt", R"({ "camera": { "position": [0, 0, 5] } })",
                 "camera: missing required key 'look_at'"},
        BadInput{"WrongTypeRadius", withObjects(R"({ "type": "sphere", "center": [0,0,0], "radius": "big" })"),
                 "objects[0].radius: must be a number, got a string"},
        BadInput{"NegativeRadius", withObjects(R"({ "type": "sphere", "center": [0,0,0], "radius": -1 })"),
                 "objects[0].radius: must be > 0, got -1"},
        BadInput{"ZeroRadius", withObjects(R"({ "type": "sphere", "center": [0,0,0], "radius": 0 })"),
                 "objects[0].radius: must be > 0, got 0"},
        BadInput{"NaNString", withObjects(R"({ "type": "sphere", "center": [0,"NaN",0], "radius": 1 })"),
                 "objects[0].center[1]: must be a finite number, got NaN"},
        BadInput{"InfString", withObjects(R"({ "type": "sphere", "center": [0,0,0], "radius": "Infinity" })"),
                 "objects[0].radius: must be a finite number, got Infinity"},
        BadInput{"HugeNumber", withObjects(R"({ "type": "sphere", "center": [1e400,0,0], "radius": 1 })"),
                 "number overflow parsing '1e400'"},
        BadInput{"ShortVector", withObjects(R"({ "type": "sphere", "center": [0,0], "radius": 1 })"),
                 "objects[0].center: must be an array of 3 numbers, got 2 elements"},
        BadInput{"ZeroNormal", withObjects(R"({ "type": "plane", "normal": [0,0,0], "offset": 1 })"),
                 "objects[0].normal: must not be the zero vector"},
        BadInput{"NonPlanar", withObjects(R"({ "type": "polygon", "vertices": [[0,0,0],[1,0,0],[1,1,0.5],[0,1,0]] })"),
                 "objects[0].vertices: is not planar"},
        BadInput{"NonConvex",
                 withObjects(R"({ "type": "polygon", "vertices": [[0,0,0],[2,0,0],[1,0.5,0],[2,2,0],[0,2,0]] })"),
                 "objects[0].vertices: is not convex"},
        BadInput{
            "Star",
            withObjects(
                R"({ "type": "polygon", "vertices": [[0,1,0],[0.588,-0.809,0],[-0.951,0.309,0],[0.951,0.309,0],[-0.588,-0.809,0]] })"),
            "objects[0].vertices: is not convex: its edges cross each other"},
        BadInput{"Collinear", withObjects(R"({ "type": "polygon", "vertices": [[0,0,0],[1,0,0],[2,0,0]] })"),
                 "objects[0].vertices: is degenerate"},
        BadInput{"TwoVertices", withObjects(R"({ "type": "polygon", "vertices": [[0,0,0],[1,0,0]] })"),
                 "objects[0].vertices: a polygon needs at least 3 vertices, got 2"},
        BadInput{"DegenerateTriangle", withObjects(R"({ "type": "triangle", "vertices": [[0,0,0],[1,1,1],[2,2,2]] })"),
                 "objects[0].vertices: is degenerate (zero area)"},
        BadInput{"UnknownMaterial",
                 withObjects(R"({ "type": "sphere", "center": [0,0,0], "radius": 1, "material": "gold" })"),
                 "objects[0].material: unknown material 'gold' (known: red)"},
        BadInput{"UnknownType", withObjects(R"({ "type": "cube" })"), "objects[0].type: must be one of"},
        BadInput{"UnknownKey", withObjects(R"({ "type": "sphere", "center": [0,0,0], "radus": 1 })"),
                 "objects[0]: unknown key 'radus' (did you mean 'radius'?)"},
        BadInput{"ReflectionRange", withObjects("", R"("materials": { "m": { "reflection": 1.5 } },)"),
                 "materials.m.reflection: must be in [0, 1], got 1.5"},
        BadInput{"Energy", withObjects("", R"("materials": { "m": { "reflection": 0.6, "transmission": 0.6 } },)"),
                 "must be <= 1 (energy)"},
        BadInput{"NegativeColor", withObjects("", R"("background": [0, -1, 0],)"),
                 "background[1]: colour components must be >= 0"},
        BadInput{"AbsurdWidth",
                 R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] }, "image": { "width": 100000 } })",
                 "image.width: must be in [1, 16384], got 100000"},
        BadInput{"FractionalSpp",
                 R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] }, "render": { "spp": 2.5 } })",
                 "render.spp: must be a whole number, got 2.5"},
        BadInput{"AbsurdDepth",
                 R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] }, "render": { "max_depth": 1000 } })",
                 "render.max_depth: must be in [0, 64], got 1000"},
        BadInput{"CameraAtTarget", R"({ "camera": { "position": [1,1,1], "look_at": [1,1,1] } })",
                 "camera.look_at: must differ from camera.position"},
        BadInput{"FovRange", R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0], "fov_y": 180 } })",
                 "camera.fov_y: must be in (0, 180) degrees, got 180"},
        BadInput{"LightType", withObjects("", R"("lights": [ { "type": "spot", "position": [0,0,0] } ],)"),
                 "lights[0].type: must be one of 'point', got 'spot'"},
        BadInput{"BadChoice",
                 R"({ "camera": { "position": [0,0,5], "look_at": [0,0,0] }, "render": { "numerics": "fast" } })",
                 "render.numerics: must be one of 'robust', 'naive', got 'fast'"}),
    [](const ::testing::TestParamInfo<BadInput>& info) { return std::string(info.param.name); });

TEST(SceneLoad, MissingFileAndDirectory) {
  EXPECT_THROW(loadScene("/nonexistent/scene.json"), InputError);
  try {
    loadScene(VKRAY_SOURCE_DIR "/scenes");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos);
  }
}

TEST(SceneLoad, RejectsFilesTooLargeToBeAScene) {
  std::string huge(kMaxSceneFileBytes + 1, ' ');
  try {
    loadSceneFromString(huge, "huge.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("file too large to be a scene"), std::string::npos);
  }
}

} // namespace
} // namespace vkray
