// The PLY reader (host/scene/mesh_import_ply.cpp). One model written here in ASCII, binary little
// endian and binary big endian — properties in an unusual order, unknown elements with list
// properties around the ones vkray reads — reads as the same MeshData, and as the same model
// written as OBJ; every PLY scalar type reads its values; colours are decoded to linear; assimp's
// PLY test models load or are refused with one line; each class of broken file is refused with a
// line naming the file and the problem.
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "test_support.h"
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "image/image.h"
#include "scene/mesh_import.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace vkray {
namespace {

namespace fs = std::filesystem;
using glm::dvec3;

const fs::path kAssimpModels = "/usr/share/assimp/models";

// ---- Writing PLY files -----------------------------------------------------------------------------

enum class Encoding { Ascii, Little, Big };
const Encoding kEncodings[] = {Encoding::Ascii, Encoding::Little, Encoding::Big};

const char* formatName(Encoding e) {
  return e == Encoding::Ascii ? "ascii" : e == Encoding::Little ? "binary_little_endian" : "binary_big_endian";
}

struct PlyProperty {
  std::string type; // a PLY type name, of the items for a list
  std::string name;
  std::string countType; // non-empty: a list
};

// One entry: per property, its values (one for a scalar, the items for a list).
using PlyRow = std::vector<std::vector<double>>;

struct PlyElement {
  std::string name;
  std::vector<PlyProperty> properties;
  std::vector<PlyRow> rows;
};

std::string baseType(const std::string& t) {
  static const std::map<std::string, std::string> names = {
      {"int8", "char"}, {"uint8", "uchar"}, {"int16", "short"},   {"uint16", "ushort"},
      {"int32", "int"}, {"uint32", "uint"}, {"float32", "float"}, {"float64", "double"}};
  auto it = names.find(t);
  return it == names.end() ? t : it->second;
}

void putBinary(std::string& out, const std::string& typeName, double v, bool big) {
  std::string t = baseType(typeName);
  unsigned char b[8];
  std::size_t n = 0;
  auto put = [&](auto x) {
    n = sizeof x;
    std::memcpy(b, &x, n);
  };
  if (t == "char") put(static_cast<std::int8_t>(v));
  if (t == "uchar") put(static_cast<std::uint8_t>(v));
  if (t == "short") put(static_cast<std::int16_t>(v));
  if (t == "ushort") put(static_cast<std::uint16_t>(v));
  if (t == "int") put(static_cast<std::int32_t>(v));
  if (t == "uint") put(static_cast<std::uint32_t>(v));
  if (t == "float") put(static_cast<float>(v));
  if (t == "double") put(v);
  ASSERT_NE(n, 0u) << typeName;
  if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
  out.append(reinterpret_cast<const char*>(b), n);
}

void putAscii(std::string& out, const std::string& typeName, double v) {
  std::string t = baseType(typeName);
  char buf[64];
  if (t == "float") {
    std::snprintf(buf, sizeof buf, "%.9g", static_cast<double>(static_cast<float>(v)));
  } else if (t == "double") {
    std::snprintf(buf, sizeof buf, "%.17g", v);
  } else {
    std::snprintf(buf, sizeof buf, "%lld", static_cast<long long>(v));
  }
  out += buf;
}

std::string writePly(const std::vector<PlyElement>& elements, Encoding enc) {
  std::string out = "ply\nformat " + std::string(formatName(enc)) + " 1.0\ncomment written by ply_test\n";
  out += "obj_info a test model\n";
  for (const PlyElement& e : elements) {
    out += "element " + e.name + " " + std::to_string(e.rows.size()) + "\n";
    for (const PlyProperty& p : e.properties) {
      out += p.countType.empty() ? "property " + p.type + " " + p.name + "\n"
                                 : "property list " + p.countType + " " + p.type + " " + p.name + "\n";
    }
  }
  out += "end_header\n";
  for (const PlyElement& e : elements) {
    for (const PlyRow& row : e.rows) {
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (enc == Encoding::Ascii) {
          if (k) out += ' ';
          if (!p.countType.empty()) {
            out += std::to_string(row[k].size());
            for (double v : row[k]) {
              out += ' ';
              putAscii(out, p.type, v);
            }
          } else {
            putAscii(out, p.type, row[k].at(0));
          }
        } else {
          bool big = enc == Encoding::Big;
          if (!p.countType.empty()) {
            putBinary(out, p.countType, static_cast<double>(row[k].size()), big);
            for (double v : row[k]) putBinary(out, p.type, v, big);
          } else {
            putBinary(out, p.type, row[k].at(0), big);
          }
        }
      }
      if (enc == Encoding::Ascii) out += '\n';
    }
  }
  return out;
}

