// The scene packed for the GPU: flat arrays of the structs in shaders/shared/gpu_types.h, in a
// camera-relative frame. Coordinates are shifted by `origin` (in double) before rounding to float,
// so hits near the camera keep full float precision even when the scene sits at 1e5 from the world
// origin ("camera-relative rendering").
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "../../shaders/shared/gpu_types.h"
#include "accel/bvh.h"
#include "accel/shadow_entries.h"
#include "scene/scene.h"

namespace vkray {

struct GpuScene {
  glm::dvec3 origin{0.0}; // world position of the packed frame's origin
  glm::dvec3 background{0.0};
  glm::dvec3 ambientLight{0.0};
  std::vector<gpu::Material> materials;
  std::vector<gpu::Light> lights;
  std::vector<gpu::Sphere> spheres;
  std::vector<gpu::Plane> planes;   // those that can cast shadows first
  std::uint32_t occluderPlanes = 0; // how many of them
  std::vector<gpu::Triangle> triangles;
  std::vector<gpu::Polygon> polygons;
  std::vector<glm::vec4> polyVertices;
  std::vector<glm::vec4> normals;
  // Where each packed primitive came from: its index in the Scene's array of its kind (spheres,
  // planes, polygons, triangles), kept through the reorderings (occluding planes first, BVH leaves).
  std::vector<std::uint32_t> sphereSource, planeSource, polygonSource, triangleSource;
  // Textures (layouts in gpu_types.h): uv records of textured triangles, texture references and
  // level records, and every level's texels. Empty for scenes without textures.
  std::vector<glm::vec4> texCoords;
  std::vector<glm::uvec4> textureInfo;
  std::vector<glm::vec4> texels;
  // A box holding every sphere, triangle and polygon of the packed scene, in float and conservative
  // (the union of bvhPrimitives' boxes); empty when there are none. Eye-ray culling uses it
  // (render/row_culling.h).
  Aabb bounds;
  // The same for the triangles alone and the polygons alone: without a BVH, a ray that misses one
  // skips that kind's loop (FrameParams::triangleBoundsMin ...).
  Aabb triangleBounds, polygonBounds;
  Bvh bvh; // empty unless asked for
  // The BVH in the shader's layout (wideBvh) and its root reference.
  std::vector<gpu::BvhWideNode> bvhNodes;
  std::uint32_t bvhRoot = gpu::kBvhNoRef;
  // Shadow entry points (accel/shadow_entries.h): two texels per (triangle, light), uploaded after
  // the BVH records. Empty until Renderer::prepare builds them for a render that gains from them
  // (buildShadowEntries).
  std::vector<glm::uvec4> shadowEntries;
  double shadowEntryMs = 0.0;         // the table's build time
  bool shadowNothingBetween = false;  // whether the build looked for "nothing between" pairs
  std::size_t shadowNothingPairs = 0; // the (triangle, light) pairs it marked so

  std::size_t bytes() const;
  std::size_t bvhBytes() const; // what the kernel reads of the BVH: the records and the references
  // What the kernel reads for the triangles: the triangles, their shading normals and the BVH
  // (`render --stats` and `bench meshes` divide it by the triangle count).
  std::size_t meshBytes() const;
};

// Packs the scene relative to `origin`; builds the BVH when withBvh. With a BVH, the primitive
// arrays are reordered to follow the leaves (see orderByLeaves).
GpuScene packScene(const Scene& scene, const glm::dvec3& origin, bool withBvh, const BvhOptions& bvhOptions = {});

// Builds g.shadowEntries for every triangle and light (accel/shadow_entries.h) and times it in
// g.shadowEntryMs; nothing where the scene has no BVH, no triangles, no light that casts shadows
// or more than gpu::kShadowEntryLightsMax lights.
void buildShadowEntries(GpuScene& g, const ShadowEntryOptions& options = {});

// The BVH's input: one box per sphere, triangle and polygon of the packed scene, in float and
// conservative (the float primitive lies inside its box).
std::vector<BvhPrimitive> bvhPrimitives(const Scene& scene, const GpuScene& g);

// Reorders spheres, triangles (with their shading normals) and polygons into the order their BVH
// leaves reference them and rewrites the references. Afterwards, in a scene whose bounded
// primitives are all triangles, primRefs[i] is triangle i: the shader may skip the indirection,
// and a leaf's triangles sit next to each other in memory.
void orderByLeaves(GpuScene& g);

// The camera basis as the kernel uses it (forward, right and up scaled by the field of view).
// An `up` parallel to the view direction falls back to another axis instead of producing NaN.
struct CameraFrame {
  glm::dvec3 position;
  glm::dvec3 forward;
  glm::dvec3 right; // unit
  glm::dvec3 up;    // unit
  double tanHalfFovY;
  double aspect;

  // Direction (not normalised) through image-plane point (px, py) in pixels, y down.
  glm::dvec3 rayDirection(double px, double py, std::uint32_t width, std::uint32_t height) const;
};

CameraFrame makeCameraFrame(const Camera& camera, std::uint32_t width, std::uint32_t height);

} // namespace vkray
