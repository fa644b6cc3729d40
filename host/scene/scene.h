// The scene model: plain C++ values in double precision, as read from the scene file. Nothing here
// knows about JSON or Vulkan; the loader fills it, Features analyses it, GpuScene packs it.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/texture.h"
#include "util/enum_names.h"

namespace vkray {

struct Animation; // scene/animation.h

// Right-handed, as glTF: a camera at the origin looking down -z with up +y sees +x on the right.
struct Camera {
  glm::dvec3 position{0.0, 0.0, 5.0};
  glm::dvec3 lookAt{0.0, 0.0, 0.0};
  glm::dvec3 up{0.0, 1.0, 0.0};
  double fovY = 45.0; // degrees, vertical
  // Thin lens (depth of field): the lens radius in world units, 0 for the pinhole, and the distance
  // of the plane in focus along the view direction; unset: the distance to lookAt, so it follows an
  // animated camera's look_at.
  double aperture = 0.0;
  std::optional<double> focusDistance;
  double focusDistanceOrDefault() const { return focusDistance.value_or(glm::length(lookAt - position)); }
};

enum class Numerics { Robust, Naive };
enum class FresnelMode { Exact, Schlick };
enum class TransmissiveShadows { Attenuated, Opaque };
enum class Antialiasing { Stratified, Adaptive };
enum class BvhMode { Auto, On, Off };
enum class Precision { Float32, Float64 }; // arithmetic of ray/surface intersection
// Texture sampling: the nearest texel or bilinear on the full-size image, or trilinear between the
// mip levels a ray cone's footprint picks (Akenine-Moller et al., Ray Tracing Gems ch. 20).
enum class TextureFilter { Nearest, Bilinear, Cone };
// Backward: rays from the eye (the Whitted tracer). Forward: photons from the lights, counted where
// they pass through the camera's lens (docs/forward.md).
enum class Method { Backward, Forward };

// The names of the knobs' values in scene files, on the command line, in the overlay and the benches.
template <> struct EnumNames<Numerics> {
  static constexpr std::array<EnumName<Numerics>, 2> values{{{Numerics::Robust, "robust"}, {Numerics::Naive, "naive"}}};
};
template <> struct EnumNames<FresnelMode> {
  static constexpr std::array<EnumName<FresnelMode>, 2> values{
      {{FresnelMode::Exact, "exact"}, {FresnelMode::Schlick, "schlick"}}};
};
template <> struct EnumNames<TransmissiveShadows> {
  static constexpr std::array<EnumName<TransmissiveShadows>, 2> values{
      {{TransmissiveShadows::Attenuated, "attenuated"}, {TransmissiveShadows::Opaque, "opaque"}}};
};
template <> struct EnumNames<Antialiasing> {
  static constexpr std::array<EnumName<Antialiasing>, 2> values{
      {{Antialiasing::Stratified, "stratified"}, {Antialiasing::Adaptive, "adaptive"}}};
};
template <> struct EnumNames<BvhMode> {
  static constexpr std::array<EnumName<BvhMode>, 3> values{
      {{BvhMode::Auto, "auto"}, {BvhMode::On, "on"}, {BvhMode::Off, "off"}}};
};
template <> struct EnumNames<Precision> {
  static constexpr std::array<EnumName<Precision>, 2> values{
      {{Precision::Float32, "float32"}, {Precision::Float64, "float64"}}};
};
template <> struct EnumNames<Method> {
  static constexpr std::array<EnumName<Method>, 2> values{
      {{Method::Backward, "backward"}, {Method::Forward, "forward"}}};
};
template <> struct EnumNames<TextureFilter> {
  static constexpr std::array<EnumName<TextureFilter>, 3> values{
      {{TextureFilter::Nearest, "nearest"}, {TextureFilter::Bilinear, "bilinear"}, {TextureFilter::Cone, "cone"}}};
};

// Accuracy knobs; every one can also be set on the command line.
struct RenderSettings {
  std::uint32_t width = 800;
  std::uint32_t height = 600;
  int maxDepth = 5;             // reflection/refraction bounces after the eye ray
  int spp = 1;                  // samples per pixel
  double bailout = 1.0 / 255.0; // branches with weight below this are not traced (0: off)
  Antialiasing antialiasing = Antialiasing::Stratified;
  double adaptiveThreshold = 0.1; // adaptive AA: max channel difference to a neighbour
  Numerics numerics = Numerics::Robust;
  FresnelMode fresnel = FresnelMode::Exact;
  TransmissiveShadows transmissiveShadows = TransmissiveShadows::Attenuated;
  BvhMode bvh = BvhMode::Auto;
  Precision precision = Precision::Float32; // float64: the accuracy reference (needs shaderFloat64)
  TextureFilter textureFilter = TextureFilter::Cone;
  // Progressive rendering (host/render/adaptive.h): either one turns it on, and spp is not used.
  // noiseThreshold: a pixel stops once its estimated standard error (and its neighbours') is below
  // this, in linear RGB (0: off). timeLimit: passes stop before the trace would exceed this many
  // seconds of GPU time (0: none). Each pixel gets at least minSpp and at most maxSpp samples.
  double noiseThreshold = 0.0;
  double timeLimit = 0.0;
  int minSpp = 4;
  int maxSpp = 1024;
  // Which of the sample sequences' independent scramblings the pixels use (0: the default). Another
  // seed gives another, equally good set of sample positions: another noise pattern over the same
  // expected image (for animation frames, or to measure noise against itself).
  std::uint32_t seed = 0;
  // Forward tracing (method forward): photons each light emits; 0: kDefaultPhotons, or with a time
  // limit as many as the time allows. A time limit may stop a given count sooner.
  Method method = Method::Backward;
  std::uint64_t photons = 0;
  static constexpr std::uint64_t kDefaultPhotons = 1u << 22;
  bool progressive() const { return method == Method::Backward && (noiseThreshold > 0.0 || timeLimit > 0.0); }
};

struct Checker {
  glm::dvec3 color2{0.0};
  double scale = 1.0; // side of a square, world units
};

// A material's use of a texture: which (Scene::textures), through which uv set and transform.
struct MaterialTexture {
  std::uint32_t texture = 0;  // index into Scene::textures
  std::uint32_t texCoord = 0; // uv set 0 or 1 (glTF TEXCOORD_n)
  TextureTransform transform; // KHR_texture_transform
};

struct Material {
  std::string name;
  glm::dvec3 color{0.8}; // linear RGB
  double ambient = 0.1;
  double diffuse = 0.6;
  double specular = 0.0;
  double shininess = 40.0;   // Phong exponent
  double reflection = 0.0;   // 0..1
  double transmission = 0.0; // 0..1
  double ior = 1.5;
  glm::dvec3 absorption{0.0}; // Beer-Lambert coefficient per unit length
  std::optional<Checker> checker;
  // The base colour is color x this texture's texel (glTF baseColorTexture x baseColorFactor).
  std::optional<MaterialTexture> baseColorTexture;
  // glTF alphaMode MASK: triangles are cut out where alpha x the texture's alpha < alphaCutoff
  // (0: not masked). Triangles only.
  double alphaCutoff = 0.0;
  double alpha = 1.0; // baseColorFactor's alpha
};

struct PointLight {
  glm::dvec3 position{0.0};
  glm::dvec3 color{1.0};
  bool shadows = true;
};

struct Sphere {
  glm::dvec3 center{0.0};
  double radius = 1.0;
  std::uint32_t material = 0;
};

// n.x + D = 0 with |n| = 1 (the loader normalises n and scales D with it).
struct Plane {
  glm::dvec3 normal{0.0, 1.0, 0.0};
  double offset = 0.0;
  std::uint32_t material = 0;
};

// Planar, convex, counter-clockwise or clockwise; 3 or more vertices.
struct Polygon {
  std::vector<glm::dvec3> vertices;
  glm::dvec3 normal{0.0}; // unit, from the vertex winding (Newell's method)
  std::uint32_t material = 0;
};

struct Triangle {
  glm::dvec3 v[3];
  std::optional<std::array<glm::dvec3, 3>> normals; // per-vertex shading normals, unit
  // Per-corner texture coordinates: xy set 0, zw set 1 (only for triangles of textured materials).
  std::optional<std::array<glm::dvec4, 3>> uvs;
  // Per-corner vertex colours, linear RGBA (glTF COLOR_0), multiplying the base colour.
  std::optional<std::array<glm::dvec4, 3>> colors;
  std::uint32_t material = 0;
};

// Where a mesh's triangles came from, for --stats and error messages.
struct MeshInfo {
  std::string file;
  std::size_t firstTriangle = 0;
  std::size_t triangleCount = 0;
  std::size_t droppedDegenerate = 0;
};

// An object the scene file gave a "name": its kind and which primitives of that kind it made.
enum class ObjectKind { Sphere, Plane, Polygon, Triangle, Mesh };
struct NamedObject {
  std::string name;
  ObjectKind kind = ObjectKind::Sphere;
  std::size_t first = 0; // index into the kind's array (triangles for a mesh)
  std::size_t count = 1; // a mesh's triangle count; 1 otherwise
};

struct NamedLight {
  std::string name;
  std::size_t index = 0; // into Scene::lights
};

struct Scene {
  std::filesystem::path path; // file it was loaded from (for messages and relative mesh paths)
  Camera camera;
  RenderSettings render;
  glm::dvec3 background{0.0};
  glm::dvec3 ambientLight{0.0};
  std::vector<Material> materials;
  std::vector<PointLight> lights;
  std::vector<Sphere> spheres;
  std::vector<Plane> planes;
  std::vector<Polygon> polygons;
  std::vector<Triangle> triangles;
  std::vector<std::shared_ptr<const Texture>> textures; // decoded once, shared by animation frames
  std::vector<MeshInfo> meshes;
  std::vector<NamedObject> namedObjects; // in file order
  std::vector<NamedLight> namedLights;
  // The scene file's "animation", if any; sceneAtFrame (scene/animation.h) turns it into the
  // static scene of one frame. Shared: every frame's Scene is a copy of this one.
  std::shared_ptr<const Animation> animation;
  // camera.fit: the camera frames every bounded object, looking from this direction (model_scene.h);
  // refitCamera() redoes it when the image's aspect changes.
  std::optional<glm::dvec3> fitFrom;

  std::size_t boundedPrimitiveCount() const { return spheres.size() + polygons.size() + triangles.size(); }
  std::size_t objectCount() const { return boundedPrimitiveCount() + planes.size(); }
};

} // namespace vkray