// ---- The test model --------------------------------------------------------------------------------

// A box's bottom, top and one side as quads, two triangles, and a concave pentagon above it; every
// value exact in float.
struct Model {
  std::vector<dvec3> positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1},   {1, 0, 1}, {1, 1, 1},
                                  {0, 1, 1}, {0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {1, 0.5, 2}, {0, 2, 2}};
  std::vector<std::vector<std::uint32_t>> faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                   {1, 2, 6},    {1, 6, 5},    {8, 9, 10, 11, 12}};
  // Outwards from the middle (appendMesh normalises); exact in float, like every value here.
  dvec3 normal(std::size_t i) const { return positions[i] - dvec3(0.5, 0.5, 0.75); }
  glm::vec2 uv(std::size_t i) const { return {static_cast<float>(i) / 16.0f, 1.0f - static_cast<float>(i) / 32.0f}; }
  int color(std::size_t i, int c) const { return static_cast<int>((i * 37 + static_cast<std::size_t>(c) * 101) % 256); }
};

// The model as PLY elements: vertex properties in an unusual order, among them properties vkray does
// not read (a list too); unknown elements before, between and after the vertices and faces.
std::vector<PlyElement> modelElements(const Model& m) {
  PlyElement range{"range", {{"uint", "spans", "int"}, {"char", "flag", ""}}, {{{1, 2, 3}, {-5}}, {{}, {7}}}};
  PlyElement vertex{"vertex",
                    {{"uchar", "green", ""},
                     {"float", "z", ""},
                     {"float", "junk", "uchar"},
                     {"float", "nx", ""},
                     {"double", "x", ""},
                     {"float", "v", ""},
                     {"int16", "ignored", ""},
                     {"float32", "ny", ""},
                     {"uint8", "red", ""},
                     {"float", "y", ""},
                     {"float", "u", ""},
                     {"double", "nz", ""},
                     {"uchar", "blue", ""},
                     {"uchar", "alpha", ""}},
                    {}};
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    dvec3 p = m.positions[i];
    dvec3 n = m.normal(i);
    glm::vec2 uv = m.uv(i);
    std::vector<double> junk(i % 3, 0.25 * static_cast<double>(i));
    vertex.rows.push_back({{double(m.color(i, 1))},
                           {p.z},
                           junk,
                           {n.x},
                           {p.x},
                           {uv.y},
                           {-static_cast<double>(i)},
                           {n.y},
                           {double(m.color(i, 0))},
                           {p.y},
                           {uv.x},
                           {n.z},
                           {double(m.color(i, 2))},
                           {255}});
  }
  PlyElement edge{"edge", {{"int", "vertex1", ""}, {"int", "vertex2", ""}, {"float", "weights", "ushort"}}, {}};
  for (int i = 0; i < 4; ++i) edge.rows.push_back({{double(i)}, {double(i + 1)}, std::vector<double>(i, 0.5)});
  PlyElement face{
      "face", {{"uchar", "flags", ""}, {"int", "vertex_indices", "uchar"}, {"float", "texcoord", "uchar"}}, {}};
  for (const auto& f : m.faces) {
    std::vector<double> idx(f.begin(), f.end());
    face.rows.push_back({{3}, idx, std::vector<double>(2 * f.size(), 0.5)});
  }
  PlyElement material{"material", {{"float", "shine", ""}, {"uchar", "kind", ""}}, {{{0.5}, {1}}, {{2}, {3}}}};
  return {range, vertex, edge, face, material};
}

