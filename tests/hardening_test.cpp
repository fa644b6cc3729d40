// Hardening, in the test process. Malformed scenes generated from one valid scene that has every
// field (non-finite numbers, wrong types and empty containers at each, every truncation, random
// bytes, deep nesting, ten million objects) and the malformed meshes in tests/data/malformed are
// refused with one line that names the place and the problem; fuzz findings stay fixed; stale
// temporary outputs are cleaned up; a lost device is reported as such.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"
#include <nlohmann/json.hpp>

#include "image/image_io.h"
#include "render/gpu_scene.h"
#include "scene/features.h"
#include "scene/mesh_import.h"
#include "scene/scene_limits.h"
#include "scene/scene_loader.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "vk/context.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kMalformedDir = VKRAY_SOURCE_DIR "/tests/data/malformed";

// Valid, and with every kind of object and every numeric field of the format (meshes included),
// so that breaking any one value in it must be reported at that value.
const char* kEverything = R"({
  "description": "every field",
  "camera": { "position": [1, 2, 8], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov_y": 50 },
  "image": { "width": 32, "height": 24, "background": [0.1, 0.2, 0.3] },
  "ambient": "#202020",
  "render": { "max_depth": 3, "spp": 4, "bailout": 0.01, "antialiasing": "adaptive", "adaptive_threshold": 0.2,
              "numerics": "robust", "fresnel": "exact", "transmissive_shadows": "attenuated", "bvh": "auto" },
  "materials": {
    "floor": { "color": [0.5, 0.5, 0.5], "ambient": 0.2, "diffuse": 0.7, "specular": 0.3, "shininess": 20,
               "reflection": 0.25, "checker": { "color2": [0, 0, 0], "scale": 2 } },
    "glass": { "color": [1, 1, 1], "transmission": 0.9, "ior": 1.5, "absorption": [0.1, 0, 0] }
  },
  "lights": [ { "type": "point", "position": [0, 10, 0], "color": [1, 1, 1], "shadows": true } ],
  "objects": [
    { "type": "plane", "normal": [0, 1, 0], "offset": -2, "material": "floor" },
    { "type": "plane", "normal": [1, 0, 0], "point": [-5, 0, 0] },
    { "type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "glass" },
    { "type": "polygon", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "material": "floor" },
    { "type": "triangle", "vertices": [[0, 0, 1], [1, 0, 1], [0, 1, 1]], "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1]] },
    { "type": "sphere", "center": [3, 1, 0], "radius": 0.5, "material": { "color": [1, 0, 0], "specular": 0.5 } },
    { "type": "mesh", "file": "tetra.obj", "normals": "smooth",
      "transform": { "translate": [0, 0, -3], "rotate": [0, 45, 0], "scale": 0.5 } },
    { "type": "mesh", "file": "triangle.gltf", "material": "floor", "light_scale": 2,
      "transform": { "matrix": [1, 0, 0, 2, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] } }
  ]
})";

const char* kTetraObj = R"(# a tetrahedron
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
)";

// One triangle; positions and uint16 indices in an embedded base64 buffer.
const char* kTriangleGltf = R"({
  "asset": { "version": "2.0" }, "scene": 0, "scenes": [ { "nodes": [0] } ], "nodes": [ { "mesh": 0 } ],
  "meshes": [ { "primitives": [ { "attributes": { "POSITION": 0 }, "indices": 1 } ] } ],
  "buffers": [ { "byteLength": 44,
                 "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA=" } ],
  "bufferViews": [ { "buffer": 0, "byteOffset": 0, "byteLength": 36 }, { "buffer": 0, "byteOffset": 36, "byteLength": 6 } ],
  "accessors": [ { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
                 { "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" } ]
})";

// True if the bytes are well-formed UTF-8 (continuation bytes where the lead byte says; the
// finer overlong and surrogate rules are the loader's to keep, this checks the structure).
bool structurallyUtf8(const std::string& s) {
  for (std::size_t i = 0; i < s.size(); ++i) {
    auto b = static_cast<unsigned char>(s[i]);
    std::size_t n = b < 0x80                 ? 0
                    : b >= 0xc2 && b <= 0xdf ? 1
                    : b >= 0xe0 && b <= 0xef ? 2
                    : b >= 0xf0 && b <= 0xf4 ? 3
                                             : 9;
    if (n == 9 || i + n >= s.size() + (n == 0)) return false; // an invalid lead, or cut short
    for (std::size_t k = 1; k <= n; ++k) {
      if ((static_cast<unsigned char>(s[i + k]) & 0xc0) != 0x80) return false;
    }
    i += n;
  }
  return true;
}

