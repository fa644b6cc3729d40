// Shared pieces of the libFuzzer targets: a private scratch directory for inputs that the code
// under test reads from files (mesh importers), and splitting one input into a main file and a
// companion file (an OBJ and its MTL, a glTF and its .bin buffer).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>
#include <utility>

#include "scene/mesh_import.h"

namespace vkray::fuzz {

// A directory of this process's own, created on first use and removed at exit.
const std::filesystem::path& scratchDir();

// Writes bytes to scratchDir()/name (replacing it) and returns the path.
std::filesystem::path writeScratch(const char* name, std::string_view bytes);

// Splits an input at the first line "#---companion---": the main file before it, the companion
// after. Without the marker the companion is empty.
std::pair<std::string_view, std::string_view> splitCompanion(const std::uint8_t* data, std::size_t size);

// Reads the mesh with `read` (readObj, readGltf) and adds it to a scene with each normals mode,
// the steps every mesh goes through; a clear error (InputError) is the expected way to fail.
void importMesh(MeshData (*read)(const MeshRequest&), MeshRequest& request);

} // namespace vkray::fuzz
