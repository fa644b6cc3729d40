// Mesh data -> scene triangles: transform, material mapping, normal handling, degenerate removal.
// The format readers are in mesh_import_obj.cpp, mesh_import_gltf.cpp and mesh_import_ply.cpp.
#include "scene/mesh_import.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string_view>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/json_reader.h"
#include "scene/scene_limits.h"
#include "util/error.h"
#include "util/file_extension.h"

namespace vkray {

namespace {

using glm::dvec3;

bool finite(const dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool inFloat32(double v) {
  return std::abs(v) <= static_cast<double>(std::numeric_limits<float>::max());
}

// Area-weighted vertex normals over vertices welded by exact position (glTF splits vertices at
// texture seams; welding keeps the shading continuous across them). World space.
std::vector<dvec3> smoothNormals(const std::vector<dvec3>& world,
                                 const std::vector<std::array<std::uint32_t, 3>>& faces,
                                 std::vector<std::uint32_t>& weld) {
  struct Hash {
    std::size_t operator()(const dvec3& v) const {
      std::hash<double> h;
      return h(v.x) ^ (h(v.y) * 0x9E3779B97F4A7C15ull) ^ (h(v.z) * 0xC2B2AE3D27D4EB4Full);
    }
  };
  std::unordered_map<dvec3, std::uint32_t, Hash> ids;
  ids.reserve(world.size());
  weld.resize(world.size());
  std::vector<dvec3> sums;
  for (std::size_t i = 0; i < world.size(); ++i) {
    auto [it, inserted] = ids.emplace(world[i], static_cast<std::uint32_t>(sums.size()));
    if (inserted) sums.emplace_back(0.0);
    weld[i] = it->second;
  }
  for (const auto& f : faces) {
    // The cross product's length is twice the area: larger faces weigh more.
    dvec3 n = glm::cross(world[f[1]] - world[f[0]], world[f[2]] - world[f[0]]);
    if (!finite(n)) continue;
    for (std::uint32_t v : f) sums[weld[v]] += n;
  }
  return sums;
}

// Text in an encoding the readers do not read (they read ASCII and UTF-8): the name of the encoding,
// from a byte-order mark or, without one, from the NUL bytes that UTF-16 and UTF-32 put in ASCII
// text; empty when the text may be read.
std::string unreadableEncoding(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  auto starts = [&](std::string_view bom) { return head.compare(0, bom.size(), bom) == 0; };
  using namespace std::string_view_literals;
  if (starts("\x00\x00\xFE\xFF"sv)) return "UTF-32 (big endian)";
  if (starts("\xFF\xFE\x00\x00"sv)) return "UTF-32 (little endian)";
  if (starts("\xFE\xFF"sv)) return "UTF-16 (big endian)";
  if (starts("\xFF\xFE"sv)) return "UTF-16 (little endian)";
  std::size_t nul = static_cast<std::size_t>(std::count(head.begin(), head.end(), '\0'));
  // ASCII as UTF-16 is half NULs, as UTF-32 three quarters; text has none.
  if (head.size() >= 8 && nul * 4 >= head.size()) {
    return nul * 2 > head.size() ? "UTF-32 (no byte-order mark)" : "UTF-16 (no byte-order mark)";
  }
  return {};
}

} // namespace

glm::dmat4 composeTransform(const dvec3& translate, const dvec3& rotateDegrees, const dvec3& scale) {
  glm::dmat4 m(1.0);
  m = glm::translate(m, translate);
  m = glm::rotate(m, glm::radians(rotateDegrees.z), dvec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(rotateDegrees.y), dvec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(rotateDegrees.x), dvec3(1, 0, 0));
  m = glm::scale(m, scale);
  return m;
}

std::optional<Camera> appendMesh(const MeshData& data, const MeshRequest& request, Scene& scene) {
  const std::string& where = request.shownAs;
  const std::size_t faceCount = data.faces.size();
  if (scene.objectCount() + faceCount > kMaxPrimitives) {
    throw InputError(where, std::to_string(faceCount) + " triangles would bring the scene past " +
                                std::to_string(kMaxPrimitives) + " primitives (the limit)");
  }
  if (!data.faceNormals.empty() && data.faceNormals.size() != faceCount) throw Error(where + ": face normal count");
  if (!data.faceMaterials.empty() && data.faceMaterials.size() != faceCount) throw Error(where + ": material count");
  if (!data.faceTexcoords.empty() && data.faceTexcoords.size() != faceCount) throw Error(where + ": texcoord count");

  // Positions to world space, checked where a face uses them.
  const glm::dmat4& m = request.worldFromMesh;
  const glm::dmat3 linear(m);
  const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(linear)); // normals: inverse transpose
  std::vector<dvec3> world(data.positions.size());
  for (std::size_t i = 0; i < world.size(); ++i) world[i] = dvec3(m * glm::dvec4(data.positions[i], 1.0));
  for (std::size_t f = 0; f < faceCount; ++f) {
    for (std::uint32_t v : data.faces[f]) {
      if (v >= world.size()) {
        throw InputError(where, "face " + std::to_string(f) + " uses vertex " + std::to_string(v) + " of " +
                                    std::to_string(world.size()));
      }
      if (!finite(data.positions[v])) {
        throw InputError(where, "vertex " + std::to_string(v) + " (used by face " + std::to_string(f) +
                                    ") is not finite (NaN or Inf)");
      }
      if (!finite(world[v])) {
        throw InputError(where, "vertex " + std::to_string(v) + " overflows under the mesh's transform");
      }
      for (int k = 0; k < 3; ++k) {
        double c = std::abs(world[v][k]);
        if (c > kMaxCoordinate) {
          // Past float32's range the GPU would see infinity; past kMaxCoordinate its squared distances overflow.
          bool pastFloat = c > static_cast<double>(std::numeric_limits<float>::max());
          throw InputError(where, "vertex " + std::to_string(v) + " (used by face " + std::to_string(f) + ") has " +
                                      "xyz"[k] + " = " + formatNumber(world[v][k]) +
                                      (pastFloat ? ", outside float32's range (+-3.40282347e+38)"
                                                 : ", past +-1e+18, where the kernel's squared distances overflow "
                                                   "float32") +
                                      (m == glm::dmat4(1.0) ? "" : " (after the mesh's transform)"));
        }
      }
    }
  }

