// libFuzzer target: the OBJ importer (tinyobjloader, then vkray's checks and appendMesh). An input
// is an OBJ file, optionally followed by a line "#---companion---" and the MTL library the OBJ
// can load as "fuzz.mtl". It must import or be refused with vkray::InputError; anything else is a
// bug.
#include <cstddef>
#include <cstdint>

#include "fuzz_support.h"
#include "scene/mesh_import.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto [obj, mtl] = vkray::fuzz::splitCompanion(data, size);
  vkray::fuzz::writeScratch("fuzz.mtl", mtl);
  vkray::MeshRequest request;
  request.file = vkray::fuzz::writeScratch("fuzz.obj", obj);
  request.shownAs = "fuzz.obj";
  try {
    vkray::MeshData mesh = vkray::readObj(request);
    for (auto normals : {vkray::MeshNormals::Auto, vkray::MeshNormals::Smooth}) {
      request.normals = normals;
      vkray::Scene scene;
      vkray::appendMesh(mesh, request, scene);
    }
  } catch (const vkray::InputError&) {
  }
  return 0;
}
