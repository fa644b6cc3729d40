// Animation: interpolation through the keys (linear and Catmull-Rom, held outside), frame N equal to
// the static scene with the interpolated values written in, and the one-line errors of bad keys.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "test_support.h"
#include <nlohmann/json.hpp>

#include "scene/animation.h"
#include "scene/mesh_import.h"
#include "scene/scene_fingerprint.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace vkray {
namespace {

using glm::dvec3;

Track<double> track(std::vector<int> frames, std::vector<double> values) {
  return Track<double>{std::move(frames), std::move(values)};
}

TEST(AnimationInterpolate, LinearPassesThroughKeysAndHoldsOutside) {
  auto t = track({2, 6, 10}, {1.0, 5.0, -3.0});
  for (std::size_t i = 0; i < t.frames.size(); ++i) {
    EXPECT_EQ(interpolate(t, t.frames[i], Interpolation::Linear), t.values[i]);
  }
  EXPECT_DOUBLE_EQ(interpolate(t, 4, Interpolation::Linear), 3.0);
  EXPECT_DOUBLE_EQ(interpolate(t, 7, Interpolation::Linear), 3.0);
  EXPECT_EQ(interpolate(t, 0, Interpolation::Linear), 1.0);
  EXPECT_EQ(interpolate(t, 30, Interpolation::Linear), -3.0);
}

TEST(AnimationInterpolate, SmoothPassesThroughEveryKeyAndHoldsOutside) {
  auto t = track({0, 3, 4, 12, 20}, {0.0, 2.0, -1.0, 4.0, 4.5}); // uneven spacing
  for (std::size_t i = 0; i < t.frames.size(); ++i) {
    EXPECT_EQ(interpolate(t, t.frames[i], Interpolation::Smooth), t.values[i]) << "key " << i;
  }
  EXPECT_EQ(interpolate(t, -5, Interpolation::Smooth), 0.0);
  EXPECT_EQ(interpolate(t, 25, Interpolation::Smooth), 4.5);
  // Continuous across keys, and not the straight line between them.
  for (int k : {3, 4, 12}) {
    EXPECT_NEAR(interpolate(t, k - 1e-7, Interpolation::Smooth), interpolate(t, k + 1e-7, Interpolation::Smooth), 1e-5);
  }
  EXPECT_GT(std::abs(interpolate(t, 8, Interpolation::Smooth) - interpolate(t, 8, Interpolation::Linear)), 1e-3);
}

TEST(AnimationInterpolate, SmoothUsesCatmullRomTangentsByFrame) {
  // Middle key's tangent (p2 - p0) / (f2 - f0); the Hermite midpoint of segment [0, 2] is then
  // (p0 + p1) / 2 + h (m0 - m1) / 8.
  auto t = track({0, 2, 6}, {0.0, 2.0, 0.0});
  double m0 = (2.0 - 0.0) / 2.0; // one-sided at the first key
  double m1 = (0.0 - 0.0) / 6.0;
  EXPECT_NEAR(interpolate(t, 1, Interpolation::Smooth), 1.0 + 2.0 * (m0 - m1) / 8.0, 1e-12);
}

TEST(AnimationInterpolate, TwoKeysSmoothIsLinear) {
  auto t = track({0, 10}, {1.0, 3.0});
  for (int f = 0; f <= 10; ++f) {
    EXPECT_NEAR(interpolate(t, f, Interpolation::Smooth), interpolate(t, f, Interpolation::Linear), 1e-12);
  }
}

const char* kAnimated = R"({
  "camera": { "position": [0, 1, 6], "look_at": [0, 0.5, 0], "fov_y": 40 },
  "lights": [ { "name": "key", "position": [2, 5, 3] }, { "position": [-3, 4, 1] } ],
  "objects": [
    { "type": "plane", "name": "floor", "normal": [0, 1, 0], "offset": 0 },
    { "type": "sphere", "name": "ball", "center": [0, 0.5, 0], "radius": 0.5 },
    { "type": "sphere", "center": [1, 0.5, 0], "radius": 0.25 },
    { "type": "triangle", "name": "tri", "vertices": [[0,0,1],[1,0,1],[0,1,1]] }
  ],
  "animation": { "frames": 10, "interpolation": "smooth",
    "camera": [ { "frame": 0, "fov_y": 40 }, { "frame": 4, "position": [1, 1, 6] }, { "frame": 9, "fov_y": 30 } ],
    "objects": {
      "ball": [ { "frame": 0, "translate": [0, 0, 0] }, { "frame": 3, "translate": [1, 1, 0] },
                { "frame": 9, "translate": [2, 0, 0] } ],
      "floor": [ { "frame": 2, "translate": [0, -0.5, 0] } ],
      "tri": [ { "frame": 0, "translate": [0, 0, 0] }, { "frame": 9, "translate": [0, 0, -1] } ]
    },
    "lights": { "key": [ { "frame": 0, "position": [2, 5, 3] }, { "frame": 9, "position": [-2, 5, 3] } ] }
  }
})";