  // Materials: the override, or the file's own (only those some face uses), or the default.
  std::vector<std::uint32_t> sceneMaterial(data.materials.size(), MeshData::kNone);
  std::uint32_t fallback = MeshData::kNone;
  std::uint32_t textureBase = MeshData::kNone;
  auto materialOf = [&](std::size_t f) -> std::uint32_t {
    if (request.material) return *request.material;
    std::uint32_t fm = data.faceMaterials.empty() ? MeshData::kNone : data.faceMaterials[f];
    if (fm == MeshData::kNone || fm >= data.materials.size()) {
      if (fallback == MeshData::kNone) {
        if (request.defaultMaterial) {
          fallback = request.defaultMaterial();
        } else {
          fallback = static_cast<std::uint32_t>(scene.materials.size());
          Material d;
          d.name = "(default)";
          scene.materials.push_back(d);
        }
      }
      return fallback;
    }
    if (sceneMaterial[fm] == MeshData::kNone) {
      const Material& mat = data.materials[fm];
      for (double v : {mat.color.x, mat.color.y, mat.color.z, mat.diffuse, mat.specular, mat.shininess}) {
        if (!inFloat32(v)) {
          throw InputError(where, "material '" + mat.name + "' has " + formatNumber(v) +
                                      ", outside float32's range (+-3.40282347e+38; the GPU computes in float32)");
        }
      }
      sceneMaterial[fm] = static_cast<std::uint32_t>(scene.materials.size());
      scene.materials.push_back(mat);
      if (mat.baseColorTexture) {
        // The file's texture list goes to the scene once, when a material first needs it.
        if (textureBase == MeshData::kNone) {
          textureBase = static_cast<std::uint32_t>(scene.textures.size());
          scene.textures.insert(scene.textures.end(), data.textures.begin(), data.textures.end());
        }
        scene.materials.back().baseColorTexture->texture += textureBase;
      }
    }
    return sceneMaterial[fm];
  };