class PlyImport : public ::testing::Test {
protected:
  void SetUp() override { dir_ = test::scratchDir("ply-test"); }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& bytes) {
    fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }

  static MeshData read(const fs::path& file, MeshData (*reader)(const MeshRequest&) = readPly) {
    MeshRequest request;
    request.file = file;
    request.shownAs = file.filename().string();
    return reader(request);
  }

  // The one-line message the file is refused with.
  std::string refusal(const std::string& bytes) {
    try {
      read(write("test.ply", bytes));
    } catch (const InputError& e) {
      std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_EQ(what.rfind("test.ply: ", 0), 0u) << what;
      return what;
    }
    ADD_FAILURE() << "accepted";
    return {};
  }

  fs::path dir_;
};

void expectSameMesh(const MeshData& a, const MeshData& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.faceNormals, b.faceNormals);
  EXPECT_EQ(a.texcoords, b.texcoords);
  EXPECT_EQ(a.colors, b.colors);
}

// ---- Encodings -------------------------------------------------------------------------------------

TEST_F(PlyImport, TheThreeEncodingsGiveTheSameMesh) {
  const Model m;
  std::vector<MeshData> meshes;
  for (Encoding e : kEncodings) {
    SCOPED_TRACE(formatName(e));
    meshes.push_back(read(write(std::string(formatName(e)) + ".ply", writePly(modelElements(m), e))));
  }
  const MeshData& mesh = meshes[0];
  for (std::size_t k = 1; k < meshes.size(); ++k) {
    SCOPED_TRACE(formatName(kEncodings[k]));
    expectSameMesh(meshes[k], mesh);
  }

  // And it is the model: positions, normals, texture coordinates, linear colours.
  ASSERT_EQ(mesh.positions, m.positions);
  ASSERT_EQ(mesh.normals.size(), m.positions.size());
  ASSERT_EQ(mesh.texcoords.size(), m.positions.size());
  ASSERT_EQ(mesh.colors.size(), m.positions.size());
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    EXPECT_EQ(mesh.normals[i], m.normal(i));
    EXPECT_EQ(mesh.texcoords[i], glm::dvec4(m.uv(i).x, 1.0 - m.uv(i).y, 0.0, 0.0)) << "v flipped to glTF's down";
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(mesh.colors[i][c], double(srgbToLinear(static_cast<float>(m.color(i, c)) / 255.0f)));
    }
  }
  // Quads split as fans, the concave pentagon (reflex at corner 3) by ear clipping: 2+2+2+1+1+3.
  ASSERT_EQ(mesh.faces.size(), 11u);
  EXPECT_EQ(mesh.faces[0], (std::array<std::uint32_t, 3>{0, 3, 2}));
  EXPECT_EQ(mesh.faces[1], (std::array<std::uint32_t, 3>{0, 2, 1}));
  EXPECT_EQ(mesh.faces[6], (std::array<std::uint32_t, 3>{1, 2, 6}));
  double pentagon = 0.0;
  for (std::size_t f = 8; f < 11; ++f) {
    const auto& t = mesh.faces[f];
    pentagon += 0.5 * glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]).z;
  }
  EXPECT_DOUBLE_EQ(pentagon, 4.0 - 1.5) << "the square less the notch (the fan would cover more)";
  EXPECT_EQ(mesh.faceNormals, mesh.faces) << "PLY normals are per vertex";
  EXPECT_TRUE(mesh.faceMaterials.empty());
}

