// libFuzzer target: a scene file's text through everything the host does with it before the GPU
// (load and validate, analyse, pack with a BVH). Any input must either load or be refused with
// vkray::InputError; a crash, a sanitizer report, a hang or any other exception is a bug.
// Relative "base" scenes and mesh files resolve against the bundled scenes/ (seed.json,
// meshes/knot.obj, ...), as they do for the seed corpus (tools/run-fuzz).
#include <cstddef>
#include <cstdint>
#include <string>

#include "render/gpu_scene.h"
#include "scene/features.h"
#include "scene/scene_loader.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    vkray::Scene scene = vkray::loadSceneFromString(text, "fuzz.json", VKRAY_FUZZ_DATA_DIR);
    vkray::Features features = vkray::analyzeScene(scene, scene.render);
    vkray::packScene(scene, scene.camera.position, features.useBvh);
  } catch (const vkray::InputError&) {
    // Refused with a message: the expected outcome for most inputs.
  }
  return 0;
}
