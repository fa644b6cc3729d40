// libFuzzer target: the OBJ importer (tinyobjloader, then vkray's checks and appendMesh). An input
// is an OBJ file, optionally followed by a line "#---companion---" and the MTL library the OBJ
// can load as "fuzz.mtl". It must import or be refused with vkray::InputError; anything else is a
// bug.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scene/mesh_import.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto [obj, mtl] = vkray::fuzz::splitCompanion(data, size);
  vkray::fuzz::writeScratch("fuzz.mtl", mtl);
  vkray::MeshRequest request;
  request.file = vkray::fuzz::writeScratch("fuzz.obj", obj);
  request.shownAs = "fuzz.obj";
  vkray::fuzz::importMesh(vkray::readObj, request);
  return 0;
}
