// glTF 2.0 (.gltf with external or embedded buffers, .glb) through tinygltf. tinygltf parses the
// JSON and loads the buffers; everything read out of them (accessor ranges, strides, indices,
// node references) is checked here before it is touched, so a broken file is an error, never a
// read out of bounds.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "scene/json_reader.h"
#include "scene/mesh_import.h"
#include "util/error.h"
#include "util/file_extension.h"

namespace vkray {

namespace {

using glm::dvec3;

// Extensions a file may require that vkray honours or that do not change what it renders.
const char* const kSupportedRequired[] = {"KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior",
                                          "KHR_materials_emissive_strength", "KHR_texture_transform"};

// tinygltf hands over each image's encoded bytes (from a file, a data URI or a .glb buffer view);
// they are kept as they are and decoded by vkray (scene/texture.h), only for images a material uses.
// Bytes from a buffer view are not copied here: tinygltf does not check the view against its buffer
// (a view past the buffer's end would be read out of bounds), so decodeGltfImage reads views itself.
bool keepImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                    int size, void*) {
  if (image->bufferView < 0 && size > 0) image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

TextureMinFilter minFilter(int gl) {
  switch (gl) {
  case TINYGLTF_TEXTURE_FILTER_NEAREST:
    return TextureMinFilter::Nearest;
  case TINYGLTF_TEXTURE_FILTER_LINEAR:
    return TextureMinFilter::Linear;
  case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST:
    return TextureMinFilter::NearestLevelNearest;
  case TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_NEAREST:
    return TextureMinFilter::NearestLevel;
  case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR:
    return TextureMinFilter::NearestBetweenLevels;
  default: // LINEAR_MIPMAP_LINEAR, or undefined (-1): the best the kernel has
    return TextureMinFilter::Trilinear;
  }
}

TextureWrap wrapMode(int gl) {
  if (gl == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return TextureWrap::Clamp;
  if (gl == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return TextureWrap::Mirror;
  return TextureWrap::Repeat;
}

std::string firstLine(const std::string& s) {
  std::string line = s.substr(0, s.find('\n'));
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

const char* componentName(int type) {
  switch (type) {
  case TINYGLTF_COMPONENT_TYPE_BYTE:
    return "BYTE";
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
    return "UNSIGNED_BYTE";
  case TINYGLTF_COMPONENT_TYPE_SHORT:
    return "SHORT";
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
    return "UNSIGNED_SHORT";
  case TINYGLTF_COMPONENT_TYPE_INT:
    return "INT";
  case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    return "UNSIGNED_INT";
  case TINYGLTF_COMPONENT_TYPE_FLOAT:
    return "FLOAT";
  case TINYGLTF_COMPONENT_TYPE_DOUBLE:
    return "DOUBLE";
  default:
    return "unknown";
  }
}

// A checked window onto an accessor's elements.
struct AccessorView {
  const unsigned char* data = nullptr;
  std::size_t stride = 0;
  std::size_t count = 0;
  int componentType = 0;
  bool normalized = false;

  // Component k of element i: float, or normalized unsigned byte or short (TEXCOORD_n, COLOR_0).
  double component(std::size_t i, int k) const {
    const unsigned char* p = data + i * stride;
    if (componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) return p[k] / 255.0;
    if (componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
      std::uint16_t v;
      std::memcpy(&v, p + 2 * k, sizeof v);
      return v / 65535.0;
    }
    float f;
    std::memcpy(&f, p + 4 * k, sizeof f);
    return f;
  }

  // A float, normalized unsigned byte or normalized unsigned short vec2 (TEXCOORD_n).
  glm::dvec2 vec2(std::size_t i) const {
    const unsigned char* p = data + i * stride;
    if (componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) return glm::dvec2(p[0], p[1]) / 255.0;
    if (componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
      std::uint16_t v[2];
      std::memcpy(v, p, sizeof v);
      return glm::dvec2(v[0], v[1]) / 65535.0;
    }
    float f[2];
    std::memcpy(f, p, sizeof f);
    return glm::dvec2(f[0], f[1]);
  }

  dvec3 vec3(std::size_t i) const {
    float f[3];
    std::memcpy(f, data + i * stride, sizeof f); // glTF data need not be aligned
    return dvec3(f[0], f[1], f[2]);
  }
  std::uint32_t index(std::size_t i) const {
    const unsigned char* p = data + i * stride;
    if (componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) return *p;
    if (componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
      std::uint16_t v;
      std::memcpy(&v, p, sizeof v);
      return v;
    }
    std::uint32_t v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }
};

// ---- Before tinygltf -------------------------------------------------------------------------
// tinygltf skips members of the wrong JSON type without a word (an object where `primitives` must be
// an array leaves a mesh with no primitives), and it resolves Draco primitives' accessors before
// anyone can say the file is Draco-compressed. So the JSON is read here first: the members vkray
// uses are checked for their type, with their JSON path, and unsupported extensions are named.

enum class JsonKind { Object, Array, Integer, Number, String, Boolean };

const char* kindName(JsonKind k) {
  switch (k) {
  case JsonKind::Object:
    return "an object";
  case JsonKind::Array:
    return "an array";
  case JsonKind::Integer:
    return "an integer";
  case JsonKind::Number:
    return "a number";
  case JsonKind::String:
    return "a string";
  default:
    return "a boolean";
  }
}

bool isKind(const nlohmann::json& v, JsonKind k) {
  switch (k) {
  case JsonKind::Object:
    return v.is_object();
  case JsonKind::Array:
    return v.is_array();
  case JsonKind::Integer:
    return v.is_number_integer() || (v.is_number_float() && v.get<double>() == std::floor(v.get<double>()));
  case JsonKind::Number:
    return v.is_number();
  case JsonKind::String:
    return v.is_string();
  default:
    return v.is_boolean();
  }
}

class GltfPreflight {
public:
  GltfPreflight(const nlohmann::json& doc, const std::string& where) : doc_(doc), where_(where) {}

  void check() {
    if (!doc_.is_object()) fail("(top level)", "must be an object");
    checkVersion();
    for (const char* list : {"extensionsRequired", "extensionsUsed"}) {
      if (const auto* v = member(doc_, list, JsonKind::Array, list)) {
        for (std::size_t i = 0; i < v->size(); ++i) {
          need((*v)[i], JsonKind::String, std::string(list) + "[" + std::to_string(i) + "]");
        }
      }
    }
    if (const auto* req = member(doc_, "extensionsRequired", JsonKind::Array, "extensionsRequired")) {
      for (std::size_t i = 0; i < req->size(); ++i) {
        std::string ext = (*req)[i].get<std::string>();
        std::string path = "extensionsRequired[" + std::to_string(i) + "]";
        if (ext == "KHR_draco_mesh_compression") {
          fail(path, "the file requires KHR_draco_mesh_compression (Draco-compressed geometry), which vkray does not "
                     "decode (re-export it without Draco compression)");
        }
        if (std::find(std::begin(kSupportedRequired), std::end(kSupportedRequired), ext) ==
            std::end(kSupportedRequired)) {
          fail(path, "the file requires extension '" + ext + "', which vkray does not support");
        }
      }
    }
    member(doc_, "scene", JsonKind::Integer, "scene");
    eachObject("scenes", [&](const nlohmann::json& s, const std::string& p) { integers(s, "nodes", p); });
    eachObject("nodes", [&](const nlohmann::json& n, const std::string& p) {
      integers(n, "children", p);
      for (const char* k : {"mesh", "camera"}) member(n, k, JsonKind::Integer, p + "." + k);
      for (const char* k : {"matrix", "translation", "rotation", "scale"}) numbers(n, k, p);
    });
    eachObject("meshes", [&](const nlohmann::json& m, const std::string& p) {
      const auto* prims = member(m, "primitives", JsonKind::Array, p + ".primitives");
      if (!prims) fail(p, "missing required key 'primitives'");
      for (std::size_t i = 0; i < prims->size(); ++i) {
        std::string pp = p + ".primitives[" + std::to_string(i) + "]";
        const auto& prim = (*prims)[i];
        need(prim, JsonKind::Object, pp);
        if (const auto* attrs = member(prim, "attributes", JsonKind::Object, pp + ".attributes")) {
          for (auto it = attrs->begin(); it != attrs->end(); ++it) {
            need(it.value(), JsonKind::Integer, pp + ".attributes." + it.key());
          }
        }
        for (const char* k : {"indices", "material", "mode"}) member(prim, k, JsonKind::Integer, pp + "." + k);
        if (const auto* ext = member(prim, "extensions", JsonKind::Object, pp + ".extensions")) {
          if (ext->contains("KHR_draco_mesh_compression")) {
            fail(pp + ".extensions.KHR_draco_mesh_compression",
                 "the primitive is Draco-compressed, which vkray does not decode (re-export it without Draco "
                 "compression)");
          }
        }
      }
    });
    eachObject("accessors", [&](const nlohmann::json& a, const std::string& p) {
      for (const char* k : {"bufferView", "byteOffset", "componentType", "count"}) {
        member(a, k, JsonKind::Integer, p + "." + k);
      }
      member(a, "type", JsonKind::String, p + ".type");
      member(a, "sparse", JsonKind::Object, p + ".sparse");
    });
    eachObject("bufferViews", [&](const nlohmann::json& b, const std::string& p) {
      for (const char* k : {"buffer", "byteOffset", "byteLength", "byteStride"}) {
        member(b, k, JsonKind::Integer, p + "." + k);
      }
    });
    eachObject("buffers", [&](const nlohmann::json& b, const std::string& p) {
      member(b, "byteLength", JsonKind::Integer, p + ".byteLength");
      member(b, "uri", JsonKind::String, p + ".uri");
    });
    eachObject("materials", [&](const nlohmann::json& m, const std::string& p) {
      member(m, "alphaMode", JsonKind::String, p + ".alphaMode");
      if (const auto* pbr = member(m, "pbrMetallicRoughness", JsonKind::Object, p + ".pbrMetallicRoughness")) {
        std::string pp = p + ".pbrMetallicRoughness";
        numbers(*pbr, "baseColorFactor", pp);
        for (const char* k : {"metallicFactor", "roughnessFactor"}) member(*pbr, k, JsonKind::Number, pp + "." + k);
      }
    });
    eachObject("cameras", [&](const nlohmann::json& c, const std::string& p) {
      member(c, "type", JsonKind::String, p + ".type");
      member(c, "perspective", JsonKind::Object, p + ".perspective");
    });
  }

private:
  [[noreturn]] void fail(const std::string& path, const std::string& problem) const {
    throw InputError(where_, path + ": " + problem);
  }
  // glTF 1.0 (2015) has the same extension and a different schema (objects keyed by name, `scene`
  // a string): name the version instead of its first type mismatch. A 2.0 reader must refuse a
  // major version it does not know (glTF 2.0 sec. 3.2); a missing version is left to the rest.
  void checkVersion() const {
    const auto asset = doc_.find("asset");
    if (asset == doc_.end() || !asset->is_object()) return;
    const auto version = asset->find("version");
    if (version == asset->end()) return;
    std::string text;
    if (version->is_string())
      text = version->get<std::string>();
    else if (version->is_number())
      text = version->dump();
    else
      fail("asset.version", "must be a string, got " + typeOf(*version));
    if (text.rfind("2.", 0) == 0 || text == "2") return;
    const std::string major = text.substr(0, text.find('.'));
    fail("asset.version", "is '" + text + "': a glTF " + (major == "1" ? std::string("1.0") : major) +
                              " file; vkray reads glTF 2.0 (re-export or convert the model to glTF 2.0)");
  }
  void need(const nlohmann::json& v, JsonKind k, const std::string& path) const {
    if (!isKind(v, k)) fail(path, std::string("must be ") + kindName(k) + ", got " + typeOf(v));
  }
  static std::string typeOf(const nlohmann::json& v) {
    if (v.is_object()) return "an object";
    if (v.is_array()) return "an array";
    if (v.is_string()) return "a string";
    if (v.is_boolean()) return "a boolean";
    if (v.is_null()) return "null";
    return "a number";
  }
  // The member if present, checked for its kind.
  const nlohmann::json* member(const nlohmann::json& obj, const char* key, JsonKind k, const std::string& path) const {
    auto it = obj.find(key);
    if (it == obj.end()) return nullptr;
    need(*it, k, path);
    return &*it;
  }
  void integers(const nlohmann::json& obj, const char* key, const std::string& parent) const {
    std::string path = parent + "." + key;
    if (const auto* v = member(obj, key, JsonKind::Array, path)) {
      for (std::size_t i = 0; i < v->size(); ++i)
        need((*v)[i], JsonKind::Integer, path + "[" + std::to_string(i) + "]");
    }
  }
  void numbers(const nlohmann::json& obj, const char* key, const std::string& parent) const {
    std::string path = parent + "." + key;
    if (const auto* v = member(obj, key, JsonKind::Array, path)) {
      for (std::size_t i = 0; i < v->size(); ++i) need((*v)[i], JsonKind::Number, path + "[" + std::to_string(i) + "]");
    }
  }
  template <class F> void eachObject(const char* list, F&& f) const {
    const auto* v = member(doc_, list, JsonKind::Array, list);
    if (!v) return;
    for (std::size_t i = 0; i < v->size(); ++i) {
      std::string path = std::string(list) + "[" + std::to_string(i) + "]";
      need((*v)[i], JsonKind::Object, path);
      f((*v)[i], path);
    }
  }

  const nlohmann::json& doc_;
  const std::string& where_;
};

// The file's JSON: the whole of a .gltf, the first chunk of a .glb (glTF 2.0 sec. 4.4). Empty when
// a .glb is too broken to find it (tinygltf then says why); a binary glTF 1.0 is refused here.
std::string gltfJson(const std::filesystem::path& file, bool binary, const std::string& shownAs) {
  std::ifstream in(file, std::ios::binary);
  if (!binary) return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  unsigned char header[20];
  if (!in.read(reinterpret_cast<char*>(header), sizeof header)) return {};
  auto u32 = [&](int at) {
    std::uint32_t v;
    std::memcpy(&v, header + at, sizeof v);
    return v;
  };
  if (std::memcmp(header, "glTF", 4) != 0) return {};
  // Binary glTF 1.0 (KHR_binary_glTF) has version 1 here and no chunk types.
  if (const std::uint32_t version = u32(4); version != 2)
    throw InputError(shownAs, "is binary glTF " + std::string(version == 1 ? "1.0" : std::to_string(version)) +
                                  " (its header says version " + std::to_string(version) +
                                  "); vkray reads glTF 2.0 (re-export or convert the model to glTF 2.0)");
  if (std::memcmp(header + 16, "JSON", 4) != 0) return {};
  std::uint32_t length = u32(12);
  if (length > u32(8)) return {};
  std::string json(length, '\0');
  if (!in.read(json.data(), length)) return {};
  return json;
}

class GltfReader {
public:
  GltfReader(const MeshRequest& request, const tinygltf::Model& model) : request_(request), model_(model) {}

  MeshData read() {
    for (std::size_t i = 0; i < model_.materials.size(); ++i) data_.materials.push_back(mapMaterial(i));
    if (std::string unread = unreadMaterialInputs(); !unread.empty()) data_.warnings.push_back(unread);

    // The default scene, else the first; a file without scenes shows every root node.
    std::vector<int> roots;
    int sceneIndex = model_.defaultScene >= 0 ? model_.defaultScene : (model_.scenes.empty() ? -1 : 0);
    if (sceneIndex >= 0) {
      if (static_cast<std::size_t>(sceneIndex) >= model_.scenes.size())
        fail("scene " + std::to_string(sceneIndex) + " does not exist");
      roots = model_.scenes[static_cast<std::size_t>(sceneIndex)].nodes;
    } else {
      std::vector<bool> isChild(model_.nodes.size(), false);
      for (const auto& n : model_.nodes) {
        for (int c : n.children) {
          if (c >= 0 && static_cast<std::size_t>(c) < isChild.size()) isChild[static_cast<std::size_t>(c)] = true;
        }
      }
      for (std::size_t i = 0; i < isChild.size(); ++i) {
        if (!isChild[i]) roots.push_back(static_cast<int>(i));
      }
    }
    visited_.assign(model_.nodes.size(), false);
    for (int root : roots) visit(root, glm::dmat4(1.0), "scenes[" + std::to_string(sceneIndex) + "].nodes");

    if (request_.importCamera && !data_.camera) fail("import_camera: the file's scene has no camera");
    if (request_.importLights && data_.lights.empty()) fail("import_lights: the file's scene has no lights");
    return std::move(data_);
  }

private:
  [[noreturn]] void fail(const std::string& problem) const { throw InputError(request_.shownAs, problem); }

  // Depth-first over the node tree; every node at most once (glTF requires a tree, and a cycle
  // must not hang the reader).
  void visit(int index, const glm::dmat4& parent, const std::string& from) {
    if (index < 0 || static_cast<std::size_t>(index) >= model_.nodes.size()) {
      fail(from + " refers to node " + std::to_string(index) + ", which does not exist");
    }
    auto i = static_cast<std::size_t>(index);
    if (visited_[i]) fail("node " + std::to_string(index) + " is reached twice (a cycle or a shared child)");
    visited_[i] = true;
    const tinygltf::Node& node = model_.nodes[i];
    const std::string where = "nodes[" + std::to_string(index) + "]";
    glm::dmat4 world = parent * localMatrix(node, where);
    if (node.mesh >= 0) {
      if (static_cast<std::size_t>(node.mesh) >= model_.meshes.size())
        fail(where + ".mesh: no mesh " + std::to_string(node.mesh));
      readMesh(static_cast<std::size_t>(node.mesh), world);
    }
    if ((request_.importCamera || request_.importPresent) && node.camera >= 0 && !data_.camera) {
      readCamera(node, world, where);
    }
    if (request_.importLights || request_.importPresent) readLight(node, world, where);
    for (int child : node.children) visit(child, world, where + ".children");
  }

  glm::dmat4 localMatrix(const tinygltf::Node& node, const std::string& where) const {
    glm::dmat4 m(1.0);
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) fail(where + ".matrix must have 16 numbers");
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[static_cast<std::size_t>(c * 4 + r)]; // column-major
      }
      if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) {
        fail(where + ".matrix is not affine (its last row must be 0 0 0 1)");
      }
    } else {
      if (!node.translation.empty()) {
        if (node.translation.size() != 3) fail(where + ".translation must have 3 numbers");
        m = glm::translate(m, dvec3(node.translation[0], node.translation[1], node.translation[2]));
      }
      if (!node.rotation.empty()) {
        if (node.rotation.size() != 4) fail(where + ".rotation must have 4 numbers");
        glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]); // glTF: x y z w
        double len = glm::length(q);
        if (!(len > 0.0)) fail(where + ".rotation is not a unit quaternion");
        m = m * glm::mat4_cast(q / len);
      }
      if (!node.scale.empty()) {
        if (node.scale.size() != 3) fail(where + ".scale must have 3 numbers");
        m = glm::scale(m, dvec3(node.scale[0], node.scale[1], node.scale[2]));
      }
    }
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) {
        if (!std::isfinite(m[c][r])) fail(where + " has a non-finite transform");
      }
    }
    return m;
  }

  AccessorView view(int accessorIndex, const std::string& what, int type, std::initializer_list<int> components) const {
    if (accessorIndex < 0 || static_cast<std::size_t>(accessorIndex) >= model_.accessors.size()) {
      fail(what + " refers to accessor " + std::to_string(accessorIndex) + ", which does not exist");
    }
    const tinygltf::Accessor& a = model_.accessors[static_cast<std::size_t>(accessorIndex)];
    const std::string name = "accessors[" + std::to_string(accessorIndex) + "] (" + what + ")";
    if (a.sparse.isSparse) fail(name + " is sparse, which vkray does not support");
    if (a.type != type) fail(name + " has the wrong type for " + what);
    if (std::find(components.begin(), components.end(), a.componentType) == components.end()) {
      fail(name + " has component type " + componentName(a.componentType) + ", which " + what + " cannot have");
    }
    if (a.bufferView < 0) fail(name + " has no bufferView (no data)");
    if (static_cast<std::size_t>(a.bufferView) >= model_.bufferViews.size()) {
      fail(name + " refers to bufferView " + std::to_string(a.bufferView) + ", which does not exist");
    }
    const tinygltf::BufferView& bv = model_.bufferViews[static_cast<std::size_t>(a.bufferView)];
    const std::string bvName = "bufferViews[" + std::to_string(a.bufferView) + "]";
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model_.buffers.size()) {
      fail(bvName + " refers to buffer " + std::to_string(bv.buffer) + ", which does not exist");
    }
    const tinygltf::Buffer& buffer = model_.buffers[static_cast<std::size_t>(bv.buffer)];
    if (bv.byteOffset > buffer.data.size() || bv.byteLength > buffer.data.size() - bv.byteOffset) {
      fail(bvName + " reaches past the end of buffer " + std::to_string(bv.buffer) + " (" +
           std::to_string(buffer.data.size()) + " bytes)");
    }
    std::size_t element =
        static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(a.componentType))) *
        static_cast<std::size_t>(tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type)));
    std::size_t stride = bv.byteStride ? bv.byteStride : element;
    if (stride < element) fail(bvName + ".byteStride " + std::to_string(bv.byteStride) + " is smaller than an element");
    AccessorView v;
    v.stride = stride;
    v.count = a.count;
    v.componentType = a.componentType;
    if (a.count > 0) {
      // Overflow-safe: (count - 1) * stride + element <= byteLength - byteOffset.
      if (a.byteOffset > bv.byteLength || element > bv.byteLength - a.byteOffset ||
          (a.count - 1) > (bv.byteLength - a.byteOffset - element) / stride) {
        fail(name + ": " + std::to_string(a.count) + " elements do not fit " + bvName + " (" +
             std::to_string(bv.byteLength) + " bytes)");
      }
      v.data = buffer.data.data() + bv.byteOffset + a.byteOffset;
    }
    return v;
  }

  void readMesh(std::size_t meshIndex, const glm::dmat4& world) {
    const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
    const glm::dmat3 normalMatrix = glm::transpose(glm::inverse(glm::dmat3(world)));
    for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = mesh.primitives[p];
      const std::string where = "meshes[" + std::to_string(meshIndex) + "].primitives[" + std::to_string(p) + "]";
      // Points and lines are not surfaces: nothing for a ray to hit.
      if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          prim.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        if (prim.mode >= TINYGLTF_MODE_POINTS && prim.mode <= TINYGLTF_MODE_LINE_STRIP) {
          data_.noTrianglesReason = "its primitives are points or lines only (mode " + std::to_string(prim.mode) +
                                    "), which are not surfaces";
          continue;
        }
        fail(where + ".mode " + std::to_string(prim.mode) + " is not a glTF primitive mode");
      }
      auto pos = prim.attributes.find("POSITION");
      if (pos == prim.attributes.end()) fail(where + " has no POSITION attribute");
      AccessorView positions =
          view(pos->second, where + " POSITION", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
      std::optional<AccessorView> normals;
      if (auto nrm = prim.attributes.find("NORMAL"); nrm != prim.attributes.end()) {
        normals = view(nrm->second, where + " NORMAL", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT});
        if (normals->count != positions.count) {
          fail(where + " has " + std::to_string(normals->count) + " normals for " + std::to_string(positions.count) +
               " positions");
        }
      }
      std::optional<AccessorView> uvSets[2];
      for (int set = 0; set < 2; ++set) {
        const std::string name = "TEXCOORD_" + std::to_string(set);
        auto uv = prim.attributes.find(name);
        if (uv == prim.attributes.end()) continue;
        uvSets[set] = view(uv->second, where + " " + name, TINYGLTF_TYPE_VEC2,
                           {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                            TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
        if (uvSets[set]->count != positions.count) {
          fail(where + " has " + std::to_string(uvSets[set]->count) + " " + name + " for " +
               std::to_string(positions.count) + " positions");
        }
      }
      // COLOR_0: linear RGB or RGBA (glTF colours are linear), float or normalized integers.
      std::optional<AccessorView> colors;
      int colorComponents = 0;
      if (auto col = prim.attributes.find("COLOR_0"); col != prim.attributes.end()) {
        const int index = col->second;
        bool rgba = index >= 0 && static_cast<std::size_t>(index) < model_.accessors.size() &&
                    model_.accessors[static_cast<std::size_t>(index)].type == TINYGLTF_TYPE_VEC4;
        colorComponents = rgba ? 4 : 3;
        colors = view(index, where + " COLOR_0", rgba ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3,
                      {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                       TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT});
        if (colors->count != positions.count) {
          fail(where + " has " + std::to_string(colors->count) + " COLOR_0 for " + std::to_string(positions.count) +
               " positions");
        }
      }
      const bool withColors = colors || !data_.colors.empty();
      if (withColors) data_.colors.resize(data_.positions.size(), glm::dvec4(1.0));
      // Texture coordinates run parallel to the positions once some primitive has them.
      const bool withUvs = uvSets[0] || uvSets[1] || !data_.texcoords.empty();
      if (withUvs) data_.texcoords.resize(data_.positions.size());
      auto base = static_cast<std::uint32_t>(data_.positions.size());
      if (data_.positions.size() + positions.count > 0xFFFFFFF0u) fail("too many vertices");
      for (std::size_t i = 0; i < positions.count; ++i) {
        dvec3 v = positions.vec3(i);
        if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z))) {
          fail(where + " POSITION " + std::to_string(i) + " is not finite (NaN or Inf)");
        }
        data_.positions.push_back(dvec3(world * glm::dvec4(v, 1.0)));
        // Non-finite normals are kept: the face falls back to flat shading (mesh_import.cpp).
        if (normals) data_.normals.push_back(normalMatrix * normals->vec3(i));
        if (withUvs) {
          glm::dvec2 a = uvSets[0] ? uvSets[0]->vec2(i) : glm::dvec2(0.0);
          glm::dvec2 b = uvSets[1] ? uvSets[1]->vec2(i) : glm::dvec2(0.0);
          glm::dvec4 uv(a, b);
          if (!(std::isfinite(uv.x) && std::isfinite(uv.y) && std::isfinite(uv.z) && std::isfinite(uv.w))) {
            fail(where + " TEXCOORD of vertex " + std::to_string(i) + " is not finite (NaN or Inf)");
          }
          data_.texcoords.push_back(uv);
        }
        if (withColors) {
          glm::dvec4 c(1.0);
          for (int k = 0; k < colorComponents; ++k) c[k] = colors->component(i, k);
          if (!(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z) && std::isfinite(c.w))) {
            fail(where + " COLOR_0 of vertex " + std::to_string(i) + " is not finite (NaN or Inf)");
          }
          data_.colors.push_back(glm::clamp(c, 0.0, 1e6));
        }
      }

      std::vector<std::uint32_t> indices;
      if (prim.indices >= 0) {
        AccessorView idx = view(prim.indices, where + " indices", TINYGLTF_TYPE_SCALAR,
                                {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                 TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
        indices.resize(idx.count);
        for (std::size_t i = 0; i < idx.count; ++i) {
          indices[i] = idx.index(i);
          if (indices[i] >= positions.count) {
            fail(where + " index " + std::to_string(i) + " is " + std::to_string(indices[i]) + ", but there are " +
                 std::to_string(positions.count) + " vertices");
          }
        }
      } else {
        indices.resize(positions.count);
        for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = static_cast<std::uint32_t>(i);
      }

      std::uint32_t material = MeshData::kNone;
      if (prim.material >= 0) {
        if (static_cast<std::size_t>(prim.material) >= model_.materials.size()) {
          fail(where + ".material " + std::to_string(prim.material) + " does not exist");
        }
        material = static_cast<std::uint32_t>(prim.material);
      }
      auto addFace = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        data_.faces.push_back({base + a, base + b, base + c});
        if (normals) {
          data_.faceNormals.push_back({base + a, base + b, base + c});
        } else {
          data_.faceNormals.push_back({MeshData::kNone, MeshData::kNone, MeshData::kNone});
        }
        data_.faceMaterials.push_back(material);
      };
      if (prim.mode == TINYGLTF_MODE_TRIANGLES) {
        if (indices.size() % 3 != 0) {
          fail(where + " has " + std::to_string(indices.size()) + " vertices, not a multiple of 3");
        }
        for (std::size_t i = 0; i + 2 < indices.size(); i += 3) addFace(indices[i], indices[i + 1], indices[i + 2]);
      } else if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        // Every other triangle of a strip is wound the other way round; swap to keep the winding.
        for (std::size_t i = 0; i + 2 < indices.size(); ++i) {
          if (i % 2 == 0)
            addFace(indices[i], indices[i + 1], indices[i + 2]);
          else
            addFace(indices[i + 1], indices[i], indices[i + 2]);
        }
      } else {
        for (std::size_t i = 1; i + 1 < indices.size(); ++i) addFace(indices[0], indices[i], indices[i + 1]);
      }
    }
  }

  void readCamera(const tinygltf::Node& node, const glm::dmat4& world, const std::string& where) {
    if (static_cast<std::size_t>(node.camera) >= model_.cameras.size()) {
      fail(where + ".camera: no camera " + std::to_string(node.camera));
    }
    const tinygltf::Camera& cam = model_.cameras[static_cast<std::size_t>(node.camera)];
    const std::string name = "cameras[" + std::to_string(node.camera) + "]";
    if (cam.type != "perspective") {
      if (!request_.importCamera) return; // a model's orthographic camera: the fitted one instead
      fail(name + " is " + cam.type + "; vkray has only perspective cameras");
    }
    double fov = glm::degrees(cam.perspective.yfov);
    if (!(fov > 0.0 && fov < 180.0)) fail(name + ".perspective.yfov must be in (0, pi)");
    // A glTF camera looks down its local -z with +y up.
    glm::dmat3 linear(world);
    Camera c;
    c.position = dvec3(world * glm::dvec4(0, 0, 0, 1));
    dvec3 forward = linear * dvec3(0, 0, -1);
    dvec3 up = linear * dvec3(0, 1, 0);
    if (!(glm::length(forward) > 0.0) || !(glm::length(up) > 0.0)) fail(name + ": its node's transform is singular");
    c.lookAt = c.position + forward;
    c.up = up;
    c.fovY = fov;
    data_.camera = c;
  }

  void readLight(const tinygltf::Node& node, const glm::dmat4& world, const std::string& where) {
    auto ext = node.extensions.find("KHR_lights_punctual");
    if (ext == node.extensions.end()) return;
    const tinygltf::Value& v = ext->second;
    if (!v.IsObject() || !v.Has("light") || !v.Get("light").IsNumber()) {
      fail(where + ".extensions.KHR_lights_punctual needs a light index");
    }
    int index = v.Get("light").GetNumberAsInt();
    if (index < 0 || static_cast<std::size_t>(index) >= model_.lights.size()) {
      fail(where + " refers to light " + std::to_string(index) + ", which does not exist");
    }
    const tinygltf::Light& light = model_.lights[static_cast<std::size_t>(index)];
    const std::string name = "KHR_lights_punctual light " + std::to_string(index) +
                             (light.name.empty() ? std::string() : " '" + light.name + "'");
    // A spot light becomes a point light (its cone is ignored); a directional light has no
    // position and vkray has no equivalent.
    if (light.type != "point" && light.type != "spot") {
      if (!request_.importLights) return; // a model's directional light: left out
      fail(name + " is " + light.type + "; vkray has only point lights (set import_lights to false to leave it out)");
    }
    PointLight p;
    p.position = dvec3(world * glm::dvec4(0, 0, 0, 1));
    dvec3 color(1.0);
    if (light.color.size() == 3) color = dvec3(light.color[0], light.color[1], light.color[2]);
    p.color = color * light.intensity;
    if (!(std::isfinite(p.color.x) && std::isfinite(p.color.y) && std::isfinite(p.color.z)) ||
        glm::any(glm::lessThan(p.color, dvec3(0.0)))) {
      fail(name + " has a negative or non-finite colour or intensity");
    }
    data_.lights.push_back(p);
  }

  double extensionNumber(const tinygltf::Material& m, const char* ext, const char* key, double fallback) const {
    auto it = m.extensions.find(ext);
    if (it == m.extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
  }

  // glTF metallic-roughness -> Phong, as docs/scene-format.md states. With m = metallic and
  // r = roughness: smooth metals become mirrors (reflection m (1 - r)^2), the rest is diffuse
  // (0.8 (1 - reflection)), the highlight fades with roughness ((1 - r)^2 (0.25 + 0.75 m)) and
  // narrows with smoothness (Phong exponent 2 / alpha^2 - 2 with alpha = r^2, the usual
  // Beckmann-Phong correspondence, Walter et al. 2007). Transmission comes from
  // KHR_materials_transmission, or from 1 - alpha for alphaMode BLEND (then without refraction).
  Material mapMaterial(std::size_t index) {
    const tinygltf::Material& g = model_.materials[index];
    const auto& pbr = g.pbrMetallicRoughness;
    auto clamp01 = [](double v) { return std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 1.0; };
    Material m;
    m.name = request_.shownAs + ": " + (g.name.empty() ? "materials[" + std::to_string(index) + "]" : g.name);
    dvec3 base(1.0);
    double alpha = 1.0;
    if (pbr.baseColorFactor.size() == 4) {
      base = dvec3(clamp01(pbr.baseColorFactor[0]), clamp01(pbr.baseColorFactor[1]), clamp01(pbr.baseColorFactor[2]));
      alpha = clamp01(pbr.baseColorFactor[3]);
    }
    double metal = clamp01(pbr.metallicFactor);
    double rough = clamp01(pbr.roughnessFactor);
    double smooth = (1.0 - rough) * (1.0 - rough);
    m.color = base;
    m.reflection = metal * smooth;
    m.specular = smooth * (0.25 + 0.75 * metal);
    double a = std::max(rough * rough, 0.03);
    m.shininess = std::clamp(2.0 / (a * a) - 2.0, 1.0, 1000.0);
    m.transmission = clamp01(extensionNumber(g, "KHR_materials_transmission", "transmissionFactor", 0.0));
    m.ior = extensionNumber(g, "KHR_materials_ior", "ior", 1.5);
    if (g.alphaMode == "BLEND" && 1.0 - alpha > m.transmission) {
      m.transmission = 1.0 - alpha;
      if (!g.extensions.count("KHR_materials_ior")) m.ior = 1.0;
    }
    if (!(m.ior >= 0.01 && m.ior <= 100.0)) m.ior = 1.5;
    m.reflection = std::min(m.reflection, 1.0 - m.transmission);
    m.diffuse = 0.8 * (1.0 - m.reflection - m.transmission);
    // Ambient light is reflected as diffuse light is: ambient term = ambient light x diffuse x base.
    m.ambient = m.diffuse;
    if (g.alphaMode == "MASK") {
      // A cutoff of 0 cuts nothing (glTF discards alpha < cutoff); a tiny one keeps the mask on.
      m.alphaCutoff = std::isfinite(g.alphaCutoff) ? std::clamp(g.alphaCutoff, 1e-6, 1.0) : 0.5;
      m.alpha = alpha;
    }
    if (pbr.baseColorTexture.index >= 0) {
      const std::string where = "materials[" + std::to_string(index) + "].pbrMetallicRoughness.baseColorTexture";
      m.baseColorTexture = materialTexture(pbr.baseColorTexture, where);
    }
    return m;
  }

  // What the file's materials ask for that vkray does not render, in one line, so that a label drawn
  // by an emissive texture over a black base (glTF2/ClearCoat-glTF) does not go black unannounced.
  // Empty when every material input is read.
  std::string unreadMaterialInputs() const {
    std::vector<std::pair<std::string, int>> counts = {{"emission", 0},
                                                       {"emissive texture", 0},
                                                       {"normal texture", 0},
                                                       {"occlusion texture", 0},
                                                       {"metallic-roughness texture", 0}};
    for (const tinygltf::Material& g : model_.materials) {
      bool emits = false;
      for (double e : g.emissiveFactor) emits = emits || (std::isfinite(e) && e > 0.0);
      counts[0].second += emits && g.emissiveTexture.index < 0 ? 1 : 0;
      counts[1].second += g.emissiveTexture.index >= 0 ? 1 : 0;
      counts[2].second += g.normalTexture.index >= 0 ? 1 : 0;
      counts[3].second += g.occlusionTexture.index >= 0 ? 1 : 0;
      counts[4].second += g.pbrMetallicRoughness.metallicRoughnessTexture.index >= 0 ? 1 : 0;
    }
    std::string list;
    for (const auto& [what, n] : counts) {
      if (n == 0) continue;
      list += (list.empty() ? "" : ", ") + what + " (" + std::to_string(n) + (n == 1 ? " material)" : " materials)");
    }
    if (list.empty()) return {};
    return "not rendered: " + list + "; vkray reads base colour, its texture, transmission and alpha " +
           "(docs/meshes.md)";
  }

  // texture -> image (decoded once per image) and sampler; KHR_texture_transform.
  MaterialTexture materialTexture(const tinygltf::TextureInfo& info, const std::string& where) {
    if (static_cast<std::size_t>(info.index) >= model_.textures.size()) {
      fail(where + ".index " + std::to_string(info.index) + " does not exist");
    }
    const tinygltf::Texture& tex = model_.textures[static_cast<std::size_t>(info.index)];
    MaterialTexture mt;
    mt.texCoord = static_cast<std::uint32_t>(info.texCoord);
    if (auto it = info.extensions.find("KHR_texture_transform"); it != info.extensions.end() && it->second.IsObject()) {
      const tinygltf::Value& t = it->second;
      auto number = [](const tinygltf::Value& v, double fallback) {
        return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
      };
      auto pair = [&](const char* key, glm::dvec2 fallback) {
        if (!t.Has(key) || !t.Get(key).IsArray() || t.Get(key).ArrayLen() != 2) return fallback;
        return glm::dvec2(number(t.Get(key).Get(0), fallback.x), number(t.Get(key).Get(1), fallback.y));
      };
      mt.transform.offset = pair("offset", glm::dvec2(0.0));
      mt.transform.scale = pair("scale", glm::dvec2(1.0));
      if (t.Has("rotation")) mt.transform.rotation = number(t.Get("rotation"), 0.0);
      if (t.Has("texCoord") && t.Get("texCoord").IsInt())
        mt.texCoord = static_cast<std::uint32_t>(t.Get("texCoord").GetNumberAsInt());
      for (double v : {mt.transform.offset.x, mt.transform.offset.y, mt.transform.scale.x, mt.transform.scale.y,
                       mt.transform.rotation}) {
        if (!std::isfinite(v)) fail(where + " KHR_texture_transform has a non-finite number");
      }
    }
    if (mt.texCoord > 1)
      fail(where + ".texCoord " + std::to_string(mt.texCoord) + ": vkray reads TEXCOORD_0 and TEXCOORD_1 only");
    if (tex.source < 0 || static_cast<std::size_t>(tex.source) >= model_.images.size()) {
      fail("textures[" + std::to_string(info.index) + "].source " + std::to_string(tex.source) + " does not exist");
    }
    const int sampler = tex.sampler;
    if (sampler >= 0 && static_cast<std::size_t>(sampler) >= model_.samplers.size()) {
      fail("textures[" + std::to_string(info.index) + "].sampler " + std::to_string(sampler) + " does not exist");
    }
    auto key = std::make_pair(tex.source, sampler);
    if (auto it = textureIndex_.find(key); it != textureIndex_.end()) {
      mt.texture = it->second;
      return mt;
    }
    auto texture = std::make_shared<Texture>();
    texture->levels = buildMipChain(decodeGltfImage(static_cast<std::size_t>(tex.source), texture->name));
    if (sampler >= 0) {
      const tinygltf::Sampler& smp = model_.samplers[static_cast<std::size_t>(sampler)];
      texture->wrapS = wrapMode(smp.wrapS);
      texture->wrapT = wrapMode(smp.wrapT);
      texture->nearest = smp.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
      texture->minFilter = minFilter(smp.minFilter);
    }
    mt.texture = static_cast<std::uint32_t>(data_.textures.size());
    textureIndex_[key] = mt.texture;
    data_.textures.push_back(std::move(texture));
    return mt;
  }

  TextureLevel decodeGltfImage(std::size_t index, std::string& name) const {
    const tinygltf::Image& img = model_.images[index];
    const std::string what = "images[" + std::to_string(index) + "]";
    if (img.bufferView >= 0) {
      name = request_.shownAs + ": " + what;
      if (static_cast<std::size_t>(img.bufferView) >= model_.bufferViews.size())
        fail(what + ".bufferView does not exist");
      const tinygltf::BufferView& bv = model_.bufferViews[static_cast<std::size_t>(img.bufferView)];
      if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model_.buffers.size()) fail(what + ": no buffer");
      const auto& data = model_.buffers[static_cast<std::size_t>(bv.buffer)].data;
      if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset) {
        fail(what + ": its bufferView reaches past the end of its buffer");
      }
      return decodeImage(data.data() + bv.byteOffset, bv.byteLength, name);
    }
    if (img.uri.empty() || img.uri.rfind("data:", 0) == 0) {
      // A data URI (tinygltf decoded the base64 and handed the bytes to keepImageBytes).
      name = request_.shownAs + ": " + what;
      if (img.image.empty()) fail(what + ": the image has no data");
      return decodeImage(img.image.data(), img.image.size(), name);
    }
    std::filesystem::path file = request_.file.parent_path() / img.uri;
    name = file.string();
    // tinygltf read it when it could; a file it could not read leaves the bytes empty.
    if (img.image.empty()) {
      if (!std::filesystem::exists(file))
        throw InputError(file.string(), "texture file not found (" + request_.shownAs + " " + what + ")");
      return readImageFile(file, file.string());
    }
    return decodeImage(img.image.data(), img.image.size(), file.string());
  }

  const MeshRequest& request_;
  const tinygltf::Model& model_;
  MeshData data_;
  std::map<std::pair<int, int>, std::uint32_t> textureIndex_; // (image, sampler) -> data_.textures
  std::vector<bool> visited_;
};

} // namespace

MeshData readGltf(const MeshRequest& request) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keepImageBytes, nullptr);
  tinygltf::Model model;
  std::string err;
  std::string warn;
  const std::string ext = lowerExtension(request.file);
  std::string json = gltfJson(request.file, ext == ".glb", request.shownAs);
  if (!json.empty()) {
    nlohmann::json doc;
    try {
      doc = parseJsonText(json, request.shownAs);
    } catch (const InputError& e) {
      // "file:3:14: invalid JSON: ..." -> "file: not a valid glTF file: at 3:14: invalid JSON: ..."
      std::string what = e.what();
      if (what.rfind(request.shownAs + ":", 0) == 0) what = "at " + what.substr(request.shownAs.size() + 1);
      throw InputError(request.shownAs, "not a valid glTF file: " + what);
    }
    GltfPreflight(doc, request.shownAs).check();
  }
  bool ok = ext == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, request.file.string())
                          : loader.LoadASCIIFromFile(&model, &err, &warn, request.file.string());
  if (!ok) throw InputError(request.shownAs, "not a valid glTF file: " + firstLine(err.empty() ? warn : err));
  return GltfReader(request, model).read();
}

} // namespace vkray