nlohmann::json vec(const dvec3& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

TEST(AnimationFrame, EqualsTheStaticSceneWithTheValuesWrittenIn) {
  Scene scene = loadSceneFromString(kAnimated, "anim.json");
  ASSERT_TRUE(scene.animation);
  const Animation& a = *scene.animation;
  for (int f : {0, 1, 3, 5, 9}) {
    // The oracle: the same file without its animation, the interpolated values written into the JSON.
    nlohmann::json doc = nlohmann::json::parse(kAnimated, nullptr, true, true);
    doc.erase("animation");
    const Interpolation m = a.interpolation;
    doc["camera"]["position"] = vec(interpolate(a.camera.position, f, m));
    doc["camera"]["fov_y"] = interpolate(a.camera.fovY, f, m);
    dvec3 ball = dvec3(0, 0.5, 0) + interpolate(a.objects[0].translate, f, m);
    doc["objects"][1]["center"] = vec(ball);
    doc["objects"][0]["offset"] = -interpolate(a.objects[1].translate, f, m).y;
    dvec3 dz = interpolate(a.objects[2].translate, f, m);
    doc["objects"][3]["vertices"] = {vec(dvec3(0, 0, 1) + dz), vec(dvec3(1, 0, 1) + dz), vec(dvec3(0, 1, 1) + dz)};
    doc["lights"][0]["position"] = vec(interpolate(a.lights[0].position, f, m));
    Scene expected = loadSceneFromString(doc.dump(), "static.json");

    Scene got = sceneAtFrame(scene, a, f);
    EXPECT_EQ(sceneFingerprint(got, f), sceneFingerprint(expected, f)) << "frame " << f;
    EXPECT_EQ(got.spheres[1].center, expected.spheres[1].center); // the unnamed sphere stays
  }
  // Keys hold: the ball's last key, and the floor's only key from frame 0 on.
  Scene last = sceneAtFrame(scene, a, 9);
  EXPECT_EQ(last.spheres[0].center, dvec3(2, 0.5, 0));
  EXPECT_EQ(sceneAtFrame(scene, a, 0).planes[0].offset, 0.5);
  EXPECT_EQ(sceneAtFrame(scene, a, 9).camera.fovY, 30.0);
  EXPECT_EQ(sceneAtFrame(scene, a, 0).camera.position, dvec3(1, 1, 6)); // before the first position key
}

TEST(AnimationFrame, DistinctFramesHaveDistinctFingerprints) {
  Scene scene = loadSceneFromString(kAnimated, "anim.json");
  EXPECT_NE(sceneFingerprint(sceneAtFrame(scene, *scene.animation, 2), 2),
            sceneFingerprint(sceneAtFrame(scene, *scene.animation, 3), 3));
  EXPECT_THROW(sceneAtFrame(scene, *scene.animation, 10), InputError);
}

TEST(AnimationFrame, AnAnimatedSeedGivesEachFrameItsOwn) {
  // Without animated_seed every frame samples with render.seed; with it, frame N with seed + N
  // (wrapping), so tiles of one frame still agree and two frames do not share a noise pattern.
  nlohmann::json doc = nlohmann::json::parse(kAnimated, nullptr, true, true);
  doc["render"]["seed"] = 4294967290u;
  Scene still = loadSceneFromString(doc.dump(), "anim.json");
  for (int f : {0, 5, 9}) EXPECT_EQ(sceneAtFrame(still, *still.animation, f).render.seed, 4294967290u);
  doc["animation"]["animated_seed"] = true;
  Scene moving = loadSceneFromString(doc.dump(), "anim.json");
  EXPECT_EQ(sceneAtFrame(moving, *moving.animation, 0).render.seed, 4294967290u);
  EXPECT_EQ(sceneAtFrame(moving, *moving.animation, 5).render.seed, 4294967295u);
  EXPECT_EQ(sceneAtFrame(moving, *moving.animation, 9).render.seed, 3u);
  doc["animation"]["animated_seed"] = 1;
  EXPECT_THROW(loadSceneFromString(doc.dump(), "anim.json"), InputError);
}

// A mesh rotated and scaled about its centre equals the mesh placed by the composed matrix.
TEST(AnimationFrame, MeshRotateScaleAboutItsCentre) {
  namespace fs = std::filesystem;
  fs::path dir = test::scratchDir("anim");
  std::ofstream(dir / "quad.obj")
      << "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n";
  std::string base = R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "objects": [ { "type": "mesh", "name": "quad", "file": "quad.obj", "transform": { "translate": [1, 0, 0] } } ])";
  std::string animated = base + R"(, "animation": { "frames": 5, "objects": { "quad": [
      { "frame": 0, "translate": [0, 0, 0], "rotate": [0, 0, 0], "scale": 1 },
      { "frame": 4, "translate": [0, 2, 0], "rotate": [0, 0, 90], "scale": [2, 1, 1] } ] } } })";
  Scene scene = loadSceneFromString(animated, "mesh.json", dir);
  Scene got = sceneAtFrame(scene, *scene.animation, 2);

  const dvec3 centre(2.0, 0.5, 0.0); // of the placed quad's bounds
  glm::dmat4 m = composeTransform(centre + dvec3(0, 1, 0), dvec3(0, 0, 45), dvec3(1.5, 1, 1)) *
                 glm::translate(glm::dmat4(1.0), -centre) * composeTransform(dvec3(1, 0, 0), dvec3(0), dvec3(1));
  nlohmann::json matrix = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) matrix.push_back(m[c][r]);
  }
  nlohmann::json doc = nlohmann::json::parse(base + "}");
  doc["objects"][0]["transform"] = {{"matrix", matrix}};
  Scene expected = loadSceneFromString(doc.dump(), "static.json", dir);
  ASSERT_EQ(got.triangles.size(), expected.triangles.size());
  for (std::size_t i = 0; i < got.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(glm::length(got.triangles[i].v[k] - expected.triangles[i].v[k]), 1e-12);
      ASSERT_TRUE(got.triangles[i].normals && expected.triangles[i].normals);
      EXPECT_LT(glm::length((*got.triangles[i].normals)[k] - (*expected.triangles[i].normals)[k]), 1e-12);
    }
  }
  fs::remove_all(dir);
}

