// Wavefront OBJ (+MTL) through tinyobjloader (double-precision build). tinyobjloader only warns
// about out-of-range indices, and its own triangulation reads vertices through them unchecked,
// so faces are read untriangulated, every index is checked here, and polygons are split here (ear
// clipping, triangulate.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include <tiny_obj_loader.h>

#include "scene/mesh_import.h"
#include "scene/triangulate.h"
#include "util/error.h"

namespace vkray {

namespace {

using glm::dvec3;

// The file-based MTL reader, remembering which mtllib files it could not find.
class TrackingMaterialReader : public tinyobj::MaterialFileReader {
public:
  explicit TrackingMaterialReader(const std::string& dir) : tinyobj::MaterialFileReader(dir) {}
  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials, std::map<std::string, int>* ids,
                  std::string* warn, std::string* err) override {
    bool ok = tinyobj::MaterialFileReader::operator()(name, materials, ids, warn, err);
    if (!ok) missing.push_back(name);
    return ok;
  }
  std::vector<std::string> missing;
};

std::string firstLine(const std::string& s) {
  std::string line = s.substr(0, s.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '.')) line.pop_back();
  return line;
}

// The lines tinyobjloader would read unsafely, screened before it sees them:
//  - it reads a coordinate it cannot parse ("nan", "inf", "abc") as 0, silently, so position lines
//    are checked here and such a vertex is refused instead of moved to 0;
//  - it converts a vertex weight's joint id ("vw" lines, skinning data vkray does not use) to int
//    unchecked, undefined behaviour for 1e42 (a fuzz finding), so those lines become comments,
//    which keeps every other line where it was.
void screenLines(std::string& text, const std::string& where) {
  std::size_t vertex = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    // Lines end where tinyobjloader ends them: at \n, \r\n or a lone \r.
    std::size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string::npos) end = text.size();
    std::size_t i = text.find_first_not_of(" \t", pos);
    if (i != std::string::npos && i + 2 < end && text[i] == 'v' && text[i + 1] == 'w' &&
        (text[i + 2] == ' ' || text[i + 2] == '\t')) {
      text[i] = '#';
    } else if (i != std::string::npos && i + 1 < end && text[i] == 'v' && (text[i + 1] == ' ' || text[i + 1] == '\t')) {
      ++vertex;
      i += 2;
      for (int k = 0; k < 3; ++k) {
        i = text.find_first_not_of(" \t\r", i);
        if (i >= end) break; // too few coordinates: tinyobjloader's own error
        std::size_t j = text.find_first_of(" \t\r\n", i);
        if (j == std::string::npos) j = text.size();
        std::string token = text.substr(i, j - i);
        char* stop = nullptr;
        double value = std::strtod(token.c_str(), &stop);
        if (stop != token.c_str() + token.size()) {
          throw InputError(where, "vertex " + std::to_string(vertex) + " (v line " + std::to_string(vertex) + "): '" +
                                      token + "' is not a number");
        }
        if (!std::isfinite(value)) {
          throw InputError(where, "vertex " + std::to_string(vertex) + " (v line " + std::to_string(vertex) +
                                      ") is not finite (NaN or Inf)");
        }
        i = j;
      }
    }
    pos = end + 1;
  }
}

double finiteOr(double v, double fallback) {
  return std::isfinite(v) ? v : fallback;
}

// MTL -> Phong, as docs/scene-format.md states: Kd is the colour (diffuse 1), the largest Ks
// component the highlight, Ns the exponent; illum 3, 5, 6, 7 (ray-traced reflection) make Ks a
// mirror too; d < 1 (dissolve) becomes transmission 1 - d with Ni as the index of refraction.
Material mapMtl(const tinyobj::material_t& mtl, const std::string& file) {
  Material m;
  m.name = file + ": " + mtl.name;
  m.color = glm::max(dvec3(finiteOr(mtl.diffuse[0], 0.8), finiteOr(mtl.diffuse[1], 0.8), finiteOr(mtl.diffuse[2], 0.8)),
                     dvec3(0.0));
  m.diffuse = 1.0;
  m.ambient = m.diffuse; // ambient light reflected as diffuse light is (docs/meshes.md)
  double ks =
      std::max({finiteOr(mtl.specular[0], 0.0), finiteOr(mtl.specular[1], 0.0), finiteOr(mtl.specular[2], 0.0)});
  m.specular = std::clamp(ks, 0.0, 1.0);
  m.shininess = std::clamp(finiteOr(mtl.shininess, 40.0), 0.0, 1e6);
  double d = std::clamp(finiteOr(mtl.dissolve, 1.0), 0.0, 1.0);
  m.transmission = 1.0 - d;
  double ior = finiteOr(mtl.ior, 1.0);
  m.ior = ior >= 0.01 && ior <= 100.0 ? ior : 1.0;
  bool mirror = mtl.illum == 3 || mtl.illum == 5 || mtl.illum == 6 || mtl.illum == 7;
  m.reflection = mirror ? std::min(m.specular, 1.0 - m.transmission) : 0.0;
  return m;
}

} // namespace