// The same model written as OBJ (v, vn, f v//vn) reads as the same positions, normals and triangles.
TEST_F(PlyImport, MatchesTheSameModelReadFromObj) {
  const Model m;
  std::ostringstream obj;
  obj.precision(9);
  for (const dvec3& p : m.positions) obj << "v " << p.x << " " << p.y << " " << p.z << "\n";
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    dvec3 n = m.normal(i);
    obj << "vn " << n.x << " " << n.y << " " << n.z << "\n";
  }
  for (const auto& f : m.faces) {
    obj << "f";
    for (std::uint32_t i : f) obj << " " << i + 1 << "//" << i + 1;
    obj << "\n";
  }
  MeshData fromObj = read(write("model.obj", obj.str()), readObj);
  for (Encoding e : kEncodings) {
    SCOPED_TRACE(formatName(e));
    MeshData fromPly = read(write("model.ply", writePly(modelElements(m), e)));
    EXPECT_EQ(fromPly.positions, fromObj.positions);
    EXPECT_EQ(fromPly.faces, fromObj.faces);
    EXPECT_EQ(fromPly.faceNormals, fromObj.faceNormals);
    ASSERT_EQ(fromPly.normals.size(), fromObj.normals.size());
    for (std::size_t i = 0; i < fromObj.normals.size(); ++i) {
      EXPECT_NEAR(glm::length(fromPly.normals[i] - fromObj.normals[i]), 0.0, 1e-7) << "normal " << i;
    }
  }
}