// True if the message is one printable line: no newline or other control character, and text
// (UTF-8) a terminal shows as it is, even when the input was binary garbage.
bool oneLine(const std::string& s) {
  return structurallyUtf8(s) &&
         std::none_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
}

// A value of the valid scene that a test replaces: where it is, and how messages name it.
struct Site {
  json::json_pointer pointer;
  std::string path; // "objects[3].center[1]"
  const json* value;
};

void collectSites(const json& j, const json::json_pointer& pointer, const std::string& path, std::vector<Site>& out) {
  if (!path.empty()) out.push_back({pointer, path, &j});
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      collectSites(it.value(), pointer / it.key(), path.empty() ? it.key() : path + "." + it.key(), out);
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      collectSites(j[i], pointer / i, path + "[" + std::to_string(i) + "]", out);
    }
  }
}

class HardeningScene : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::scratchDir("hardening");
    std::ofstream(dir_ / "tetra.obj") << kTetraObj;
    std::ofstream(dir_ / "triangle.gltf") << kTriangleGltf;
    base_ = json::parse(kEverything);
    collectSites(base_, json::json_pointer(), "", sites_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The loader's verdict on text: nullopt if it loads, else the InputError's message. Any other
  // exception fails the test.
  std::optional<std::string> load(const std::string& text) {
    try {
      loadSceneFromString(text, "test.json", dir_);
      return std::nullopt;
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  }

  // The valid scene with the value at `site` replaced by `value`.
  std::string replaced(const Site& site, const json& value) const {
    json doc = base_;
    doc[site.pointer] = value;
    return doc.dump(2);
  }

  // Expects text to be refused with one line naming "test.json: <path>: " (and `problem`).
  void expectRefusedAt(const std::string& text, const std::string& path, const std::string& problem = "") {
    auto message = load(text);
    ASSERT_TRUE(message.has_value()) << "accepted with " << path << " broken:\n" << text;
    EXPECT_NE(message->find("test.json: " + path + ": " + problem), std::string::npos)
        << "message: " << *message << "\nexpected the path " << path << " and '" << problem << "'";
    EXPECT_TRUE(oneLine(*message)) << *message;
  }

  std::vector<const Site*> sitesWhere(bool (*pred)(const json&)) const {
    std::vector<const Site*> out;
    for (const auto& s : sites_) {
      if (pred(*s.value)) out.push_back(&s);
    }
    return out;
  }

  fs::path dir_;
  json base_;
  std::vector<Site> sites_;
};

TEST_F(HardeningScene, TheSceneEveryTestBreaksIsValid) {
  ASSERT_EQ(load(kEverything), std::nullopt) << *load(kEverything);
  Scene s = loadSceneFromString(kEverything, "test.json", dir_);
  EXPECT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.spheres.size(), 2u);
  EXPECT_EQ(s.planes.size(), 2u);
  // Enough sites that the generated cases below cover the format, not a handful of fields.
  EXPECT_GT(sitesWhere([](const json& j) { return j.is_number(); }).size(), 90u);
}

TEST_F(HardeningScene, NonFiniteNumbersAreRefusedAtEveryField) {
  auto numbers = sitesWhere([](const json& j) { return j.is_number(); });
  for (const Site* site : numbers) {
    SCOPED_TRACE(site->path);
    // JSON has no NaN or Inf: people write them as strings, or as bare words that are not JSON.
    expectRefusedAt(replaced(*site, "NaN"), site->path, "must be a finite number, got NaN");
    expectRefusedAt(replaced(*site, "-Infinity"), site->path, "must be a finite number, got -Infinity");
    expectRefusedAt(replaced(*site, "inf"), site->path, "must be a finite number");
    for (const char* bare : {"NaN", "Infinity", "-1e999", "1e400"}) {
      std::string text = replaced(*site, "@@bare@@");
      text.replace(text.find("\"@@bare@@\""), 10, bare);
      auto message = load(text);
      ASSERT_TRUE(message.has_value()) << bare << " accepted at " << site->path;
      EXPECT_NE(message->find("invalid JSON"), std::string::npos) << *message;
      EXPECT_TRUE(message->rfind("test.json", 0) == 0) << *message;
      EXPECT_TRUE(oneLine(*message)) << *message;
    }
  }
}