  std::vector<std::uint32_t> weld;
  std::vector<dvec3> smooth;
  if (request.normals == MeshNormals::Smooth) smooth = smoothNormals(world, data.faces, weld);

  MeshInfo info;
  info.file = where;
  info.firstTriangle = scene.triangles.size();
  scene.triangles.reserve(scene.triangles.size() + faceCount);
  for (std::size_t f = 0; f < faceCount; ++f) {
    const auto& face = data.faces[f];
    Triangle t;
    for (int k = 0; k < 3; ++k) t.v[k] = world[face[static_cast<std::size_t>(k)]];
    dvec3 e1 = t.v[1] - t.v[0];
    dvec3 e2 = t.v[2] - t.v[0];
    dvec3 ng = glm::cross(e1, e2);
    double len = glm::length(ng);
    // Zero area (repeated or collinear vertices, to double precision): no ray can hit it.
    if (!(len > 1e-15 * glm::length(e1) * glm::length(e2)) || !std::isfinite(len)) {
      ++info.droppedDegenerate;
      continue;
    }
    std::array<dvec3, 3> ns;
    bool haveNormals = false;
    if (request.normals == MeshNormals::Auto && !data.faceNormals.empty()) {
      const auto& fn = data.faceNormals[f];
      haveNormals = true;
      for (int k = 0; k < 3 && haveNormals; ++k) {
        std::uint32_t ni = fn[static_cast<std::size_t>(k)];
        if (ni == MeshData::kNone || ni >= data.normals.size()) {
          haveNormals = false;
          break;
        }
        dvec3 n = normalMatrix * data.normals[ni];
        double nl = glm::length(n);
        // A zero, NaN or Inf normal in the file: the face falls back to flat shading.
        if (!(nl > 0.0) || !std::isfinite(nl)) haveNormals = false;
        ns[static_cast<std::size_t>(k)] = n / nl;
      }
    } else if (request.normals == MeshNormals::Smooth) {
      haveNormals = true;
      for (int k = 0; k < 3 && haveNormals; ++k) {
        dvec3 n = smooth[weld[face[static_cast<std::size_t>(k)]]];
        double nl = glm::length(n);
        if (!(nl > 0.0) || !std::isfinite(nl)) haveNormals = false;
        ns[static_cast<std::size_t>(k)] = n / nl;
      }
    }
    if (haveNormals) {
      // The kernel expects the shading normal on the geometric normal's side (it flips both
      // together); a face wound against its normals gets them turned to its side.
      if (glm::dot(ns[0] + ns[1] + ns[2], ng) < 0.0) {
        for (auto& n : ns) n = -n;
      }
      t.normals = ns;
    }
    t.material = materialOf(f);
    if (scene.materials[t.material].baseColorTexture && !data.faceTexcoords.empty()) {
      const auto& ft = data.faceTexcoords[f];
      if (ft[0] < data.texcoords.size() && ft[1] < data.texcoords.size() && ft[2] < data.texcoords.size())
        t.uvs = std::array<glm::dvec4, 3>{data.texcoords[ft[0]], data.texcoords[ft[1]], data.texcoords[ft[2]]};
    } else if (scene.materials[t.material].baseColorTexture && data.texcoords.size() == data.positions.size()) {
      std::array<glm::dvec4, 3> uvs;
      for (int k = 0; k < 3; ++k) uvs[static_cast<std::size_t>(k)] = data.texcoords[face[static_cast<std::size_t>(k)]];
      t.uvs = uvs;
    }
    if (data.colors.size() == data.positions.size()) {
      std::array<glm::dvec4, 3> colors;
      for (int k = 0; k < 3; ++k) colors[static_cast<std::size_t>(k)] = data.colors[face[static_cast<std::size_t>(k)]];
      t.colors = colors;
    }
    scene.triangles.push_back(t);
  }
  info.triangleCount = scene.triangles.size() - info.firstTriangle;
  // A file that adds nothing a ray can hit is a mistake (a wrong file, a failed export), never an
  // empty picture.
  if (info.triangleCount == 0) {
    if (faceCount > 0) {
      throw InputError(where, "no triangles: all " + std::to_string(faceCount) +
                                  " of its faces are degenerate (zero area), nothing a ray can hit");
    }
    std::string reason = data.noTrianglesReason;
    if (reason.empty()) {
      reason = data.positions.empty() ? "the file has no vertices and no faces"
                                      : "the file has " + std::to_string(data.positions.size()) +
                                            " vertices but no faces (a point cloud?)";
    }
    throw InputError(where, "no triangles: " + reason + "; nothing a ray can hit");
  }
  scene.meshes.push_back(info);
  for (const std::string& warning : data.warnings) {
    std::fprintf(stderr, "vkray: warning: %s: %s\n", where.c_str(), warning.c_str());
  }

