// libFuzzer target: the PLY importer (vkray's own parser, the triangulation of its polygons, then
// appendMesh). An input is a PLY file, ASCII or binary. It must import or be refused with
// vkray::InputError; anything else is a bug.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_support.h"
#include "scene/mesh_import.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vkray::MeshRequest request;
  request.file = vkray::fuzz::writeScratch("fuzz.ply", std::string_view(reinterpret_cast<const char*>(data), size));
  request.shownAs = "fuzz.ply";
  vkray::fuzz::importMesh(vkray::readPly, request);
  return 0;
}