TEST_F(HardeningScene, WrongTypesAreRefusedAtEveryField) {
  auto leaves = sitesWhere([](const json& j) { return j.is_primitive(); });
  const json wrong[] = {json("text"), json(7), json(true), json(nullptr), json::array(), json::object()};
  int refused = 0;
  for (const Site* site : leaves) {
    for (const json& value : wrong) {
      if (value.type() == site->value->type() || (value.is_number() && site->value->is_number())) {
        continue; // not a wrong type
      }
      SCOPED_TRACE(site->path + " = " + value.dump());
      // An object where a material name is expected is an inline material: valid.
      bool inlineMaterial =
          value.is_object() && site->path.size() >= 9 && site->path.compare(site->path.size() - 9, 9, ".material") == 0;
      if (inlineMaterial) {
        EXPECT_EQ(load(replaced(*site, value)), std::nullopt);
        continue;
      }
      expectRefusedAt(replaced(*site, value), site->path);
      ++refused;
    }
  }
  EXPECT_GT(refused, 400);
}

TEST_F(HardeningScene, EmptyContainersLoadOrAreRefusedAtTheirPath) {
  auto containers = sitesWhere([](const json& j) { return j.is_structured(); });
  int refused = 0;
  for (const Site* site : containers) {
    for (const json& empty : {json::array(), json::object()}) {
      SCOPED_TRACE(site->path + " = " + empty.dump());
      std::string text = replaced(*site, empty);
      auto message = load(text);
      if (!message) continue; // e.g. "objects": [], "render": {}: valid
      ++refused;
      // Emptied materials leave the objects that name one dangling: reported at the reference.
      bool atReference = site->path == "materials" && message->find(".material: unknown material") != std::string::npos;
      EXPECT_TRUE(atReference || message->find("test.json: " + site->path + ": ") != std::string::npos) << *message;
      EXPECT_TRUE(oneLine(*message)) << *message;
    }
  }
  EXPECT_GT(refused, 60);
  // A few that must be refused, with the problem stated.
  expectRefusedAt(replaced(sites_[0], json::array()), sites_[0].path);
  json doc = base_;
  doc["objects"][2]["center"] = json::array();
  expectRefusedAt(doc.dump(), "objects[2].center", "must be an array of 3 numbers, got 0 elements");
  doc = base_;
  doc["objects"][3]["vertices"] = json::array();
  expectRefusedAt(doc.dump(), "objects[3].vertices", "a polygon needs at least 3 vertices, got 0");
}

TEST_F(HardeningScene, EveryTruncationIsRefused) {
  std::string text = base_.dump(1);
  for (std::size_t cut = 0; cut < text.size(); ++cut) {
    auto message = load(text.substr(0, cut));
    ASSERT_TRUE(message.has_value()) << "accepted when cut at " << cut;
    EXPECT_NE(message->find("invalid JSON"), std::string::npos) << *message;
    EXPECT_TRUE(oneLine(*message)) << *message;
  }
}

TEST_F(HardeningScene, RandomBytesAreRefused) {
  std::mt19937 rng(20240611);
  for (int i = 0; i < 400; ++i) {
    std::string bytes(1 + rng() % 2048, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    // Half of them start like a scene, so the parser gets past the first byte.
    if (i % 2) bytes = std::string(kEverything).substr(0, rng() % 400) + bytes;
    auto message = load(bytes);
    ASSERT_TRUE(message.has_value());
    EXPECT_TRUE(oneLine(*message)) << *message;
  }
}

// Nesting is limited while parsing (a scene is a few levels deep): a million levels must neither
// overflow the stack in the parser or in the base-scene merge nor take memory in proportion.
TEST_F(HardeningScene, DeepNestingIsRefusedBeforeItIsBuilt) {
  const std::size_t depth = 1'000'000;
  std::string arrays = std::string(depth, '[') + std::string(depth, ']');
  auto message = load(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] }, "description": )" + arrays + "}");
  ASSERT_TRUE(message.has_value());
  EXPECT_NE(message->find("nested more than"), std::string::npos) << *message;
  EXPECT_TRUE(oneLine(*message)) << *message;

  // Objects under a key merged into a base scene: nlohmann's merge_patch recurses per level.
  std::string objects;
  for (std::size_t i = 0; i < depth; ++i) objects += "{\"a\":";
  objects += "1" + std::string(depth, '}');
  fs::copy_file(VKRAY_SOURCE_DIR "/scenes/seed.json", dir_ / "seed.json");
  message = load(R"({ "base": "seed.json", "render": )" + objects + "}");
  ASSERT_TRUE(message.has_value());
  EXPECT_NE(message->find("nested more than"), std::string::npos) << *message;

  // The deepest legitimate scene still loads: a polygon vertex is at depth 5.
  EXPECT_EQ(load(kEverything), std::nullopt);
}

