// libFuzzer target: the glTF importer (tinygltf, then vkray's accessor, node and material checks
// and appendMesh). An input starting with "glTF" is a .glb, anything else a .gltf; an optional line
// "#---companion---" is followed by the contents of "fuzz.bin", a buffer the file may name. It must
// import or be refused with vkray::InputError; anything else is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_support.h"
#include "scene/mesh_import.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto [gltf, bin] = vkray::fuzz::splitCompanion(data, size);
  bool binary = gltf.substr(0, 4) == std::string_view("glTF");
  vkray::fuzz::writeScratch("fuzz.bin", bin);
  vkray::MeshRequest request;
  request.file = vkray::fuzz::writeScratch(binary ? "fuzz.glb" : "fuzz.gltf", gltf);
  request.shownAs = "fuzz.gltf";
  // With cameras and lights asked for, every reader path runs; the file may then be refused only
  // because it has none, so it is read once more without them and appended.
  request.importCamera = true;
  request.importLights = true;
  try {
    vkray::readGltf(request);
  } catch (const vkray::InputError&) {
  }
  request.importCamera = false;
  request.importLights = false;
  vkray::fuzz::importMesh(vkray::readGltf, request);
  return 0;
}
