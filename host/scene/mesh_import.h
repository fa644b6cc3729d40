// Triangle meshes from files: Wavefront OBJ (+MTL) through tinyobjloader, glTF 2.0 (.gltf/.glb)
// through tinygltf and PLY through our own reader, validated, transformed and appended to a Scene.
// docs/scene-format.md ("Meshes") and docs/meshes.md document the formats, the material mapping
// and every repair.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace vkray {

// A mesh file's contents in the file's own frame (glTF node transforms already applied), indexed.
struct MeshData {
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

  std::vector<glm::dvec3> positions;
  std::vector<glm::dvec3> normals;                       // may be empty
  std::vector<std::array<std::uint32_t, 3>> faces;       // indices into positions
  std::vector<std::array<std::uint32_t, 3>> faceNormals; // into normals (kNone: none); empty or one per face
  std::vector<std::uint32_t> faceMaterials;              // into materials, kNone: the default
  std::vector<Material> materials;                       // named "file: material"
  // Texture coordinates per position (xy TEXCOORD_0, zw TEXCOORD_1); empty when the file has none.
  std::vector<glm::dvec4> texcoords;
  // Per face, the corners' indices into texcoords (kNone: none), for formats that index texture
  // coordinates apart from positions (OBJ); empty: texcoords run parallel to positions.
  std::vector<std::array<std::uint32_t, 3>> faceTexcoords;
  // Vertex colours per position (linear RGBA); empty when the file has none.
  std::vector<glm::dvec4> colors;
  // The textures materials' baseColorTexture indices refer to (appendMesh moves them to the scene).
  std::vector<std::shared_ptr<const Texture>> textures;
  std::optional<Camera> camera;   // the first camera, when asked for
  std::vector<PointLight> lights; // when asked for
  std::string noTrianglesReason;  // the reader's word on why the file has no faces ("points only")
  // What the reader repaired and the user should hear of; printed once the mesh is accepted, so a
  // file that is refused says only why.
  std::vector<std::string> warnings;
};

enum class MeshNormals {
  Auto,   // the file's vertex normals where a face has them, else flat
  Flat,   // geometric normals only
  Smooth, // area-weighted vertex normals computed over shared vertices (the file's are ignored)
};
template <> struct EnumNames<MeshNormals> {
  static constexpr std::array<EnumName<MeshNormals>, 3> values{
      {{MeshNormals::Auto, "auto"}, {MeshNormals::Flat, "flat"}, {MeshNormals::Smooth, "smooth"}}};
};

// What a `mesh` object asks for.
struct MeshRequest {
  std::filesystem::path file;            // resolved (relative paths already joined to the scene's dir)
  std::string shownAs;                   // the file as messages name it
  glm::dmat4 worldFromMesh{1.0};         // affine
  std::optional<std::uint32_t> material; // override: every triangle gets this scene material
  MeshNormals normals = MeshNormals::Auto;
  bool importCamera = false;
  bool importLights = false;
  // A model opened as a scene: its first perspective camera and its point and spot lights when it
  // has any; none, or kinds vkray lacks, are left out without an error.
  bool importPresent = false;
  // A model opened as a scene, where no scene file can give the mesh a material: an OBJ material
  // library or name that is missing gives its faces the default grey, with a warning on stderr,
  // instead of refusing the file.
  bool defaultMissingMaterials = false;
  double lightScale = 1.0; // imported light colours are multiplied by this
  // The scene material of faces the file gives none (called once, when first needed). Unset:
  // appendMesh adds a default grey material itself.
  std::function<std::uint32_t()> defaultMaterial;
};

// Readers: the file into MeshData (file frame), or InputError naming the file and the problem.
MeshData readObj(const MeshRequest& request);
MeshData readGltf(const MeshRequest& request);
MeshData readPly(const MeshRequest& request); // ASCII and binary PLY (docs/meshes.md, "PLY")

// The reader for a file, by extension (any case): readObj for .obj, readGltf for .gltf and .glb,
// readPly for .ply;
// nullptr for formats vkray does not read. The one list of mesh formats: importMesh dispatches
// through it, and model_scene.h's isModelFile asks it.
using MeshReader = MeshData (*)(const MeshRequest&);
MeshReader meshReaderFor(const std::filesystem::path& file);

// Reads the file (by extension: .obj, .gltf, .glb, .ply), transforms it and appends its triangles,
// materials, camera and lights to the scene; records a MeshInfo. Degenerate triangles (zero area
// after the transform, in double) are dropped and counted. Returns the imported camera, if any.
std::optional<Camera> importMesh(const MeshRequest& request, Scene& scene);

// Appends already-read mesh data (used by importMesh, the benchmark's procedural meshes and tests).
std::optional<Camera> appendMesh(const MeshData& data, const MeshRequest& request, Scene& scene);

// worldFromMesh from translate / rotate (degrees about x, then y, then z) / scale: T * Rz * Ry * Rx * S.
glm::dmat4 composeTransform(const glm::dvec3& translate, const glm::dvec3& rotateDegrees, const glm::dvec3& scale);

} // namespace vkray