TEST_F(HardeningScene, ControlCharactersInNamesStayOnOneLine) {
  json doc = base_;
  doc["objects\n\r\x1b[31m"] = json::array();
  auto message = load(doc.dump());
  ASSERT_TRUE(message.has_value());
  EXPECT_TRUE(oneLine(*message)) << *message;
  EXPECT_NE(message->find("unknown key 'objects\\n\\r\\x1b[31m'"), std::string::npos) << *message;

  doc = base_;
  doc["objects"][2]["material"] = "gl\nass";
  message = load(doc.dump());
  ASSERT_TRUE(message.has_value());
  EXPECT_TRUE(oneLine(*message)) << *message;
  EXPECT_NE(message->find("unknown material 'gl\\nass'"), std::string::npos) << *message;

  doc = base_;
  doc["objects"][6]["file"] = "no\nsuch.obj";
  message = load(doc.dump());
  ASSERT_TRUE(message.has_value());
  EXPECT_TRUE(oneLine(*message)) << *message;
}

// Ten million spheres are far beyond the scene-file cap: refused on the size alone, before parsing.
TEST_F(HardeningScene, TenMillionObjectsAreRefusedOnSize) {
  const std::string sphere = R"({"type":"sphere","center":[0,0,0],"radius":1},)";
  std::string text = R"({"camera":{"position":[0,0,5],"look_at":[0,0,0]},"objects":[)";
  text.reserve(text.size() + sphere.size() * 10'000'000 + 4);
  for (int i = 0; i < 10'000'000; ++i) text += sphere;
  text.back() = ']';
  text += '}';
  auto message = load(text);
  ASSERT_TRUE(message.has_value());
  EXPECT_NE(message->find("test.json: file too large to be a scene (" + std::to_string(text.size()) +
                          " bytes; at most " + std::to_string(kMaxSceneFileBytes) + ")"),
            std::string::npos)
      << *message;
}

// ---- Meshes --------------------------------------------------------------------------------------

struct MalformedMesh {
  const char* file; // in tests/data/malformed
  const char* problem;
};

class HardeningMesh : public ::testing::TestWithParam<MalformedMesh> {};

// Each file is named by a scene's mesh object; the message names the object, the file and what is
// wrong with it.
TEST_P(HardeningMesh, IsRefusedWithTheProblem) {
  const MalformedMesh& bad = GetParam();
  fs::path file = kMalformedDir / bad.file;
  ASSERT_TRUE(fs::exists(file)) << file;
  json scene = json::parse(R"({ "camera": { "position": [0, 0, 5], "look_at": [0, 0, 0] } })");
  scene["objects"] = json::array({{{"type", "mesh"}, {"file", file.string()}}});
  try {
    loadSceneFromString(scene.dump(), "mesh.json");
    FAIL() << "accepted " << file;
  } catch (const InputError& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("mesh.json: objects[0].file: " + file.lexically_normal().string() + ": "), std::string::npos)
        << what;
    EXPECT_NE(what.find(bad.problem), std::string::npos) << what << "\nexpected: " << bad.problem;
    EXPECT_TRUE(oneLine(what)) << what;
  }
}