  for (std::size_t i = 0; i < data.lights.size(); ++i) {
    PointLight light = data.lights[i];
    light.position = dvec3(m * glm::dvec4(light.position, 1.0));
    light.color *= request.lightScale;
    for (int k = 0; k < 3; ++k) {
      if (!(std::abs(light.position[k]) <= kMaxCoordinate)) {
        throw InputError(where, "light " + std::to_string(i) + " is at " + "xyz"[k] + " = " +
                                    formatNumber(light.position[k]) +
                                    ", past +-1e+18, where the kernel's squared distances overflow float32");
      }
      if (!inFloat32(light.color[k])) {
        throw InputError(where, "light " + std::to_string(i) + " has colour x intensity " +
                                    formatNumber(light.color[k]) + ", outside float32's range (+-3.40282347e+38)");
      }
    }
    scene.lights.push_back(light);
  }
  std::optional<Camera> camera;
  if (data.camera) {
    Camera c = *data.camera;
    dvec3 forward = linear * (c.lookAt - c.position);
    c.position = dvec3(m * glm::dvec4(c.position, 1.0));
    c.lookAt = c.position + forward;
    c.up = linear * c.up;
    for (int k = 0; k < 3; ++k) {
      if (!(std::abs(c.position[k]) <= kMaxCoordinate)) {
        throw InputError(where, std::string("the camera is at ") + "xyz"[k] + " = " + formatNumber(c.position[k]) +
                                    ", past +-1e+18, where the kernel's squared distances overflow float32");
      }
    }
    camera = c;
  }
  return camera;
}

MeshReader meshReaderFor(const std::filesystem::path& file) {
  std::string ext = lowerExtension(file);
  if (ext == ".obj") return readObj;
  if (ext == ".gltf" || ext == ".glb") return readGltf;
  if (ext == ".ply") return readPly;
  return nullptr;
}

std::optional<Camera> importMesh(const MeshRequest& request, Scene& scene) {
  std::error_code ec;
  auto status = std::filesystem::status(request.file, ec);
  if (ec || !std::filesystem::exists(status)) throw InputError(request.shownAs, "no such file");
  if (std::filesystem::is_directory(status)) throw InputError(request.shownAs, "is a directory, not a mesh file");
  std::string ext = lowerExtension(request.file);
  if (ext == ".obj" || ext == ".gltf") {
    std::string encoding = unreadableEncoding(request.file);
    if (!encoding.empty()) {
      throw InputError(request.shownAs, "is " + encoding + " text; vkray reads " + ext.substr(1) +
                                            " files as ASCII or UTF-8 (convert it: iconv -t UTF-8)");
    }
  }
  MeshReader read = meshReaderFor(request.file);
  if (!read)
    throw InputError(request.shownAs, "unknown mesh format '" + ext + "' (vkray reads .obj, .gltf, .glb and .ply)");
  return appendMesh(read(request), request, scene);
}

} // namespace vkray