MeshData readObj(const MeshRequest& request) {
  const std::string& where = request.shownAs;
  std::ifstream file(request.file, std::ios::binary);
  if (!file) throw InputError(where, "cannot open for reading");
  std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  screenLines(text, where);
  std::istringstream in(std::move(text));
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn;
  std::string err;
  std::string dir = request.file.parent_path().string();
  TrackingMaterialReader mtlReader(dir.empty() ? std::string("./") : dir + "/");
  bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, &mtlReader, /*triangulate=*/false,
                             /*default_vcols_fallback=*/false);
  if (!ok || !err.empty()) throw InputError(where, "not a valid OBJ file: " + firstLine(err));

  std::vector<std::string> warnings;
  if (!request.material) {
    // The file's materials are used: a missing library or name would silently turn grey. In a scene
    // file that is an error (the scene can give the mesh a material); a model opened on its own
    // has no such place, so it renders grey and says so.
    auto missing = [&](const std::string& problem) {
      if (!request.defaultMissingMaterials) {
        throw InputError(where, problem + " (give the mesh a 'material' to ignore the file's materials)");
      }
      warnings.push_back(problem + "; those faces get the default grey");
    };
    if (!mtlReader.missing.empty()) missing("material library '" + mtlReader.missing.front() + "' not found");
    const std::string marker = "material [ '";
    if (auto p = warn.find(marker); p != std::string::npos) {
      auto q = warn.find('\'', p + marker.size());
      missing("usemtl '" + warn.substr(p + marker.size(), q - p - marker.size()) + "' is not in the material library");
    }
  }

  MeshData data;
  data.warnings = std::move(warnings);
  const std::size_t vertexCount = attrib.vertices.size() / 3;
  const std::size_t normalCount = attrib.normals.size() / 3;
  data.positions.resize(vertexCount);
  for (std::size_t i = 0; i < vertexCount; ++i) {
    data.positions[i] = dvec3(attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]);
  }
  data.normals.resize(normalCount);
  for (std::size_t i = 0; i < normalCount; ++i) {
    data.normals[i] = dvec3(attrib.normals[3 * i], attrib.normals[3 * i + 1], attrib.normals[3 * i + 2]);
  }
  bool anyNormals = false;
  for (const auto& shape : shapes) {
    for (const auto& idx : shape.mesh.indices) anyNormals = anyNormals || idx.normal_index >= 0;
  }
  for (const auto& mtl : materials) data.materials.push_back(mapMtl(mtl, where));
  // map_Kd: the diffuse colour times the image (relative to the OBJ's directory; OBJ's v runs up).
  for (std::size_t i = 0; i < materials.size(); ++i) {
    if (materials[i].diffuse_texname.empty()) continue;
    std::filesystem::path image = request.file.parent_path() / materials[i].diffuse_texname;
    if (!std::filesystem::exists(image)) {
      // MTL files written on Windows name textures with backslashes (".\\wood.jpg").
      std::string portable = materials[i].diffuse_texname;
      std::replace(portable.begin(), portable.end(), '\\', '/');
      if (std::filesystem::exists(request.file.parent_path() / portable)) image = request.file.parent_path() / portable;
    }
    if (!std::filesystem::exists(image))
      throw InputError(image.string(), "texture file not found (map_Kd of " + where + ")");
    auto texture = std::make_shared<Texture>();
    texture->name = image.string();
    texture->levels = buildMipChain(readImageFile(image, image.string()));
    MaterialTexture use;
    use.texture = static_cast<std::uint32_t>(data.textures.size());
    data.materials[i].baseColorTexture = use;
    data.textures.push_back(std::move(texture));
  }
  for (std::size_t i = 0; i + 1 < attrib.texcoords.size(); i += 2)
    data.texcoords.emplace_back(attrib.texcoords[i], 1.0 - attrib.texcoords[i + 1], 0.0, 0.0);
  auto texcoordOf = [&](const tinyobj::index_t& idx) {
    return idx.texcoord_index >= 0 && static_cast<std::size_t>(idx.texcoord_index) < data.texcoords.size()
               ? static_cast<std::uint32_t>(idx.texcoord_index)
               : MeshData::kNone;
  };

  std::vector<bool> checkedVertex(vertexCount, false);
  std::vector<dvec3> corners;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> cornerIds; // vertex, normal
  std::vector<Corners> triangles;
  for (const auto& shape : shapes) {
    const auto& mesh = shape.mesh;
    const std::string shapeName = shape.name.empty() ? std::string("(unnamed)") : shape.name;
    std::size_t offset = 0;
    for (std::size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
      std::size_t n = mesh.num_face_vertices[f];
      auto context = [&] { return "object '" + shapeName + "', face " + std::to_string(f + 1) + ": "; };
      // tinyobjloader counts face vertices in 8 bits: a larger face would desynchronise the lists.
      if (offset + n > mesh.indices.size()) throw InputError(where, context() + "more than 255 vertices");
      std::array<std::uint32_t, 3> fv{};
      std::array<std::uint32_t, 3> fn{};
      auto vertex = [&](std::size_t k) {
        const tinyobj::index_t& idx = mesh.indices[offset + k];
        if (idx.vertex_index < 0 || static_cast<std::size_t>(idx.vertex_index) >= vertexCount) {
          throw InputError(where, context() + "vertex index out of range (resolves to " +
                                      std::to_string(static_cast<long long>(idx.vertex_index) + 1) + "; the file has " +
                                      std::to_string(vertexCount) + " vertices)");
        }
        auto v = static_cast<std::uint32_t>(idx.vertex_index);
        if (!checkedVertex[v]) {
          const dvec3& p = data.positions[v];
          if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
            throw InputError(where, "vertex " + std::to_string(v + 1) + " (v line " + std::to_string(v + 1) +
                                        ") is not finite (NaN or Inf)");
          }
          checkedVertex[v] = true;
        }
        std::uint32_t nrm = MeshData::kNone;
        if (idx.normal_index >= 0) {
          if (static_cast<std::size_t>(idx.normal_index) >= normalCount) {
            throw InputError(where, context() + "normal index out of range (resolves to " +
                                        std::to_string(static_cast<long long>(idx.normal_index) + 1) +
                                        "; the file has " + std::to_string(normalCount) + " normals)");
          }
          nrm = static_cast<std::uint32_t>(idx.normal_index);
        } else if (idx.normal_index != -1) {
          throw InputError(where, context() + "normal index out of range");
        }
        return std::pair{v, nrm};
      };
      std::uint32_t material = MeshData::kNone;
      if (f < mesh.material_ids.size() && mesh.material_ids[f] >= 0 &&
          static_cast<std::size_t>(mesh.material_ids[f]) < materials.size()) {
        material = static_cast<std::uint32_t>(mesh.material_ids[f]);
      }
      if (n >= 3) {
        // Polygons are split by ear clipping (triangulate.h): concave faces keep their shape, and
        // convex ones become the fan from their first vertex, as they always did.
        corners.clear();
        cornerIds.clear();
        for (std::size_t k = 0; k < n; ++k) {
          cornerIds.push_back(vertex(k));
          corners.push_back(data.positions[cornerIds.back().first]);
        }
        triangles.clear();
        triangulatePolygon(corners, triangles);
        for (const Corners& t : triangles) {
          for (int k = 0; k < 3; ++k) {
            fv[static_cast<std::size_t>(k)] = cornerIds[t[static_cast<std::size_t>(k)]].first;
            fn[static_cast<std::size_t>(k)] = cornerIds[t[static_cast<std::size_t>(k)]].second;
          }
          data.faces.push_back(fv);
          if (anyNormals) data.faceNormals.push_back(fn);
          if (!data.texcoords.empty()) {
            data.faceTexcoords.push_back({texcoordOf(mesh.indices[offset + t[0]]),
                                          texcoordOf(mesh.indices[offset + t[1]]),
                                          texcoordOf(mesh.indices[offset + t[2]])});
          }
          data.faceMaterials.push_back(material);
        }
      }
      offset += n;
    }
  }
  for (const auto& shape : shapes) {
    if (data.faces.empty() && (!shape.points.indices.empty() || !shape.lines.indices.empty())) {
      data.noTrianglesReason = "the file has only points (p) or lines (l), which are not surfaces";
    }
  }
  if (request.importCamera) throw InputError(where, "OBJ files have no cameras (import_camera needs glTF)");
  if (request.importLights) throw InputError(where, "OBJ files have no lights (import_lights needs glTF)");
  return data;
}

} // namespace vkray