const MalformedMesh kMalformedMeshes[] = {
    {"obj-vertex-index-out-of-range.obj", "face 1: vertex index out of range (resolves to 4; the file has 3 vertices)"},
    {"obj-negative-index-out-of-range.obj", "vertex index out of range"},
    {"obj-normal-index-out-of-range.obj", "normal index out of range"},
    {"obj-nan-vertex.obj", "is not finite"},
    {"obj-missing-mtl.obj", "material library 'no-such-library.mtl' not found"},
    {"gltf-index-out-of-range.gltf", "index 2 is 7, but there are 3 vertices"},
    {"gltf-accessor-past-buffer-view.gltf", "1000 elements do not fit bufferViews[0]"},
    {"gltf-buffer-view-past-buffer.gltf", "bufferViews[0] reaches past the end of buffer 0"},
    {"gltf-node-cycle.gltf", "node 0 is reached twice"},
    {"gltf-missing-node.gltf", "refers to node 5, which does not exist"},
    {"gltf-missing-buffer-file.gltf", "not a valid glTF file"},
    {"gltf-bad-mode.gltf", ".mode 42 is not a glTF primitive mode"},
    {"gltf-garbage.gltf", "not a valid glTF file"},
    {"glb-truncated.glb", "not a valid glTF file"},
    {"ply-truncated-binary.ply", "face 0 (byte 218): the file ends inside it (truncated?)"},
    {"ply-absurd-count.ply", "element 'vertex' declares 4000000000 entries, more than the file's 215 bytes can hold"},
    {"ply-bad-list-count.ply", "line 13: face 0: vertex_indices: the list's length is negative (-3)"},
};