// Every PLY scalar type, by both of its names, as the vertices' coordinates and as the face list's
// count and index types.
TEST_F(PlyImport, EveryScalarTypeReadsItsValues) {
  const char* types[] = {"char", "uchar", "short", "ushort", "int",   "uint",   "float",   "double",
                         "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
  for (const char* type : types) {
    const std::string t = type;
    const bool integer = baseType(t) != "float" && baseType(t) != "double";
    const bool isSigned = baseType(t) == "char" || baseType(t) == "short" || baseType(t) == "int";
    const double a = integer ? (isSigned ? -3 : 3) : -0.375;
    const double b = integer ? 100 : 1.5e3;
    PlyElement vertex{
        "vertex", {{t, "x", ""}, {t, "y", ""}, {t, "z", ""}}, {{{0}, {0}, {0}}, {{a}, {0}, {b}}, {{0}, {b}, {a}}}};
    const std::string listType = integer ? t : "uchar";
    PlyElement face{"face", {{listType, "vertex_index", listType}}, {{{0, 1, 2}}}};
    for (Encoding e : kEncodings) {
      SCOPED_TRACE(t + ", " + formatName(e));
      MeshData mesh = read(write("types.ply", writePly({vertex, face}, e)));
      ASSERT_EQ(mesh.positions.size(), 3u);
      EXPECT_EQ(mesh.positions[1], dvec3(a, 0, b));
      EXPECT_EQ(mesh.positions[2], dvec3(0, b, a));
      ASSERT_EQ(mesh.faces.size(), 1u);
      EXPECT_EQ(mesh.faces[0], (std::array<std::uint32_t, 3>{0, 1, 2}));
    }
  }
}

// Texture coordinates by each of their spellings; float colours (0..1) and ushort colours (0..65535)
// decoded from sRGB like byte ones.
TEST_F(PlyImport, TextureCoordinateSpellingsAndColourTypes) {
  for (auto [u, v] : {std::pair{"u", "v"}, std::pair{"s", "t"}, std::pair{"texture_u", "texture_v"}}) {
    SCOPED_TRACE(u);
    PlyElement vertex{"vertex",
                      {{"float", "x", ""},
                       {"float", "y", ""},
                       {"float", "z", ""},
                       {"float", u, ""},
                       {"float", v, ""},
                       {"float", "red", ""},
                       {"float", "green", ""},
                       {"float", "blue", ""}},
                      {{{0}, {0}, {0}, {0.25}, {0.75}, {0.0}, {0.5}, {1.0}},
                       {{1}, {0}, {0}, {0.5}, {1}, {2.0}, {-1.0}, {0.04}},
                       {{0}, {1}, {0}, {1}, {0}, {1}, {1}, {1}}}};
    PlyElement face{"face", {{"uint", "vertex_indices", "uchar"}}, {{{0, 1, 2}}}};
    MeshData mesh = read(write("uv.ply", writePly({vertex, face}, Encoding::Ascii)));
    ASSERT_EQ(mesh.texcoords.size(), 3u);
    EXPECT_EQ(mesh.texcoords[0], glm::dvec4(0.25, 0.25, 0.0, 0.0));
    EXPECT_EQ(mesh.texcoords[1], glm::dvec4(0.5, 0.0, 0.0, 0.0));
    ASSERT_EQ(mesh.colors.size(), 3u);
    EXPECT_EQ(mesh.colors[0], glm::dvec4(0.0, srgbToLinear(0.5f), 1.0, 1.0));
    EXPECT_EQ(mesh.colors[1], glm::dvec4(1.0, 0.0, 0.04f / 12.92f, 1.0)) << "clamped to 0..1; the linear segment";
  }
  PlyElement vertex{
      "vertex",
      {{"float", "x", ""},
       {"float", "y", ""},
       {"float", "z", ""},
       {"ushort", "red", ""},
       {"ushort", "green", ""},
       {"ushort", "blue", ""}},
      {{{0}, {0}, {0}, {0}, {65535}, {32768}}, {{1}, {0}, {0}, {0}, {0}, {0}}, {{0}, {1}, {0}, {0}, {0}, {0}}}};
  PlyElement face{"face", {{"uint", "vertex_indices", "uchar"}}, {{{0, 1, 2}}}};
  MeshData mesh = read(write("ushort.ply", writePly({vertex, face}, Encoding::Little)));
  ASSERT_EQ(mesh.colors.size(), 3u);
  EXPECT_EQ(mesh.colors[0], glm::dvec4(0.0, 1.0, srgbToLinear(static_cast<float>(32768.0 / 65535.0)), 1.0));
  EXPECT_TRUE(mesh.normals.empty());
  EXPECT_TRUE(mesh.faceNormals.empty());
}

// Through a scene: a .ply mesh object imports, its vertex normals shade.
TEST_F(PlyImport, LoadsAsASceneMesh) {
  const Model m;
  write("model.ply", writePly(modelElements(m), Encoding::Big));
  nlohmann::json scene = {{"camera", {{"position", {0, 0, 10}}, {"look_at", {0, 0, 0}}}},
                          {"objects", {{{"type", "mesh"}, {"file", "model.ply"}}}}};
  Scene s = loadSceneFromString(scene.dump(), "mesh.json", dir_);
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].triangleCount, 11u);
  EXPECT_EQ(s.meshes[0].droppedDegenerate, 0u);
  for (const Triangle& t : s.triangles) EXPECT_TRUE(t.normals);
}

// ---- Broken files ----------------------------------------------------------------------------------

const std::string kTriangleHeader = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n";

