// Scratch files for the fuzz targets (see fuzz_support.h).
#include "fuzz_support.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <unistd.h>

#include "scene/scene.h"
#include "util/error.h"

namespace vkray::fuzz {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view kMarker = "\n#---companion---\n";

struct Scratch {
  Scratch() {
    std::string tmpl = (fs::temp_directory_path() / "vkray-fuzz-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
      std::perror("vkray fuzz: mkdtemp");
      std::abort();
    }
    path = tmpl;
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path path;
};

} // namespace

const fs::path& scratchDir() {
  static Scratch scratch;
  return scratch.path;
}

fs::path writeScratch(const char* name, std::string_view bytes) {
  fs::path p = scratchDir() / name;
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    std::perror("vkray fuzz: writing a scratch file");
    std::abort();
  }
  return p;
}

std::pair<std::string_view, std::string_view> splitCompanion(const std::uint8_t* data, std::size_t size) {
  std::string_view all(reinterpret_cast<const char*>(data), size);
  auto at = all.find(kMarker);
  if (at == std::string_view::npos) return {all, {}};
  return {all.substr(0, at), all.substr(at + kMarker.size())};
}

void importMesh(MeshData (*read)(const MeshRequest&), MeshRequest& request) {
  try {
    MeshData mesh = read(request);
    for (auto normals : {MeshNormals::Auto, MeshNormals::Smooth}) {
      request.normals = normals;
      Scene scene;
      appendMesh(mesh, request, scene);
    }
  } catch (const InputError&) {
  }
}

} // namespace vkray::fuzz