INSTANTIATE_TEST_SUITE_P(Corpus, HardeningMesh, ::testing::ValuesIn(kMalformedMeshes),
                         [](const ::testing::TestParamInfo<MalformedMesh>& info) {
                           std::string name = info.param.file;
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

// Every mesh file in the corpus has a row above (a new file must say what it is for).
TEST(HardeningMeshCorpus, EveryFileHasAnExpectation) {
  for (const auto& entry : fs::directory_iterator(kMalformedDir)) {
    std::string ext = entry.path().extension().string();
    if (ext != ".obj" && ext != ".gltf" && ext != ".glb" && ext != ".ply") continue;
    std::string name = entry.path().filename().string();
    bool listed = std::any_of(std::begin(kMalformedMeshes), std::end(kMalformedMeshes),
                              [&](const MalformedMesh& m) { return name == m.file; });
    EXPECT_TRUE(listed) << name << " has no row in kMalformedMeshes";
  }
}

// ---- Fuzz findings -------------------------------------------------------------------------------

// Inputs that once crashed a fuzz target (tests/data/malformed/fuzz/<target>/) are run through the
// same code as the target: each must load or be refused with InputError. Under the sanitizer build
// (tools/run-sanitizers) a memory error in any of them fails the run.
TEST(HardeningFuzz, FindingsStayFixed) {
  fs::path root = kMalformedDir / "fuzz";
  if (!fs::exists(root)) GTEST_SKIP() << "no fuzz findings recorded";
  fs::path scratch = test::scratchDir("fuzz-replay");
  int replayed = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    std::string target = entry.path().parent_path().filename().string();
    std::ifstream in(entry.path(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    SCOPED_TRACE(entry.path().string());
    try {
      if (target == "scene") {
        Scene scene = loadSceneFromString(bytes, "fuzz.json", VKRAY_SOURCE_DIR "/scenes");
        Features f = analyzeScene(scene, scene.render);
        packScene(scene, scene.camera.position, f.useBvh);
      } else if (target == "ply") {
        MeshRequest request;
        request.file = scratch / "fuzz.ply";
        std::ofstream(request.file, std::ios::binary) << bytes;
        request.shownAs = "fuzz.ply";
        Scene scene;
        importMesh(request, scene);
      } else if (target == "texture") {
        decodeTextureData(bytes, "fuzz.png");
      } else {
        // obj and gltf inputs: the file, then optionally "#---companion---" and its MTL or .bin.
        const std::string marker = "\n#---companion---\n";
        auto at = bytes.find(marker);
        std::string main = bytes.substr(0, at);
        std::string companion = at == std::string::npos ? "" : bytes.substr(at + marker.size());
        bool glb = main.rfind("glTF", 0) == 0;
        std::ofstream(scratch / (target == "obj" ? "fuzz.mtl" : "fuzz.bin"), std::ios::binary) << companion;
        MeshRequest request;
        request.file = scratch / (target == "obj" ? "fuzz.obj" : glb ? "fuzz.glb" : "fuzz.gltf");
        std::ofstream(request.file, std::ios::binary) << main;
        request.shownAs = request.file.filename().string();
        Scene scene;
        importMesh(request, scene);
      }
    } catch (const InputError& e) {
      EXPECT_TRUE(oneLine(e.what())) << e.what();
    }
    ++replayed;
  }
  fs::remove_all(scratch);
  EXPECT_GT(replayed, 0);
}

// ---- Outputs -------------------------------------------------------------------------------------

// The PID of a process that has ended (forked, exited and reaped), for a dead writer's temporary
// file; -1 if fork failed.
pid_t finishedProcess() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  if (pid > 0) ::waitpid(pid, nullptr, 0);
  return pid;
}

std::size_t filesIn(const fs::path& dir) {
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  return files;
}

// A process killed between creating its temporary output and renaming it leaves a hidden
// ".NAME.tmp-PID-XXXXXX"; the next write to NAME removes it, and leaves live writers' files alone.
TEST(HardeningOutput, StaleTemporariesOfDeadWritersAreRemoved) {
  fs::path dir = test::freshScratchDir("stale");
  const pid_t dead = finishedProcess();
  ASSERT_GT(dead, 0);
  const std::string deadName = ".out.png.tmp-" + std::to_string(dead) + "-a1b2c3";
  const std::string liveName = ".out.png.tmp-" + std::to_string(::getpid()) + "-d4e5f6";
  const std::string otherName = ".other.png.tmp-" + std::to_string(dead) + "-g7h8i9";
  for (const auto& name : {deadName, liveName, otherName}) std::ofstream(dir / name) << "partial";

  writeFileAtomic(dir / "out.png", {1, 2, 3});
  EXPECT_FALSE(fs::exists(dir / deadName)) << "a dead writer's temporary file was kept";
  EXPECT_TRUE(fs::exists(dir / liveName)) << "a live writer's temporary file was removed";
  EXPECT_TRUE(fs::exists(dir / otherName)) << "another output's temporary file was removed";
  EXPECT_EQ(fs::file_size(dir / "out.png"), 3u);
  EXPECT_EQ(filesIn(dir), 3u) << "the write left its own temporary file";
  fs::remove_all(dir);
}

// The caches (pipeline cache, folded SPIR-V) write the same way, quietly: a failed write returns
// false and leaves nothing, and a killed process's temporary goes on the next write, as above.
TEST(HardeningOutput, CacheWritesAreAtomicQuietAndCleanUpAfterDeadWriters) {
  fs::path dir = test::freshScratchDir("quiet");
  const pid_t dead = finishedProcess();
  ASSERT_GT(dead, 0);
  const std::string deadName = ".cache.bin.tmp-" + std::to_string(dead) + "-a1b2c3";
  std::ofstream(dir / deadName) << "partial";
  const std::vector<std::uint8_t> bytes{1, 2, 3, 4};
  EXPECT_TRUE(writeFileAtomicQuietly(dir / "cache.bin", bytes));
  EXPECT_FALSE(fs::exists(dir / deadName)) << "a dead writer's temporary file was kept";
  EXPECT_EQ(fs::file_size(dir / "cache.bin"), 4u);
  EXPECT_FALSE(writeFileAtomicQuietly(dir / "missing" / "cache.bin", bytes));
  EXPECT_EQ(filesIn(dir), 1u) << "a write left its temporary file";
  fs::remove_all(dir);
}

// ---- Device loss ---------------------------------------------------------------------------------

// VK_ERROR_DEVICE_LOST cannot be provoked on lavapipe; the path that reports it is the one every
// Vulkan call goes through (vulkanStep), given the exception Vulkan-Hpp throws.
TEST(HardeningDevice, LostDeviceIsReportedAsSuchWithTheStep) {
  try {
    vulkan::vulkanStep("tracing rows 0..7", []() -> int { throw vk::DeviceLostError("vkQueueSubmit"); });
    FAIL();
  } catch (const DeviceLostError& e) {
    std::string what = e.what();
    EXPECT_EQ(what.rfind("tracing rows 0..7: vkQueueSubmit", 0), 0u) << what;
    EXPECT_NE(what.find("VK_ERROR_DEVICE_LOST"), std::string::npos) << what;
    EXPECT_TRUE(oneLine(what)) << what;
  }
  // Other failures are device errors, not device loss.
  try {
    vulkan::vulkanStep("uploading 'spheres'", []() -> int { throw vk::OutOfDeviceMemoryError("vkAllocateMemory"); });
    FAIL();
  } catch (const DeviceLostError&) {
    FAIL() << "an out-of-memory error reported as a lost device";
  } catch (const DeviceError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("uploading 'spheres': vkAllocateMemory", 0), 0u) << e.what();
  }
}

} // namespace
} // namespace vkray