struct BadAnimation {
  const char* name;
  const char* animation;
  const char* expect;
};

class AnimationRejects : public ::testing::TestWithParam<BadAnimation> {};

TEST_P(AnimationRejects, OneLineWithThePath) {
  std::string json = R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] },
    "lights": [ { "name": "key", "position": [1, 1, 1] } ],
    "objects": [ { "type": "sphere", "name": "ball", "center": [0, 0, 0], "radius": 1 } ],
    "animation": )" + std::string(GetParam().animation) +
                     "}";
  try {
    loadSceneFromString(json, "bad.json");
    FAIL() << "accepted " << GetParam().animation;
  } catch (const InputError& e) {
    std::string what = e.what();
    EXPECT_NE(what.find(GetParam().expect), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Animation, AnimationRejects,
    ::testing::Values(
        BadAnimation{"MissingFrames", R"({ "fps": 24 })", "bad.json: animation: missing required key 'frames'"},
        BadAnimation{"UnknownObject",
                     R"({ "frames": 4, "objects": { "bal": [ { "frame": 0, "translate": [0,0,0] } ] } })",
                     "animation.objects.bal: no object is named 'bal' (named objects: ball)"},
        BadAnimation{"UnknownLight",
                     R"({ "frames": 4, "lights": { "fill": [ { "frame": 0, "position": [0,0,0] } ] } })",
                     "animation.lights.fill: no light is named 'fill'"},
        BadAnimation{
            "KeyOutOfRange",
            R"({ "frames": 4, "objects": { "ball": [ { "frame": 0, "translate": [0,0,0] }, { "frame": 4, "translate": [1,0,0] } ] } })",
            "animation.objects.ball[1].frame: must be in [0, 3], got 4"},
        BadAnimation{"KeysUnordered",
                     R"({ "frames": 9, "camera": [ { "frame": 5, "fov_y": 30 }, { "frame": 2, "fov_y": 40 } ] })",
                     "animation.camera[1].frame: keys must be in increasing frame order"},
        BadAnimation{"RotateASphere",
                     R"({ "frames": 4, "objects": { "ball": [ { "frame": 0, "rotate": [0,0,1] } ] } })",
                     "animation.objects.ball[0].rotate: animates meshes only; 'ball' is a sphere"},
        BadAnimation{"UnknownKey", R"({ "frames": 4, "camera": [ { "frame": 0, "fovy": 30 } ] })",
                     "animation.camera[0]: unknown key 'fovy'"},
        BadAnimation{"BadInterpolation", R"({ "frames": 4, "interpolation": "cubic" })",
                     "animation.interpolation: must be one of"}),
    [](const auto& info) { return std::string(info.param.name); });

} // namespace
} // namespace vkray