TEST_F(PlyImport, BadHeadersAreRefusedWithTheLine) {
  const std::string body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  struct Case {
    std::string text;
    std::string problem;
  };
  const Case cases[] = {
      {"", "not a PLY file (it does not begin with 'ply')"},
      {"plyx\nformat ascii 1.0\n", "not a PLY file"},
      {"ply\nformat ascii 1.0\nelement vertex 3\n", "the header has no end_header line"},
      {"ply\nelement vertex 0\nend_header\n", "the header has no format line"},
      {"ply\nformat binary_middle_endian 1.0\nend_header\n",
       "header line 2: unsupported format 'binary_middle_endian' (vkray reads ascii, binary_little_endian and "
       "binary_big_endian)"},
      {"ply\nformat ascii 2.0\nend_header\n", "header line 2: unsupported PLY version '2.0'"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nCreated by hand\nend_header\n",
       "header line 4: 'Created' is not a PLY header keyword (a comment line begins with 'comment')"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "header line 3: a property before any element"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float16 x\nend_header\n",
       "header line 4: 'float16' is not a PLY type"},
      {"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "header line 3: element 'vertex': the count '-3'"},
      {"ply\nformat ascii 1.0\nelement v\x01rtex 3\nend_header\n",
       "header line 3: the name 'v?rtex' is not printable ASCII"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n",
       "header line 4: list 'vertex_indices': its count type must be an integer type"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\nend_header\n",
       "header line 5: element 'vertex' has a second property 'x'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 1\n"
       "property list uchar int vertex_indices\nend_header\n",
       "vertex has 'x' but no 'z'"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar float vertex_indices\nend_header\n",
       "face 'vertex_indices' has float items; indices must be integers"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty uchar flags\nend_header\n",
       "header line 7: face has no vertex_indices (or vertex_index) list"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "property int red\nproperty int green\nproperty int blue\nelement face 1\n"
       "property list uchar int vertex_indices\nend_header\n",
       "header line 7: colour 'red' is int; vkray reads colours as uchar or ushort"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    std::string what = refusal(c.text.find("end_header") == std::string::npos ? c.text : c.text + body);
    EXPECT_NE(what.find(c.problem), std::string::npos) << what << "\nexpected: " << c.problem;
  }
}

// A point cloud is refused by name, from its header alone.
TEST_F(PlyImport, PointCloudsAreRefusedByName) {
  for (const char* text : {"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty "
                           "float z\nend_header\n0 0 0\n1 1 1\n",
                           "ply\nformat binary_little_endian 1.0\nelement vertex 1000000\nproperty float x\n"
                           "property float y\nproperty float z\nelement face 0\nproperty list uchar int "
                           "vertex_indices\nend_header\n"}) {
    EXPECT_EQ(refusal(text), "test.ply: has no faces (a point cloud); vkray renders surfaces");
  }
  EXPECT_EQ(refusal("ply\nformat ascii 1.0\nend_header\n"), "test.ply: has no vertices and no faces");
}

// Element counts beyond what the file's size can hold are refused before anything is allocated.
TEST_F(PlyImport, AbsurdCountsAreRefusedBeforeReading) {
  std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\nproperty list uchar int "
                       "vertex_indices\nend_header\n";
  std::string what = refusal(header + std::string(64, '\0'));
  EXPECT_NE(what.find("header line 3: element 'vertex' declares 4000000000 entries, more than the file's"),
            std::string::npos)
      << what;
  what = refusal("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 16777216\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n"
                 "0 1 0\n");
  EXPECT_NE(what.find("element 'face' declares 16777216 entries"), std::string::npos) << what;
  what = refusal("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 16777217\nproperty list uchar int vertex_indices\nend_header\n");
  EXPECT_NE(what.find("header line 7: 16777217 faces are more than the scene limit of 16777216 primitives"),
            std::string::npos)
      << what;
  // A face takes at least its count and three indices: 1 + 3 * 4 bytes here, so 1000 of them need
  // more than 10000 bytes.
  what = refusal("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1000\nproperty list uchar int vertex_indices\nend_header\n" +
                 std::string(36 + 10000, '\0'));
  EXPECT_NE(what.find("element 'face' declares 1000 entries, more than the file's"), std::string::npos) << what;
  what = refusal("ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nelement nothing 99999999999\nelement face 1\nproperty list uchar int "
                 "vertex_indices\nend_header\n");
  EXPECT_NE(what.find("header line 7: element 'nothing' has 99999999999 entries but no properties"), std::string::npos)
      << what;
}

// Damage in the body: the line (ASCII) or the byte (binary), the element and entry, and what.
TEST_F(PlyImport, BadBodiesAreRefusedWithTheEntry) {
  struct Case {
    std::string body;
    std::string problem;
  };
  const Case cases[] = {
      {"0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "line 13: face 0: vertex index 7 is out of range (the file has 3 vertices)"},
      {"0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "line 13: face 0: vertex index -1 is out of range"},
      {"0 0 0\n1 0 0\n0 1 0\n2 0 1    \n", "line 13: face 0: has 2 vertices (a face needs at least 3)"},
      // Too short to hold the entries at all: refused before reading.
      {"0 0 0\n1 0 0\n", "header line 3: element 'vertex' declares 3 entries, more than the file's"},
      // Long enough, but lines short.
      {"0 0 0                    \n1 0 0                    \n",
       "line 12: the file ends before vertex 2 of 3 (truncated?)"},
      {"0 0 0\n1 0 0\n0 1 0         \n", "line 13: the file ends before face 0 of 1 (truncated?)"},
      {"0 0 0\n1 0\n0 1 0\n3 0 1 2  \n", "line 11: vertex 1: too few values (the line ends before z)"},
      {"0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n", "line 11: vertex 1: more values than the header's 3 properties"},
      {"0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n", "line 11: vertex 1: y: 'abc' is not a number"},
      {"0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "line 11: vertex 1: not finite (NaN or Inf)"},
      {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", "line 13: face 0: vertex_indices: '2.5' is not an integer (int)"},
      {"0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n", "line 13: face 0: vertex_indices: '300' is out of range for uchar"},
      {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "line 14: more data after the last element the header declares"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.body);
    std::string what = refusal(kTriangleHeader + c.body);
    EXPECT_NE(what.find(c.problem), std::string::npos) << what << "\nexpected: " << c.problem;
  }
  // Blank lines and a last line without its newline are fine.
  MeshData mesh = read(write("ok.ply", kTriangleHeader + "0 0 0\n\n1 0 0\n0 1 0\r\n3 0 1 2"));
  EXPECT_EQ(mesh.faces.size(), 1u);
}

TEST_F(PlyImport, BadBinaryBodiesAreRefusedWithTheByte) {
  PlyElement vertex{"vertex",
                    {{"float", "x", ""}, {"float", "y", ""}, {"float", "z", ""}},
                    {{{0}, {0}, {0}}, {{1}, {0}, {0}}, {{0}, {1}, {0}}}};
  PlyElement face{"face", {{"int", "vertex_indices", "uchar"}}, {{{0, 1, 2}}, {{0, 2, 3}}}};
  PlyElement edge{"edge", {{"int", "a", ""}, {"int", "b", "uint"}}, {{{0}, {1, 2}}}};
  for (Encoding e : {Encoding::Little, Encoding::Big}) {
    SCOPED_TRACE(formatName(e));
    std::string good = writePly({vertex, face}, e);
    std::string what = refusal(good);
    EXPECT_NE(what.find("face 1 (byte "), std::string::npos) << what;
    EXPECT_NE(what.find("vertex index 3 is out of range (the file has 3 vertices)"), std::string::npos) << what;

    face.rows = {{{0, 1, 2, 0}}}; // 17 bytes, cut to 14: more than a triangle's 13
    good = writePly({vertex, face}, e);
    EXPECT_NO_THROW(read(write("ok.ply", good)));
    what = refusal(good.substr(0, good.size() - 3));
    EXPECT_NE(what.find("face 0 (byte"), std::string::npos) << what;
    EXPECT_NE(what.find("the file ends inside it (truncated?)"), std::string::npos) << what;
    EXPECT_NE(refusal(good + "xy").find("2 bytes after the last element the header declares"), std::string::npos);
    // An unknown element with a list, truncated; and one of fixed size, truncated.
    std::string withEdge = writePly({vertex, edge, face}, e);
    EXPECT_NO_THROW(read(write("ok.ply", withEdge)));
    std::string cut = writePly({vertex, face, edge}, e);
    what = refusal(cut.substr(0, cut.size() - 2));
    EXPECT_NE(what.find("edge 0 (byte"), std::string::npos) << what;
    edge.properties.pop_back();
    edge.rows = {{{0}}, {{1}}};
    cut = writePly({vertex, edge, face}, e);
    what = refusal(cut.substr(0, cut.size() - 21));
    EXPECT_NE(what.find("element 'edge' declares 2 entries, more than the file's"), std::string::npos) << what;
    edge = {"edge", {{"int", "a", ""}, {"int", "b", "uint"}}, {{{0}, {1, 2}}}};
    face.rows = {{{0, 1, 2}}, {{0, 2, 3}}};
  }
}

// ---- Real files --------------------------------------------------------------------------------------

// assimp's PLY test models: each loads, or is refused with one line saying why.
TEST_F(PlyImport, AssimpTestModelsLoadOrAreRefusedWithOneLine) {
  fs::path dir = kAssimpModels / "PLY";
  if (!fs::exists(dir)) GTEST_SKIP() << dir << " is absent (apt-get install assimp-testmodels)";
  struct Expected {
    std::size_t triangles; // 0: refused
    const char* problem;
  };
  const std::map<std::string, Expected> expected = {
      {"cube.ply", {12, ""}},
      {"cube_binary.ply", {12, ""}},
      {"cube_uv.ply", {12, ""}},
      {"float-color.ply", {1, ""}},
      // Blender 2.47's exporter wrote its credit line without "comment": read as one.
      {"Wuson.ply", {3732, ""}},
      // Its header declares no face element (the list is on the vertices).
      {"issue623.ply", {0, "has no faces (a point cloud); vkray renders surfaces"}},
      {"points.ply", {0, "has no faces (a point cloud); vkray renders surfaces"}},
      {"pond.0.ply", {0, "has no faces (a point cloud); vkray renders surfaces"}},
  };
  int seen = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".ply") continue;
    SCOPED_TRACE(name);
    ++seen;
    MeshRequest request;
    request.file = entry.path();
    request.shownAs = name;
    auto it = expected.find(name);
    try {
      Scene scene;
      importMesh(request, scene);
      EXPECT_TRUE(it == expected.end() || it->second.triangles == scene.triangles.size())
          << "loaded " << scene.triangles.size() << " triangles";
    } catch (const InputError& e) {
      std::string what = e.what();
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_TRUE(it == expected.end() ||
                  (it->second.triangles == 0 && what.find(it->second.problem) != std::string::npos))
          << what;
    }
  }
  EXPECT_GE(seen, 8);
}

// Wuson.ply and WusonOBJ.obj are one model (3732 triangles; the PLY has a vertex per corner, the OBJ
// shares them). Its stray header line (no 'comment') read as a comment, the triangles agree to the
// precision of the PLY's floats, face by face.
TEST_F(PlyImport, WusonMatchesWusonObj) {
  fs::path ply = kAssimpModels / "PLY" / "Wuson.ply";
  fs::path obj = kAssimpModels / "OBJ" / "WusonOBJ.obj";
  if (!fs::exists(ply) || !fs::exists(obj)) GTEST_SKIP() << "assimp's test models are absent";
  MeshData fromPly = read(ply, readPly);
  MeshData fromObj = read(obj, readObj);
  ASSERT_EQ(fromPly.faces.size(), 3732u);
  ASSERT_EQ(fromObj.faces.size(), fromPly.faces.size());
  EXPECT_EQ(fromPly.texcoords.size(), fromPly.positions.size()) << "s, t";
  EXPECT_EQ(fromPly.normals.size(), fromPly.positions.size());
  double worst = 0.0;
  for (std::size_t f = 0; f < fromPly.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      dvec3 a = fromPly.positions[fromPly.faces[f][static_cast<std::size_t>(k)]];
      dvec3 b = fromObj.positions[fromObj.faces[f][static_cast<std::size_t>(k)]];
      worst = std::max(worst, glm::length(a - b));
    }
  }
  EXPECT_LT(worst, 1e-6) << "the farthest corner apart";
}

} // namespace
} // namespace vkray
